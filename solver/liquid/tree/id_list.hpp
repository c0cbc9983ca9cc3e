#pragma once
// A list of 32-bit ids with a few entries stored inline: the face list of one cell. Most cells have
// at most 2*Dim faces, so most lists never allocate; a cell next to finer cells spills to the heap.

#include <algorithm>
#include <cstdint>

namespace liquid::tree::detail {

class IdList {
 public:
  static constexpr int n_inline = 6;

  IdList() = default;
  IdList(const IdList& o) { copy_from(o); }
  IdList(IdList&& o) noexcept { steal(o); }
  IdList& operator=(const IdList& o) {
    if (this != &o) {
      size_ = 0;
      copy_from(o);
    }
    return *this;
  }
  IdList& operator=(IdList&& o) noexcept {
    if (this != &o) {
      release();
      steal(o);
    }
    return *this;
  }
  ~IdList() { release(); }

  int size() const { return size_; }
  bool empty() const { return size_ == 0; }
  const std::int32_t* data() const { return cap_ > n_inline ? heap_ : inline_; }
  std::int32_t* data() { return cap_ > n_inline ? heap_ : inline_; }
  const std::int32_t* begin() const { return data(); }
  const std::int32_t* end() const { return data() + size_; }
  std::int32_t operator[](int i) const { return data()[i]; }
  std::int32_t& operator[](int i) { return data()[i]; }
  std::int32_t back() const { return data()[size_ - 1]; }

  void push_back(std::int32_t v) {
    if (size_ == cap_) grow(2 * cap_);
    data()[size_++] = v;
  }
  void pop_back() { --size_; }
  /// Empties the list, keeping its capacity.
  void clear() { size_ = 0; }
  void reserve(int n) {
    if (n > cap_) grow(n);
  }

 private:
  void grow(int n) {
    auto* p = new std::int32_t[n];
    std::copy(data(), data() + size_, p);
    if (cap_ > n_inline) delete[] heap_;
    heap_ = p;
    cap_ = n;
  }
  void release() {
    if (cap_ > n_inline) delete[] heap_;
    cap_ = n_inline;
    size_ = 0;
  }
  void copy_from(const IdList& o) {
    reserve(o.size_);
    std::copy(o.begin(), o.end(), data());
    size_ = o.size_;
  }
  void steal(IdList& o) {
    size_ = o.size_;
    cap_ = o.cap_;
    if (o.cap_ > n_inline)
      heap_ = o.heap_;
    else
      std::copy(o.inline_, o.inline_ + o.size_, inline_);
    o.cap_ = n_inline;
    o.size_ = 0;
  }

  std::int32_t size_ = 0;
  std::int32_t cap_ = n_inline;
  union {
    std::int32_t inline_[n_inline];
    std::int32_t* heap_;
  };
};

}  // namespace liquid::tree::detail
