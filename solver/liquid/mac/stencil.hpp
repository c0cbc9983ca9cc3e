#pragma once
// Stencil nodes for RBF-FD operators on a CellGraph: which cell centres (and boundary points) an
// operator at a cell centre or a face centre uses, and their weights.
//
// A node's value is p[dof] + value: an unknown (dof >= 0: a cell centre, or a mirror image of one
// across a Neumann wall, whose value then carries the wall flux) or a known value alone (dof < 0: a
// point on a Dirichlet interface or wall). The caller turns weights into matrix entries (unknowns)
// and right-hand-side terms (known parts).

#include <span>
#include <string>
#include <vector>

#include "liquid/core/types.hpp"
#include "liquid/mac/boundary.hpp"
#include "liquid/mac/dof_layout.hpp"
#include "liquid/rbf/weight_cache.hpp"
#include "liquid/rbf/weights.hpp"
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

/// The one stencil-size rule: `growth` times the number of polynomial terms of `degree` in Dim
/// dimensions, plus one (the paper: about twice the terms).
int stencil_size(int dim, int degree, double growth);

template <int Dim>
struct StencilNode {
  Vec<Dim> x;
  int dof = -1;        ///< unknown index, or -1 for a known value alone
  double value = 0.0;  ///< the known part: the node carries p[dof] + value (dof >= 0) or value
};

/// Gathers the nodes of an operator evaluated at `at`, seeded by `seeds` (the cell(s) the operator
/// belongs to; seeds[0] is the anchor from which interface crossings are searched). Cells outside
/// the level set become their crossing point on the segment anchor -> cell, with the Dirichlet
/// value. Nodes of cells that touch a Neumann wall are mirrored across it (same unknown, plus
/// twice the distance to the wall times its flux); with Dirichlet walls the projections of those
/// nodes onto the wall carry the wall value. Keeps at least `n_target` nodes when the graph has
/// them, the nodes ordered by distance from `at`. `n_cap` > 0 (ring rule only, at least n_target)
/// keeps the nearest n_cap nodes and every node tied with the last kept.
template <int Dim>
void gather_stencil(const tree::CellGraph<Dim>& graph, const DofLayout<Dim>& layout,
                    const Boundary<Dim>& boundary, std::span<const tree::CellId> seeds, const Vec<Dim>& at,
                    StencilRule rule, int n_target, int n_cap, std::vector<StencilNode<Dim>>& out);

/// Weights `w` of `op` at `at` on `nodes`, dropping an offending node and retrying when the local
/// system is unusable: a known node of a pair closer than 0.1 h (as often as there are such pairs),
/// else the second of two coincident nodes or the farthest node (up to 4 times); `n_retried`
/// counts the drops. With a cache, the nodes are
/// first put in rbf::canonical_order (so congruent stencils share one solve; the weights follow
/// their nodes) and looked up at scale `h`. Returns the status of the final attempt.
template <int Dim>
rbf::Status stencil_weights(std::vector<StencilNode<Dim>>& nodes, const Vec<Dim>& at,
                            const rbf::Operator<Dim>& op, const rbf::Config& config, std::vector<double>& w,
                            long& n_retried, rbf::WeightCache<Dim>* cache = nullptr, double h = 0.0);

/// The cache for a stencil's weights: none when it holds an interface crossing (a level-set
/// problem's known node), whose position is arbitrary and would only fill the cache.
template <int Dim>
rbf::WeightCache<Dim>* cache_for(const std::vector<StencilNode<Dim>>& nodes, const Boundary<Dim>& boundary,
                                 rbf::WeightCache<Dim>* cache) {
  if (cache == nullptr || !boundary.levelset) return cache;
  for (const auto& n : nodes)
    if (n.dof < 0) return nullptr;
  return cache;
}

}  // namespace liquid::mac
