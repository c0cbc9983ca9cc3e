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
  bool empty() const { return words.empty(); }
  bool operator==(const ShapeKey& o) const { return words == o.words; }
};

struct ShapeKeyHash {
  std::size_t operator()(const ShapeKey& k) const;
};

/// The key of `nodes` (in their order) seen from `at` in units of `h`, on `quantum`; an empty key
/// when an offset is off the quantum by more than round-off (cells of a box whose sides are not in
/// power-of-two ratios): such stencils are computed directly.
template <int Dim>
ShapeKey shape_key(std::span<const Vec<Dim>> nodes, const Vec<Dim>& at, double h, double quantum,
                   const Config& config);

/// The offsets (units of h, from `at`) that a key of `n_nodes` nodes stands for, in its order.
template <int Dim>
void shape_offsets(const ShapeKey& key, int n_nodes, double quantum, std::vector<Vec<Dim>>& out);

/// Entries shared by key, safe under OpenMP: a lookup takes a shared lock on one of many shards,
/// and a miss is computed by the caller outside any lock and then offered with insert(), which keeps
/// the first entry offered for a key.
template <class Value>
class ShapeMap {
 public:
  ShapeMap() : shards_(new Shard[n_shards]) {}

  std::shared_ptr<const Value> find(const ShapeKey& key) const {
    const Shard& s = shard(key);
    std::shared_lock lock(s.mutex);
    auto it = s.map.find(key);
    return it == s.map.end() ? nullptr : it->second;
  }
  /// The entry kept for `key`: `value`, or the one another thread inserted first.
  std::shared_ptr<const Value> insert(const ShapeKey& key, std::shared_ptr<const Value> value) {
    Shard& s = shard(key);
    std::unique_lock lock(s.mutex);
    return s.map.emplace(key, std::move(value)).first->second;
  }
  std::size_t size() const {
    std::size_t n = 0;
    for (int i = 0; i < n_shards; ++i) {
      std::shared_lock lock(shards_[i].mutex);
      n += shards_[i].map.size();
    }
    return n;
  }
  void clear() {
    for (int i = 0; i < n_shards; ++i) {
      std::unique_lock lock(shards_[i].mutex);
      shards_[i].map.clear();
    }
  }

 private:
  struct Shard {
    mutable std::shared_mutex mutex;
    std::unordered_map<ShapeKey, std::shared_ptr<const Value>, ShapeKeyHash> map;
  };
  static constexpr int n_shards = 64;
  Shard& shard(const ShapeKey& key) const { return shards_[ShapeKeyHash{}(key) % n_shards]; }

  std::unique_ptr<Shard[]> shards_;
};

}  // namespace liquid::rbf
