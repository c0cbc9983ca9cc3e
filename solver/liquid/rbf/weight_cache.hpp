#pragma once
// A cache of RBF-FD basis weights keyed by the stencil's geometry (shape_key.hpp): every T-junction
// of the same layout, at any level, has the same node offsets once they are divided by the size h
// of the centre cell. The stored weights are for h = 1 and are rescaled on the way out (1/h per
// derivative order). An entry is computed from the key's own offsets, so assembly is reproducible
// bit for bit at any thread count. Stencils whose offsets are not on the quantum to round-off are
// computed directly, uncached. Safe under OpenMP.

#include <atomic>
#include <cstdint>
#include <span>
#include <vector>

#include "liquid/rbf/shape_key.hpp"
#include "liquid/rbf/weights.hpp"

namespace liquid::rbf {

template <int Dim>
class WeightCache {
 public:
  /// `quantum`: offsets (in units of h) closer than this share an entry. `max_entries` (0: no
  /// limit): about the most entries kept; those unused longest are dropped first (see ShapeMap), so
  /// a cache kept across many assemblies keeps the shapes it keeps meeting.
  explicit WeightCache(double quantum = 0x1p-24, std::size_t max_entries = 0);

  /// Weights of `op` at `at` for `nodes`, with `h` the size of the centre cell. Same contract as
  /// rbf::weights(). Node order matters: a permuted stencil is a different entry.
  Status weights(std::span<const Vec<Dim>> nodes, const Vec<Dim>& at, double h, const Operator<Dim>& op,
                 const Config& config, std::vector<double>& out);

  long hits() const { return map_.hits(); }
  long misses() const { return map_.misses(); }
  long bypassed() const { return bypassed_.load(std::memory_order_relaxed); }  ///< off-quantum stencils
  long flushes() const { return map_.flushes(); }  ///< times its older half was dropped
  std::size_t size() const;
  void clear();

 private:
  double quantum_;
  ShapeMap<BasisWeights<Dim>> map_;
  std::atomic<long> bypassed_{0};
};

}  // namespace liquid::rbf
