#pragma once
// The geometry of a stencil as a hashable key, and a thread-safe map from keys to shared entries:
// what the weight cache (RBF-FD rows) and the interpolant cache (face -> particle transfers) share.
//
// Stencils on a tree repeat: every cell of the same neighbourhood layout, at any level and place,
// has the same node offsets once they are taken from a reference point `at` and divided by the
// cell size h. The key holds those offsets on a power-of-two quantum (dyadic cell centres and face
// centres land on it exactly) plus the kernel settings. An entry must be computed from the key's own
// offsets (shape_offsets), never from the stencil that happened to miss first, so that what a
// lookup returns does not depend on which thread got there first.

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <shared_mutex>
#include <span>
#include <unordered_map>
#include <vector>

#include "liquid/core/types.hpp"
#include "liquid/rbf/weights.hpp"

namespace liquid::rbf {

struct ShapeKey {
  std::vector<std::int64_t> words;  ///< empty: no key (an offset off the quantum)
  std::size_t hash = 0;             ///< of the words, set once by shape_key (a lookup uses it up to 3 times)
  bool empty() const { return words.empty(); }
  bool operator==(const ShapeKey& o) const { return hash == o.hash && words == o.words; }
};

struct ShapeKeyHash {
  std::size_t operator()(const ShapeKey& k) const { return k.hash; }
  static std::size_t of(std::span<const std::int64_t> words);
};

/// The key of `nodes` (in their order) seen from `at` in units of `h`, on `quantum`; an empty key
/// when an offset is off the quantum by more than round-off (cells of a box whose sides are not in
/// power-of-two ratios) or farther than 2^14 h: such stencils are computed directly.
template <int Dim>
ShapeKey shape_key(std::span<const Vec<Dim>> nodes, const Vec<Dim>& at, double h, double quantum,
                   const Config& config);

/// A canonical order of stencil nodes, so that congruent stencils gathered in different orders
/// share a cache entry: by squared distance from `at`, ties by offset, on offsets rounded to
/// 2^-16 h (exact for dyadic layouts). Offsets beyond 2^14 h are taken as 2^14 h and non-finite
/// ones as 0 (such stencils get no key anyway), so any input gives a valid order. On return
/// `order[j]` is the index in `nodes` of the j-th node; the sort is stable.
template <int Dim>
void canonical_order(std::span<const Vec<Dim>> nodes, const Vec<Dim>& at, double h, std::vector<int>& order);

/// The offsets (units of h, from `at`) that a key of `n_nodes` nodes stands for, in its order.
template <int Dim>
void shape_offsets(const ShapeKey& key, int n_nodes, double quantum, std::vector<Vec<Dim>>& out);

/// Entries shared by key, safe under OpenMP: a lookup takes a shared lock on one of many shards; a
/// miss is made outside any lock, and the first entry made for a key is the one kept. With
/// `max_entries` (0: no limit) the map holds two generations of at most half that many each: when
/// the young one fills, the old one is dropped and the young one becomes old, and an old entry that
/// is looked up moves back to the young one. So the shapes a run keeps meeting stay, and only those
/// unused for a whole generation are made again (approximately so under threads: an insertion
/// racing a rotation may land in either generation). Entries already handed out live on with their
/// holders; what a lookup returns never depends on the map's state.
template <class Value>
class ShapeMap {
 public:
  explicit ShapeMap(std::size_t max_entries = 0)
      : generation_(max_entries == 0 ? 0 : std::max<std::size_t>(1, max_entries / 2)),
        shards_(new Shard[n_shards]) {}

  /// The entry for `key`, made by `make(offsets)` on a miss from the key's own offsets (units of h,
  /// `n_nodes` of them, on `quantum`) so that it is a function of the key alone.
  template <int Dim, class Make>
  std::shared_ptr<const Value> find_or_make(const ShapeKey& key, int n_nodes, double quantum, Make&& make) {
    Shard& s = shard(key);
    bool in_old = false;
    {
      std::shared_lock lock(s.mutex);
      auto it = s.young.find(key);
      if (it != s.young.end()) {
        hits_.fetch_add(1, std::memory_order_relaxed);
        return it->second;
      }
      in_old = s.old.find(key) != s.old.end();
    }
    if (in_old) {
      std::shared_ptr<const Value> kept;
      bool moved = false;
      {
        std::unique_lock lock(s.mutex);
        auto it = s.old.find(key);
        if (it != s.old.end()) {
          kept = it->second;
          s.old.erase(it);
          moved = s.young.emplace(key, kept).second;
        } else if (auto y = s.young.find(key); y != s.young.end()) {
          kept = y->second;  // moved back or made by another thread meanwhile
        }
      }
      if (kept) {
        hits_.fetch_add(1, std::memory_order_relaxed);
        if (moved) count_young();
        return kept;
      }
    }
    misses_.fetch_add(1, std::memory_order_relaxed);
    std::vector<Vec<Dim>> offsets;
    shape_offsets<Dim>(key, n_nodes, quantum, offsets);
    std::shared_ptr<const Value> made = make(std::span<const Vec<Dim>>(offsets));
    std::shared_ptr<const Value> kept;
    bool inserted = false;
    {
      std::unique_lock lock(s.mutex);
      auto [it, fresh] = s.young.emplace(key, std::move(made));
      kept = it->second;
      inserted = fresh;
    }
    if (inserted) count_young();
    return kept;
  }

  long hits() const { return hits_.load(std::memory_order_relaxed); }
  long misses() const { return misses_.load(std::memory_order_relaxed); }
  /// Times the young generation filled and the old one was dropped.
  long flushes() const { return flushes_.load(std::memory_order_relaxed); }
  std::size_t size() const {
    std::size_t n = 0;
    for (int i = 0; i < n_shards; ++i) {
      std::shared_lock lock(shards_[i].mutex);
      n += shards_[i].young.size() + shards_[i].old.size();
    }
    return n;
  }
  /// Empties the map and its counts.
  void clear() {
    for (int i = 0; i < n_shards; ++i) {
      std::unique_lock lock(shards_[i].mutex);
      shards_[i].young.clear();
      shards_[i].old.clear();
    }
    young_ = 0;
    hits_ = 0;
    misses_ = 0;
    flushes_ = 0;
  }

 private:
  using Map = std::unordered_map<ShapeKey, std::shared_ptr<const Value>, ShapeKeyHash>;
  struct Shard {
    mutable std::shared_mutex mutex;
    Map young, old;
  };
  /// One more young entry; the thread that fills the generation rotates every shard.
  void count_young() {
    if (generation_ == 0 || young_.fetch_add(1, std::memory_order_relaxed) + 1 != generation_) return;
    for (int i = 0; i < n_shards; ++i) {
      std::unique_lock lock(shards_[i].mutex);
      shards_[i].old = std::move(shards_[i].young);
      shards_[i].young = Map{};
    }
    young_ = 0;
    flushes_.fetch_add(1, std::memory_order_relaxed);
  }
  static constexpr int n_shards = 64;
  Shard& shard(const ShapeKey& key) const { return shards_[ShapeKeyHash{}(key) % n_shards]; }
  std::size_t generation_;  // entries a generation holds before it turns old; 0: no limit
  std::unique_ptr<Shard[]> shards_;
  std::atomic<std::size_t> young_{0};
  std::atomic<long> hits_{0}, misses_{0}, flushes_{0};
};

}  // namespace liquid::rbf
