#pragma once
// The numbering of a Poisson problem's unknowns: which cells carry one, and its index.

#include <cstdint>
#include <span>
#include <vector>

#include "liquid/levelset/levelset.hpp"
#include "liquid/tree/cell_graph.hpp"

namespace liquid::mac {

template <int Dim>
struct DofLayout {
  std::vector<int> dof_of_cell;  ///< per cell id: unknown index, or -1
  std::vector<tree::CellId> cell_of_dof;

  long n_unknowns() const { return static_cast<long>(cell_of_dof.size()); }
  bool is_unknown(tree::CellId c) const { return dof_of_cell[c] >= 0; }
};

/// Unknowns at the cells whose centre has inside(centre) < 0, or at every cell when `inside` is
/// empty, numbered in the graph's cell order. Throws liquid::Error naming the cell where `inside` is
/// not finite, and when no cell is inside.
template <int Dim>
DofLayout<Dim> number_unknowns(const tree::CellGraph<Dim>& graph, const levelset::Function<Dim>& inside);

/// Unknowns at the alive cells c with mask[c] != 0 (mask.size() >= graph.cell_capacity()), in the
/// graph's cell order. Throws liquid::Error when the mask is too short or selects no cell.
template <int Dim>
DofLayout<Dim> number_unknowns(const tree::CellGraph<Dim>& graph, std::span<const std::uint8_t> mask);

}  // namespace liquid::mac
