#pragma once
// Stencil nodes for RBF-FD operators on a CellGraph: which cell centres (and boundary points) an
// operator at a cell centre or a face centre uses.
//
// A node is either an unknown (a degree of freedom: a cell centre, or a mirror image of one across
// a Neumann wall, carrying the same unknown) or a known value (a point on a Dirichlet interface,
// or the centre of an air cell). The caller turns weights into matrix entries (unknowns) and
// right-hand-side terms (known values).

#include <functional>
#include <vector>

#include "liquid/core/types.hpp"
#include "liquid/levelset/levelset.hpp"
#include "liquid/tree/cell_graph.hpp"

namespace liquid::mac {

/// How an irregular stencil is chosen around its centre.
enum class StencilRule {
  nearest,     ///< the N cells nearest the centre among its 2-ring (grown when too few)
  face_grown,  ///< face neighbours, then the next ring's nearest cells until N
  ring,        ///< whole k-rings, k = 1, 2, ... until at least N cells
};
StencilRule parse_stencil_rule(const std::string& name);
const char* to_string(StencilRule rule);

template <int Dim>
struct StencilNode {
  Vec<Dim> x;
  int dof = -1;        ///< unknown index, or -1 for a known value
  double value = 0.0;  ///< the known value when dof < 0
};

/// Which cells carry unknowns, and what is known at the others.
template <int Dim>
struct DofLayout {
  std::vector<int> dof_of_cell;  ///< per cell id: unknown index or -1
  std::vector<CellId> cell_of_dof;
  levelset::Function<Dim> levelset;                  ///< empty: every cell is an unknown, walls are Neumann
  std::function<double(const Vec<Dim>&)> dirichlet;  ///< value on the interface {levelset = 0} and walls
  bool dirichlet_walls = false;  ///< domain walls carry `dirichlet` values instead of being Neumann
};

/// Gathers the nodes of an operator evaluated at `at`, seeded by `seeds` (the cell(s) the operator
/// belongs to; seeds[0] is the anchor from which interface crossings are searched). Cells outside
/// the level set become their crossing point on the segment anchor -> cell, with the Dirichlet
/// value. Nodes of cells that touch a Neumann wall are mirrored across it (same unknown); with
/// Dirichlet walls the projections of those nodes onto the wall carry the wall value. Keeps at
/// least `n_target` nodes when the graph has them, the nodes ordered by distance from `at`.
template <int Dim>
void gather_stencil(const CellGraph<Dim>& graph, const DofLayout<Dim>& layout, std::span<const CellId> seeds,
                    const Vec<Dim>& at, StencilRule rule, int n_target, std::vector<StencilNode<Dim>>& out);

}  // namespace liquid::mac
