#pragma once
// An open-addressing hash map from tree keys (see core/morton.hpp; never 0) to 32-bit values,
// with linear probing and backward-shift deletion. The cell graph keeps every node of the tree in
// one: leaves map to their cell id, interior nodes to `interior`. Reads are safe from many threads
// while nobody writes; value_ptr() lets threads fill values of distinct existing keys in parallel.

#include <cstdint>
#include <vector>

namespace liquid::tree::detail {

class KeyMap {
 public:
  static constexpr std::int32_t absent = INT32_MIN;  ///< find() of a key not in the map
  static constexpr std::int32_t interior = -1;       ///< value of an interior tree node

  KeyMap() { rehash(16); }

  /// Makes room for `n` keys without rehashing.
  void reserve(std::size_t n) {
    if (2 * n > slots_.size()) rehash(n);
  }
  std::size_t size() const { return size_; }
  void clear() {
    slots_.assign(slots_.size(), Slot{});
    size_ = 0;
  }

  /// The value of `key`, or `absent`.
  std::int32_t find(std::uint64_t key) const {
    for (std::size_t i = home(key);; i = (i + 1) & mask_) {
      const Slot& s = slots_[i];
      if (s.key == key) return s.value;
      if (s.key == 0) return absent;
    }
  }
  bool contains(std::uint64_t key) const { return find(key) != absent; }

  /// Pointer to the stored value of an existing key (nullptr if absent). Valid until the next insert.
  std::int32_t* value_ptr(std::uint64_t key) {
    for (std::size_t i = home(key);; i = (i + 1) & mask_) {
      Slot& s = slots_[i];
      if (s.key == key) return &s.value;
      if (s.key == 0) return nullptr;
    }
  }

  /// Inserts `key` or overwrites its value.
  void set(std::uint64_t key, std::int32_t value) {
    if (2 * (size_ + 1) > slots_.size()) rehash(size_ + 1);
    for (std::size_t i = home(key);; i = (i + 1) & mask_) {
      Slot& s = slots_[i];
      if (s.key == key) {
        s.value = value;
        return;
      }
      if (s.key == 0) {
        s.key = key;
        s.value = value;
        ++size_;
        return;
      }
    }
  }

  /// Removes `key`; returns whether it was there.
  bool erase(std::uint64_t key) {
    std::size_t i = home(key);
    for (;; i = (i + 1) & mask_) {
      if (slots_[i].key == key) break;
      if (slots_[i].key == 0) return false;
    }
    // Backward shift: pull later entries of the probe run into the hole when their home allows.
    std::size_t j = i;
    for (;;) {
      j = (j + 1) & mask_;
      if (slots_[j].key == 0) break;
      const std::size_t h = home(slots_[j].key);
      const bool movable = (i <= j) ? (h <= i || h > j) : (h <= i && h > j);
      if (movable) {
        slots_[i] = slots_[j];
        i = j;
      }
    }
    slots_[i] = Slot{};
    --size_;
    return true;
  }

  /// Calls fn(key, value) for every entry, in storage order.
  template <class Fn>
  void for_each(Fn&& fn) const {
    for (const Slot& s : slots_)
      if (s.key != 0) fn(s.key, s.value);
  }

 private:
  struct Slot {
    std::uint64_t key = 0;
    std::int32_t value = 0;
  };

  std::size_t home(std::uint64_t key) const {
    key ^= key >> 31;
    key *= 0x9e3779b97f4a7c15ULL;
    return static_cast<std::size_t>(key >> shift_);
  }

  void rehash(std::size_t n_keys) {
    std::size_t capacity = 16;
    int bits = 4;
    while (capacity < 2 * n_keys) {
      capacity *= 2;
      ++bits;
    }
    std::vector<Slot> old;
    old.swap(slots_);
    slots_.assign(capacity, Slot{});
    mask_ = capacity - 1;
    shift_ = 64 - bits;
    size_ = 0;
    for (const Slot& s : old)
      if (s.key != 0) set(s.key, s.value);
  }

  std::vector<Slot> slots_;
  std::size_t mask_ = 0;
  int shift_ = 60;
  std::size_t size_ = 0;
};

}  // namespace liquid::tree::detail
