#pragma once
// Interpolants that share their factorisation with every congruent stencil (shape_key.hpp): the
// face -> particle transfer factorises one RBF system per cell and axis, and on a tree most cells
// see the same layout of faces around them, so most of those factorisations are the same matrix.
// The nodes are put in canonical order (canonical_order, from the cell's centre in units of its
// size), so stencils gathered in any order share an entry. An entry is factorised from the key's
// own offsets, so an interpolant does not depend on which cell or thread missed first.
// Safe under OpenMP.
//
//   InterpolantCache<2> cache;
//   auto interp = cache.interpolant(nodes, graph.centre(c), graph.cell_size(c)[0], config, order);
//   for (j...) v[j] = values[order[j]];
//   interp.fit(v);

#include <atomic>
#include <cstddef>
#include <span>
#include <vector>

#include "liquid/rbf/interpolant.hpp"
#include "liquid/rbf/shape_key.hpp"

namespace liquid::rbf {

template <int Dim>
class InterpolantCache {
 public:
  /// `quantum`: offsets (units of h) closer than this share an entry. `max_entries` (0: no limit):
  /// about the most factorisations kept; those unused longest are dropped first (see ShapeMap;
  /// interpolants already handed out keep theirs). The same order and meaning as WeightCache's.
  explicit InterpolantCache(double quantum = 0x1p-24, std::size_t max_entries = 4096);

  /// An interpolant of `nodes` (seen from `at`, the stencil's cell centre, with `h` its size). Its
  /// j-th node is nodes[order[j]] (`order`, out): give fit() the values in that order; node indices
  /// in its status (node_a, node_b) are in that order too. Stencils off the quantum, farther than
  /// 2^14 h or with a non-finite coordinate are factorised directly (counted as bypassed).
  Interpolant<Dim> interpolant(std::span<const Vec<Dim>> nodes, const Vec<Dim>& at, double h,
                               const Config& config, std::vector<int>& order);

  long hits() const { return map_.hits(); }
  long misses() const { return map_.misses(); }
  long bypassed() const { return bypassed_.load(std::memory_order_relaxed); }
  long flushes() const { return map_.flushes(); }  ///< times its older half was dropped
  std::size_t size() const { return map_.size(); }

 private:
  double quantum_;
  ShapeMap<typename Interpolant<Dim>::Factors> map_;
  std::atomic<long> bypassed_{0};
};

}  // namespace liquid::rbf
