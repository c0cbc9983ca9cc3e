#pragma once
// The divergence of a staggered velocity (normal components at faces) at cell centres, two ways:
//   - finite volumes: (1 / V) * sum over the cell's faces of (u . n) * area. Conservative by
//     construction: the volume-weighted sum over cells telescopes to the boundary flux.
//   - RBF-FD (the paper's): for each axis k, the derivative d/dx_k at the cell centre from the
//     k-normal velocities at nearby face centres (faces of the cell's 1-ring, grown to the 2-ring
//     when too few), summed over k. Not conservative in general.

#include <span>
#include <vector>

#include "liquid/rbf/weights.hpp"
#include "liquid/tree/cell_graph.hpp"

namespace liquid::mac {

/// u: normal velocity per face id (along the face's axis, positive towards the upper side).
/// Returns the divergence per cell id (NaN for dead ids).
template <int Dim>
std::vector<double> fv_divergence(const tree::CellGraph<Dim>& graph, const std::vector<double>& u);
/// The same at one cell c.
template <int Dim>
double fv_divergence_at(const tree::CellGraph<Dim>& graph, std::span<const double> u, tree::CellId c);

/// The RBF-FD divergence; throws liquid::Error naming the cell when a stencil has no usable weights.
template <int Dim>
std::vector<double> rbf_divergence(const tree::CellGraph<Dim>& graph, const std::vector<double>& u,
                                   const rbf::Config& config = rbf::Config{3, 2}, double growth = 2.0);

}  // namespace liquid::mac
