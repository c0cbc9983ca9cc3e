#include "liquid/mac/laplacian.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "liquid/core/error.hpp"
#include "liquid/mac/gradient.hpp"

namespace liquid::mac {

template <int Dim>
bool regular_neighbourhood(const tree::CellGraph<Dim>& graph, tree::CellId c) {
  for (int k = 0; k < Dim; ++k)
    for (int dir : {-1, 1}) {
      int n_faces = 0;
      bool ok = true;
      graph.for_each_side_face(c, k, dir, [&](const tree::SideFace& s) {
        ++n_faces;
        ok = ok && (s.adjacency == tree::Adjacency::same || s.adjacency == tree::Adjacency::boundary);
      });
      if (n_faces != 1 || !ok) return false;
    }
  return true;
}

template <int Dim>
RowKind fd_row(const tree::CellGraph<Dim>& graph, const DofLayout<Dim>& layout, const Boundary<Dim>& boundary,
               tree::CellId c, Row& row, std::span<const double> coefficient) {
  const int i = layout.dof_of_cell[c];
  const Vec<Dim> x = graph.centre(c);
  const Vec<Dim> h = graph.cell_size(c);
  double diag = 0.0;
  for (int k = 0; k < Dim; ++k) {
    // Per side: distance to the node, the node (an unknown or -1), and its known part.
    double d[2];
    int dof[2];
    double val[2];
    double beta[2] = {1.0, 1.0};
    for (int s = 0; s < 2; ++s) {
      const int dir = s == 0 ? -1 : 1;
      d[s] = h[k];
      dof[s] = i;
      val[s] = 0.0;
      graph.for_each_side_face(c, k, dir, [&](const tree::SideFace& sf) {
        // A Neumann wall's flux is given (beta dp/dn); every other side's weight takes its face's beta.
        if (!coefficient.empty() && (sf.adjacency != tree::Adjacency::boundary || boundary.dirichlet_walls))
          beta[s] = coefficient[sf.face];
        if (sf.adjacency == tree::Adjacency::boundary) {
          Vec<Dim> w = x;
          w[k] = dir < 0 ? graph.domain().lo[k] : graph.domain().hi[k];
          if (!boundary.dirichlet_walls) {
            // Neumann: the ghost mirrors the centre, p_ghost = p_c + h dp/dn at the wall.
            val[s] = h[k] * boundary.flux(w, k, dir);
            return;
          }
          d[s] = 0.5 * h[k];
          dof[s] = -1;
          val[s] = boundary.dirichlet(w);
          return;
        }
        const int j = layout.dof_of_cell[sf.neighbour];
        if (j >= 0) {
          dof[s] = j;
          return;
        }
        const Vec<Dim> y = graph.centre(sf.neighbour);
        if (boundary.air_cells()) {  // the air cell's centre carries the value
          d[s] = std::abs(y[k] - x[k]);
          dof[s] = -1;
          val[s] = boundary.dirichlet(y);
          return;
        }
        const auto cut =
            levelset::crossing<Dim>(boundary.levelset, x, y, boundary.levelset(x), boundary.levelset(y));
        LIQUID_VERIFY(cut.has_value(), "cell {}: no interface crossing towards outside neighbour {}", c,
                      sf.neighbour);
        d[s] = cut->theta * h[k];
        dof[s] = -1;
        val[s] = boundary.dirichlet(cut->point);
      });
    }
    for (int s = 0; s < 2; ++s) {
      if (dof[s] < 0 && d[s] <= 1e-12 * h[k]) {  // the centre is on the interface
        row.entries = {{i, 1.0}};
        row.rhs = val[s];
        return RowKind::on_interface;
      }
    }
    const double scale = 2.0 / (d[0] + d[1]);
    for (int s = 0; s < 2; ++s) {
      const double w = beta[s] * scale / d[s];
      diag += w;
      if (dof[s] >= 0) row.entries.emplace_back(dof[s], -w);
      row.rhs += w * val[s];
    }
  }
  row.entries.emplace_back(i, diag);
  return RowKind::fd;
}

namespace {
int capped_size(double cap, const char* what, StencilRule rule, int n_target) {
  LIQUID_VERIFY(cap == 0.0 || (cap >= 1.0 && std::isfinite(cap)),
                "{} {} must be 0 (whole rings) or at least 1", what, cap);
  if (rule != StencilRule::ring || cap == 0.0) return 0;
  return static_cast<int>(std::ceil(cap * n_target));
}
}  // namespace

int PoissonOptions::node_cap(int n_target) const {
  return capped_size(ring_cap, "ring_cap", rule, n_target);
}

int PoissonOptions::gradient_node_cap(int n_target) const {
  if (gradient_ring_cap == 0.0) return node_cap(n_target);
  return capped_size(gradient_ring_cap, "gradient_ring_cap", rule, n_target);
}

template <int Dim>
RowKind rbf_row(const tree::CellGraph<Dim>& graph, const DofLayout<Dim>& layout,
                const Boundary<Dim>& boundary, tree::CellId c, const PoissonOptions& options,
                rbf::WeightCache<Dim>* cache, RowScratch<Dim>& scratch, Row& row, rbf::Status& status) {
  const int i = layout.dof_of_cell[c];
  const Vec<Dim> x = graph.centre(c);
  const tree::CellId seed[1] = {c};
  auto& nodes = scratch.nodes;
  const int n_target = stencil_size(Dim, options.rbf.degree, options.growth);
  gather_stencil<Dim>(graph, layout, boundary, seed, x, options.rule, n_target, options.node_cap(n_target),
                      nodes);
  const double near = 1e-3 * graph.cell_size(c).maxCoeff();
  for (const auto& nd : nodes)
    if (nd.dof < 0 && (nd.x - x).norm() < near) {
      row.entries = {{i, 1.0}};
      row.rhs = nd.value;
      return RowKind::on_interface;
    }
  status =
      stencil_weights<Dim>(nodes, x, rbf::Operator<Dim>::lap(), options.rbf, scratch.w, scratch.n_retried,
                           cache_for<Dim>(nodes, boundary, cache), graph.cell_size(c)[0]);
  LIQUID_VERIFY(status.usable(), "cell {} at ({:.6g}): RBF-FD Laplacian weights unusable: {}", c,
                fmt::join(x.data(), x.data() + Dim, ", "), status.describe());
  for (std::size_t j = 0; j < nodes.size(); ++j) {
    if (nodes[j].dof >= 0) row.entries.emplace_back(nodes[j].dof, -scratch.w[j]);
    row.rhs += scratch.w[j] * nodes[j].value;
  }
  return RowKind::rbf;
}

const char* to_string(IrregularRows rows) {
  return rows == IrregularRows::flux ? "flux" : "laplacian";
}

IrregularRows parse_irregular_rows(const std::string& name) {
  if (name == "laplacian") return IrregularRows::laplacian;
  if (name == "flux") return IrregularRows::flux;
  throw Error(fmt::format("unknown irregular row kind '{}' (laplacian or flux)", name));
}

template <int Dim>
RowKind flux_row(const tree::CellGraph<Dim>& graph, const DofLayout<Dim>& layout,
                 const Boundary<Dim>& boundary, tree::CellId c, const PoissonOptions& options,
                 rbf::WeightCache<Dim>* cache, RowScratch<Dim>& scratch, Row& row, rbf::Status& status,
                 std::span<const double> coefficient) {
  const int i = layout.dof_of_cell[c];
  const Vec<Dim> x = graph.centre(c);
  const Vec<Dim> h = graph.cell_size(c);
  const double volume = graph.volume(c);
  thread_local std::vector<FaceGradientTerm<Dim>> terms;
  RowKind kind = RowKind::fd;
  double diag = 0.0;
  for (int k = 0; k < Dim; ++k)
    for (int dir : {-1, 1})
      graph.for_each_side_face(c, k, dir, [&](const tree::SideFace& sf) {
        const double a = graph.face_area(sf.face) / volume;
        const bool wall = sf.adjacency == tree::Adjacency::boundary;
        const double beta =
            coefficient.empty() || (wall && !boundary.dirichlet_walls) ? 1.0 : coefficient[sf.face];
        // Each face adds -a beta dp/dn (outward) to the row: unknowns to the entries, known parts to rhs.
        if (wall) {
          const Vec<Dim> w = graph.face_centre(sf.face);
          if (!boundary.dirichlet_walls) {
            row.rhs += a * boundary.flux(w, k, dir);
            return;
          }
          const double g = a * beta * 2.0 / h[k];  // dp/dn = (p_wall - p_c) / (h / 2)
          diag += g;
          row.rhs += g * boundary.dirichlet(w);
          return;
        }
        const int j = layout.dof_of_cell[sf.neighbour];
        if (j < 0 && !boundary.air_cells()) {
          // Ghost fluid towards the crossing, as the projection forms this face's gradient.
          const GhostFace ghost = ghost_face<Dim>(boundary, x, graph.centre(sf.neighbour), k);
          const double g = a * beta / ghost.distance;
          diag += g;
          row.rhs += g * ghost.value;
          return;
        }
        rbf::Status st;
        st.degree_used = options.gradient_degree;
        const bool any =
            face_gradient_weights<Dim>(graph, layout, boundary, options, sf.face, cache, scratch, terms, &st);
        LIQUID_VERIFY(any, "cell {}: face {} has no gradient", c, sf.face);
        if (terms.size() > 2) {
          kind = RowKind::rbf;
          if (st.condition > status.condition || st.degree_used < status.degree_used || status.n_nodes == 0)
            status = st;
        }
        const double scale = dir * a * beta;  // outward = dir x (d/dx_axis)
        for (const FaceGradientTerm<Dim>& t : terms) {
          const double w = scale * t.weight;
          if (t.dof == i)
            diag -= w;
          else if (t.dof >= 0)
            row.entries.emplace_back(t.dof, -w);
          row.rhs += w * t.value;
        }
      });
  row.entries.emplace_back(i, diag);
  return kind;
}

template bool regular_neighbourhood<2>(const tree::CellGraph<2>&, tree::CellId);
template bool regular_neighbourhood<3>(const tree::CellGraph<3>&, tree::CellId);
template RowKind fd_row<2>(const tree::CellGraph<2>&, const DofLayout<2>&, const Boundary<2>&, tree::CellId,
                           Row&, std::span<const double>);
template RowKind fd_row<3>(const tree::CellGraph<3>&, const DofLayout<3>&, const Boundary<3>&, tree::CellId,
                           Row&, std::span<const double>);
template RowKind flux_row<2>(const tree::CellGraph<2>&, const DofLayout<2>&, const Boundary<2>&, tree::CellId,
                             const PoissonOptions&, rbf::WeightCache<2>*, RowScratch<2>&, Row&, rbf::Status&,
                             std::span<const double>);
template RowKind flux_row<3>(const tree::CellGraph<3>&, const DofLayout<3>&, const Boundary<3>&, tree::CellId,
                             const PoissonOptions&, rbf::WeightCache<3>*, RowScratch<3>&, Row&, rbf::Status&,
                             std::span<const double>);
template RowKind rbf_row<2>(const tree::CellGraph<2>&, const DofLayout<2>&, const Boundary<2>&, tree::CellId,
                            const PoissonOptions&, rbf::WeightCache<2>*, RowScratch<2>&, Row&, rbf::Status&);
template RowKind rbf_row<3>(const tree::CellGraph<3>&, const DofLayout<3>&, const Boundary<3>&, tree::CellId,
                            const PoissonOptions&, rbf::WeightCache<3>*, RowScratch<3>&, Row&, rbf::Status&);

}  // namespace liquid::mac
