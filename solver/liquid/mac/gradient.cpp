#include "liquid/mac/gradient.hpp"

#include <algorithm>
#include <limits>

#include "liquid/core/error.hpp"
#include "liquid/core/parallel.hpp"
#include "liquid/rbf/weight_cache.hpp"

namespace liquid::mac {

template <int Dim>
std::vector<double> face_normal_derivative(const tree::CellGraph<Dim>& graph, const DofLayout<Dim>& layout,
                                           const Boundary<Dim>& boundary, const PoissonOptions& options,
                                           const linalg::Vector& p, rbf::WeightCache<Dim>* shared) {
  LIQUID_VERIFY(p.size() >= layout.n_unknowns(), "face_normal_derivative: {} values for {} unknowns",
                p.size(), layout.n_unknowns());
  std::vector<double> out(graph.face_capacity(), std::numeric_limits<double>::quiet_NaN());
  const std::vector<tree::FaceId> faces = graph.face_ids();
  rbf::WeightCache<Dim> weight_cache;
  rbf::WeightCache<Dim>* const cache = shared ? shared : &weight_cache;
  struct Scratch {
    RowScratch<Dim> row;
    std::vector<FaceGradientTerm<Dim>> terms;
  };
  parallel_for(
      static_cast<long>(faces.size()), [] { return Scratch{}; },
      [&](Scratch& scratch, long q) {
        const tree::FaceId f = faces[q];
        auto& terms = scratch.terms;
        if (!face_gradient_weights<Dim>(graph, layout, boundary, options, f, cache, scratch.row, terms))
          return;
        const auto value = [&](const FaceGradientTerm<Dim>& t) {
          return (t.dof >= 0 ? p[t.dof] : 0.0) + t.value;
        };
        const tree::GraphFace& g = graph.face(f);
        if (!g.hanging() && g.side_level[0] == g.side_level[1]) {  // two-point, as a difference
          out[f] = (value(terms[1]) - value(terms[0])) / graph.cell_size(g.cell[0])[g.axis];
          return;
        }
        double v = 0.0;
        for (const FaceGradientTerm<Dim>& t : terms) v += t.weight * value(t);
        out[f] = v;
      },
      [](Scratch&) {});
  return out;
}

template <int Dim>
bool face_gradient_weights(const tree::CellGraph<Dim>& graph, const DofLayout<Dim>& layout,
                           const Boundary<Dim>& boundary, const PoissonOptions& options, tree::FaceId f,
                           rbf::WeightCache<Dim>* cache, RowScratch<Dim>& scratch,
                           std::vector<FaceGradientTerm<Dim>>& terms, rbf::Status* status) {
  terms.clear();
  const tree::GraphFace& g = graph.face(f);
  if (g.is_boundary()) return false;
  const int ia = layout.dof_of_cell[g.cell[0]], ib = layout.dof_of_cell[g.cell[1]];
  if (ia < 0 && ib < 0) return false;
  if ((ia < 0 || ib < 0) && !boundary.air_cells()) return false;
  if (!g.hanging() && g.side_level[0] == g.side_level[1]) {
    const double w = 1.0 / graph.cell_size(g.cell[0])[g.axis];
    terms.push_back({ia, -w, ia >= 0 ? 0.0 : boundary.dirichlet(graph.centre(g.cell[0]))});
    terms.push_back({ib, w, ib >= 0 ? 0.0 : boundary.dirichlet(graph.centre(g.cell[1]))});
    return true;
  }
  rbf::Config config = options.rbf;
  config.degree = options.gradient_degree;
  const int n_target = stencil_size(Dim, config.degree, options.growth);
  const Vec<Dim> at = graph.face_centre(f);
  const tree::CellId seeds[2] = {g.cell[0], g.cell[1]};
  auto& nodes = scratch.nodes;
  gather_stencil<Dim>(graph, layout, boundary, seeds, at, options.rule, n_target,
                      options.gradient_node_cap(n_target), nodes);
  const rbf::Status st = stencil_weights<Dim>(
      nodes, at, rbf::Operator<Dim>::partial(g.axis), config, scratch.w, scratch.n_retried,
      cache_for<Dim>(nodes, boundary, options.cache_weights ? cache : nullptr),
      std::min(graph.cell_size(g.cell[0])[0], graph.cell_size(g.cell[1])[0]));
  LIQUID_VERIFY(st.usable(), "face {} between cells {} and {}: RBF-FD gradient weights unusable: {}", f,
                g.cell[0], g.cell[1], st.describe());
  if (status) *status = st;
  for (std::size_t j = 0; j < nodes.size(); ++j)
    terms.push_back({nodes[j].dof, scratch.w[j], nodes[j].value});
  return true;
}

template bool face_gradient_weights<2>(const tree::CellGraph<2>&, const DofLayout<2>&, const Boundary<2>&,
                                       const PoissonOptions&, tree::FaceId, rbf::WeightCache<2>*,
                                       RowScratch<2>&, std::vector<FaceGradientTerm<2>>&, rbf::Status*);
template bool face_gradient_weights<3>(const tree::CellGraph<3>&, const DofLayout<3>&, const Boundary<3>&,
                                       const PoissonOptions&, tree::FaceId, rbf::WeightCache<3>*,
                                       RowScratch<3>&, std::vector<FaceGradientTerm<3>>&, rbf::Status*);

template std::vector<double> face_normal_derivative<2>(const tree::CellGraph<2>&, const DofLayout<2>&,
                                                       const Boundary<2>&, const PoissonOptions&,
                                                       const linalg::Vector&, rbf::WeightCache<2>*);
template std::vector<double> face_normal_derivative<3>(const tree::CellGraph<3>&, const DofLayout<3>&,
                                                       const Boundary<3>&, const PoissonOptions&,
                                                       const linalg::Vector&, rbf::WeightCache<3>*);

}  // namespace liquid::mac
