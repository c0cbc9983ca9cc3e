#pragma once
// Each cell's faces as (face, cell across) pairs grouped by axis, in one flat array: walks that visit
// many cells' faces of one axis (the velocity extrapolation) read these 8-byte pairs instead of each
// face's record. Derived from the topology alone, so it is rebuilt only when graph.topology() moves.

#include <cstdint>
#include <span>
#include <vector>

#include "liquid/tree/cell_graph.hpp"

namespace liquid::tree {

template <int Dim>
class CellAdjacency {
 public:
  struct Side {
    FaceId face;
    CellId other;  ///< the cell across the face, or no_cell on the domain boundary
  };

  /// Made for `graph` as it is now; a call with the same topology (graph.topology()) keeps what is
  /// there.
  void bind(const CellGraph<Dim>& graph);

  /// c's faces of `axis`, in the order graph.faces(c) lists them.
  std::span<const Side> of(CellId c, int axis) const {
    const std::size_t k = static_cast<std::size_t>(c) * Dim + axis;
    return {sides_.data() + start_[k], static_cast<std::size_t>(start_[k + 1] - start_[k])};
  }
  /// c's faces of every axis, axis by axis.
  std::span<const Side> of(CellId c) const {
    const std::size_t k = static_cast<std::size_t>(c) * Dim;
    return {sides_.data() + start_[k], static_cast<std::size_t>(start_[k + Dim] - start_[k])};
  }

 private:
  std::uint64_t topology_ = 0;  // 0: never bound (graphs' numbers start at 1)
  std::vector<long> start_;     // per (cell, axis), and one past the last
  std::vector<Side> sides_;
};

}  // namespace liquid::tree
