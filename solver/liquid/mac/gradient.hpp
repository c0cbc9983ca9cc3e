#pragma once
// The normal derivative of a cell-centred p at faces: the two-point difference between equal
// cells, RBF-FD at the face centre otherwise (hanging faces, level jumps). The projection of a PIC
// step and the Poisson studies' dp/dn errors both use it.

#include <vector>

#include "liquid/linalg/solver.hpp"
#include "liquid/mac/boundary.hpp"
#include "liquid/mac/dof_layout.hpp"
#include "liquid/mac/laplacian.hpp"
#include "liquid/tree/cell_graph.hpp"

namespace liquid::mac {

/// dp/dx_axis at every interior face whose two cells are unknowns, indexed by face id (NaN at the
/// others). `p` holds one value per unknown of `layout` (extra trailing entries are ignored);
/// known values (interface, walls) come from `boundary`. Throws liquid::Error naming the face when
/// a stencil has no usable weights. `cache`: as assemble_poisson's.
template <int Dim>
std::vector<double> face_normal_derivative(const tree::CellGraph<Dim>& graph, const DofLayout<Dim>& layout,
                                           const Boundary<Dim>& boundary, const PoissonOptions& options,
                                           const linalg::Vector& p, rbf::WeightCache<Dim>* cache = nullptr);

/// The same face gradient as weights: d/dx_axis at face f from g.cell[0] towards g.cell[1] is
/// sum_j w_j (p[dof_j] + value_j) over `terms` (dof -1: a known value alone). Returns false where
/// face_normal_derivative gives NaN (a boundary face, no unknown side, or a level-set problem's
/// face towards a cell outside, whose gradient the caller forms). The flux rows of the PPE use it,
/// so that their D G is the projection's. Throws liquid::Error as face_normal_derivative does.
template <int Dim>
struct FaceGradientTerm {
  int dof = -1;
  double weight = 0.0, value = 0.0;
};
template <int Dim>
bool face_gradient_weights(const tree::CellGraph<Dim>& graph, const DofLayout<Dim>& layout,
                           const Boundary<Dim>& boundary, const PoissonOptions& options, tree::FaceId f,
                           rbf::WeightCache<Dim>* cache, RowScratch<Dim>& scratch,
                           std::vector<FaceGradientTerm<Dim>>& terms, rbf::Status* status = nullptr);

}  // namespace liquid::mac
