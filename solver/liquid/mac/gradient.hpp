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

}  // namespace liquid::mac
