#include "liquid/mac/poisson.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include <fmt/format.h>

#include "liquid/core/error.hpp"
#include "liquid/core/timer.hpp"
#include "liquid/rbf/polynomial.hpp"
#include "liquid/rbf/weight_cache.hpp"

namespace liquid::mac {

namespace {

template <int Dim>
DofLayout<Dim> make_layout(const CellGraph<Dim>& graph, const PoissonProblem<Dim>& problem) {
  DofLayout<Dim> layout;
  layout.levelset = problem.levelset;
  layout.dirichlet = problem.dirichlet;
  layout.dirichlet_walls = problem.dirichlet_walls;
  layout.dof_of_cell.assign(graph.cell_capacity(), -1);
  graph.for_each_cell([&](CellId c) {
    if (problem.levelset) {
      const double phi = problem.levelset(graph.centre(c));
      LIQUID_VERIFY(std::isfinite(phi), "level set is not finite at the centre of cell {}", c);
      if (!(phi < 0.0)) return;
    }
    layout.dof_of_cell[c] = static_cast<int>(layout.cell_of_dof.size());
    layout.cell_of_dof.push_back(c);
  });
  LIQUID_VERIFY(!layout.cell_of_dof.empty(),
                "the level set leaves no unknowns: no cell centre has phi < 0 ({} cells)", graph.n_cells());
  LIQUID_VERIFY(!problem.levelset || problem.dirichlet,
                "a level-set problem needs its Dirichlet value function");
  return layout;
}

// One matrix row: (column, value) pairs and a right-hand-side term.
struct Row {
  std::vector<std::pair<int, double>> entries;
  double rhs = 0.0;
};

// True when every side of c has exactly one face and it is full (same level) or a wall.
template <int Dim>
bool regular_neighbourhood(const CellGraph<Dim>& graph, CellId c) {
  for (int k = 0; k < Dim; ++k)
    for (int dir : {-1, 1}) {
      int n_faces = 0;
      bool ok = true;
      graph.for_each_side_face(c, k, dir, [&](const SideFace& s) {
        ++n_faces;
        ok = ok && (s.adjacency == Adjacency::same || s.adjacency == Adjacency::boundary);
      });
      if (n_faces != 1 || !ok) return false;
    }
  return true;
}

// Standard FD row of -Lap p at a regular cell (Shortley-Weller at interface cuts). Returns false
// when the centre sits on the interface (the row is then p_c = value).
template <int Dim>
void fd_row(const CellGraph<Dim>& graph, const DofLayout<Dim>& layout, CellId c, Row& row) {
  const int i = layout.dof_of_cell[c];
  const Vec<Dim> x = graph.centre(c);
  const Vec<Dim> h = graph.cell_size(c);
  double diag = 0.0;
  for (int k = 0; k < Dim; ++k) {
    // Per side: distance to the node, and the node (unknown or known value).
    double d[2];
    int dof[2];
    double val[2];
    for (int s = 0; s < 2; ++s) {
      const int dir = s == 0 ? -1 : 1;
      d[s] = h[k];
      dof[s] = i;  // a wall's ghost mirrors the centre
      val[s] = 0.0;
      graph.for_each_side_face(c, k, dir, [&](const SideFace& sf) {
        if (sf.adjacency == Adjacency::boundary) {
          if (!layout.dirichlet_walls) return;  // Neumann: the ghost mirrors the centre
          Vec<Dim> w = x;
          w[k] = dir < 0 ? graph.domain().lo[k] : graph.domain().hi[k];
          d[s] = 0.5 * h[k];
          dof[s] = -1;
          val[s] = layout.dirichlet(w);
          return;
        }
        const int j = layout.dof_of_cell[sf.neighbour];
        if (j >= 0) {
          dof[s] = j;
          return;
        }
        const Vec<Dim> y = graph.centre(sf.neighbour);
        const auto cut =
            levelset::crossing<Dim>(layout.levelset, x, y, layout.levelset(x), layout.levelset(y));
        LIQUID_VERIFY(cut.has_value(), "cell {}: no interface crossing towards outside neighbour {}", c,
                      sf.neighbour);
        d[s] = cut->theta * h[k];
        dof[s] = -1;
        val[s] = layout.dirichlet(cut->point);
      });
    }
    for (int s = 0; s < 2; ++s) {
      if (dof[s] < 0 && d[s] <= 1e-12 * h[k]) {  // the centre is on the interface
        row.entries = {{i, 1.0}};
        row.rhs = val[s];
        return;
      }
    }
    const double scale = 2.0 / (d[0] + d[1]);
    for (int s = 0; s < 2; ++s) {
      const double w = scale / d[s];
      diag += w;
      if (dof[s] >= 0)
        row.entries.emplace_back(dof[s], -w);
      else
        row.rhs += w * val[s];
    }
  }
  row.entries.emplace_back(i, diag);
}

// Weights of an operator on gathered nodes, dropping an offending node and retrying when the
// system is unusable. Returns the status of the final attempt. With a cache, stencils whose nodes
// all sit on the tree (cell centres and their wall images, no interface crossings) are looked up
// by their shape relative to the scale h: congruent T-junctions share one solve.
template <int Dim>
rbf::Status stencil_weights(std::vector<StencilNode<Dim>>& nodes, const Vec<Dim>& at,
                            const rbf::Operator<Dim>& op, const rbf::Config& config, std::vector<double>& w,
                            long& n_retried, rbf::WeightCache<Dim>* cache = nullptr, double h = 0.0) {
  thread_local std::vector<Vec<Dim>> xs;
  if (cache != nullptr) {
    // A canonical node order, so congruent stencils gathered in different orders share an entry:
    // by distance from `at`, ties by offset, on offsets rounded to 2^-16 h (exact for dyadic
    // layouts; squares fit in 64 bits for offsets up to 2^14 h). Weights follow their nodes, so
    // the caller is unaffected, except that a retry below then drops the farthest node by
    // distance rather than the last one gathered.
    using Key = std::array<std::int64_t, Dim + 1>;
    thread_local std::vector<std::pair<Key, StencilNode<Dim>>> keyed;
    keyed.clear();
    for (const auto& n : nodes) {
      Key k{};
      for (int d = 0; d < Dim; ++d) {
        k[d + 1] = std::llround((n.x[d] - at[d]) / h * 0x1p16);
        k[0] += k[d + 1] * k[d + 1];
      }
      keyed.emplace_back(k, n);
    }
    std::stable_sort(keyed.begin(), keyed.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    for (std::size_t j = 0; j < nodes.size(); ++j) nodes[j] = keyed[j].second;
  }
  const auto solve = [&] {
    xs.clear();
    for (const auto& n : nodes) xs.push_back(n.x);
    return cache != nullptr ? cache->weights(xs, at, h, op, config, w)
                            : rbf::weights<Dim>(xs, at, op, config, w);
  };
  for (int attempt = 0; attempt < 4; ++attempt) {
    const rbf::Status st = solve();
    if (st.usable()) return st;
    if (st.info == rbf::Info::coincident_nodes && st.node_b > 0) {
      nodes.erase(nodes.begin() + st.node_b);  // keep the nearer of the two
    } else if (st.info == rbf::Info::singular_system && nodes.size() > 2) {
      nodes.pop_back();  // drop the farthest node
    } else {
      return st;
    }
    ++n_retried;
  }
  return solve();
}

/// The cache to use for a stencil: none when it holds an interface crossing (a level-set problem's
/// known node), whose position is arbitrary and would only fill the cache.
template <int Dim>
rbf::WeightCache<Dim>* cache_for(const std::vector<StencilNode<Dim>>& nodes, const DofLayout<Dim>& layout,
                                 rbf::WeightCache<Dim>* cache) {
  if (cache == nullptr || !layout.levelset) return cache;
  for (const auto& n : nodes)
    if (n.dof < 0) return nullptr;
  return cache;
}

template <int Dim>
int target_nodes(const PoissonOptions& options) {
  return static_cast<int>(std::ceil(options.growth * rbf::n_polynomial_terms(Dim, options.rbf.degree))) + 1;
}

}  // namespace

template <int Dim>
PoissonSystem<Dim> assemble_poisson(const CellGraph<Dim>& graph, const PoissonProblem<Dim>& problem,
                                    const PoissonOptions& options) {
  LIQUID_VERIFY(problem.f, "Poisson problem without a right-hand side");
  Stopwatch watch;
  PoissonSystem<Dim> sys;
  sys.layout = make_layout(graph, problem);
  const long n = sys.n_unknowns();
  const bool neumann = !problem.levelset && !problem.dirichlet_walls;
  sys.bordered = neumann && options.nullspace == Nullspace::zero_mean;
  if (neumann && options.nullspace == Nullspace::pin) {
    LIQUID_VERIFY(problem.pin_value, "pinning a Neumann problem needs the value at the pinned cell");
    const Vec<Dim> mid = graph.domain().centre();
    double best = std::numeric_limits<double>::infinity();
    for (CellId c : sys.layout.cell_of_dof) {
      const double d = (graph.centre(c) - mid).squaredNorm();
      if (d < best) best = d, sys.pinned = c;
    }
  }

  std::vector<Row> rows(n);
  const int n_target = target_nodes<Dim>(options);
  rbf::WeightCache<Dim> weight_cache;
  rbf::WeightCache<Dim>* const cache = options.cache_weights ? &weight_cache : nullptr;
  AssemblyStats stats;
  std::string failure;
  long n_fd = 0, n_rbf = 0, n_reduced = 0, n_retried = 0, n_on_interface = 0;
#pragma omp parallel reduction(+ : n_fd, n_rbf, n_reduced, n_retried, n_on_interface)
  {
    std::vector<StencilNode<Dim>> nodes;
    std::vector<double> w;
    double worst = 0.0;
    CellId worst_cell = no_cell;
    int min_degree = 99;
#pragma omp for schedule(dynamic, 64)
    for (long i = 0; i < n; ++i) {
      const CellId c = sys.layout.cell_of_dof[i];
      Row& row = rows[i];
      try {
        if (c == sys.pinned) {
          row.entries = {{static_cast<int>(i), 1.0}};
          row.rhs = problem.pin_value(graph.centre(c));
          continue;
        }
        row.rhs = -problem.f(graph.centre(c));
        if (options.regular_fd && regular_neighbourhood(graph, c)) {
          fd_row(graph, sys.layout, c, row);
          ++n_fd;
          continue;
        }
        const Vec<Dim> x = graph.centre(c);
        const CellId seed[1] = {c};
        gather_stencil<Dim>(graph, sys.layout, seed, x, options.rule, n_target, nodes);
        // A centre within 1e-3 cell sizes of the interface takes the interface value.
        const double near = 1e-3 * graph.cell_size(c).maxCoeff();
        bool on_interface = false;
        for (const auto& nd : nodes)
          if (nd.dof < 0 && (nd.x - x).norm() < near) {
            row.entries = {{static_cast<int>(i), 1.0}};
            row.rhs = nd.value;
            on_interface = true;
            break;
          }
        if (on_interface) {
          ++n_on_interface;
          continue;
        }
        const rbf::Status st =
            stencil_weights<Dim>(nodes, x, rbf::Operator<Dim>::lap(), options.rbf, w, n_retried,
                                 cache_for<Dim>(nodes, sys.layout, cache), graph.cell_size(c)[0]);
        LIQUID_VERIFY(st.usable(), "cell {} at ({:.6g}): RBF-FD Laplacian weights unusable: {}", c,
                      fmt::join(x.data(), x.data() + Dim, ", "), st.describe());
        ++n_rbf;
        if (st.info == rbf::Info::degree_reduced) ++n_reduced;
        min_degree = std::min(min_degree, st.degree_used);
        if (st.condition > worst) worst = st.condition, worst_cell = c;
        for (std::size_t j = 0; j < nodes.size(); ++j) {
          if (nodes[j].dof >= 0)
            row.entries.emplace_back(nodes[j].dof, -w[j]);
          else
            row.rhs += w[j] * nodes[j].value;
        }
      } catch (const std::exception& e) {
#pragma omp critical(liquid_poisson_failure)
        if (failure.empty()) failure = e.what();
      }
    }
#pragma omp critical(liquid_poisson_stats)
    {
      if (worst > stats.worst_condition)
        stats.worst_condition = worst, stats.worst_condition_cell = worst_cell;
      stats.min_degree = std::min(stats.min_degree, min_degree);
    }
  }
  if (!failure.empty()) throw Error(failure);
  stats.n_unknowns = n;
  stats.n_fd_rows = n_fd;
  stats.n_rbf_rows = n_rbf;
  stats.n_degree_reduced = n_reduced;
  stats.n_retried = n_retried;
  stats.n_on_interface = n_on_interface;
  stats.n_cache_hits = weight_cache.hits();

  const long size = n + (sys.bordered ? 1 : 0);
  std::vector<Eigen::Triplet<double>> triplets;
  sys.b.resize(size);
  // The pinned unknown is known: its column moves to the right-hand side, so the remaining system
  // is a Laplacian with one Dirichlet node (its FD part stays symmetric).
  const int pinned_dof = sys.pinned == no_cell ? -1 : sys.layout.dof_of_cell[sys.pinned];
  const double pinned_value = pinned_dof < 0 ? 0.0 : rows[pinned_dof].rhs;
  for (long i = 0; i < n; ++i) {
    sys.b[i] = rows[i].rhs;
    for (const auto& [j, v] : rows[i].entries) {
      if (j == pinned_dof && i != pinned_dof)
        sys.b[i] -= v * pinned_value;
      else
        triplets.emplace_back(i, j, v);
    }
  }
  if (sys.bordered) {
    // Rows get a multiplier column; the last row asks for zero (volume-weighted) mean.
    const double h_min = graph.cell_size(sys.layout.cell_of_dof.front()).minCoeff();
    double volume = 0.0;
    for (CellId c : sys.layout.cell_of_dof) volume += graph.volume(c);
    const double scale = 1.0 / (h_min * h_min);
    for (long i = 0; i < n; ++i) {
      triplets.emplace_back(i, n, 1.0);
      triplets.emplace_back(n, i, scale * graph.volume(sys.layout.cell_of_dof[i]) / volume);
    }
    sys.b[n] = 0.0;
  }
  sys.A.resize(size, size);
  sys.A.setFromTriplets(triplets.begin(), triplets.end());
  LIQUID_VERIFY(sys.b.allFinite(),
                "the Poisson right-hand side has a non-finite entry (check f and the boundary values)");
  stats.seconds = watch.seconds();
  sys.stats = stats;
  return sys;
}

template <int Dim>
std::vector<double> face_normal_derivative(const CellGraph<Dim>& graph, const PoissonSystem<Dim>& system,
                                           const PoissonOptions& options, const linalg::Vector& p) {
  LIQUID_VERIFY(p.size() >= system.n_unknowns(), "face_normal_derivative: {} values for {} unknowns",
                p.size(), system.n_unknowns());
  std::vector<double> out(graph.face_capacity(), std::numeric_limits<double>::quiet_NaN());
  const std::vector<FaceId> faces = graph.face_ids();
  rbf::Config config = options.rbf;
  config.degree = options.gradient_degree;
  const int n_target =
      static_cast<int>(std::ceil(options.growth * rbf::n_polynomial_terms(Dim, config.degree))) + 1;
  const auto& layout = system.layout;
  std::string failure;
  long n_retried = 0;
  rbf::WeightCache<Dim> weight_cache;
  rbf::WeightCache<Dim>* const cache = options.cache_weights ? &weight_cache : nullptr;
#pragma omp parallel reduction(+ : n_retried)
  {
    std::vector<StencilNode<Dim>> nodes;
    std::vector<double> w;
#pragma omp for schedule(dynamic, 64)
    for (std::size_t q = 0; q < faces.size(); ++q) {
      const FaceId f = faces[q];
      const GraphFace& g = graph.face(f);
      if (g.is_boundary()) continue;
      const int ia = layout.dof_of_cell[g.cell[0]], ib = layout.dof_of_cell[g.cell[1]];
      if (ia < 0 || ib < 0) continue;
      try {
        if (!g.hanging() && g.side_level[0] == g.side_level[1]) {
          out[f] = (p[ib] - p[ia]) / graph.cell_size(g.cell[0])[g.axis];
          continue;
        }
        const Vec<Dim> at = graph.face_centre(f);
        const CellId seeds[2] = {g.cell[0], g.cell[1]};
        gather_stencil<Dim>(graph, layout, seeds, at, options.rule, n_target, nodes);
        const rbf::Status st =
            stencil_weights<Dim>(nodes, at, rbf::Operator<Dim>::partial(g.axis), config, w, n_retried,
                                 cache_for<Dim>(nodes, layout, cache),
                                 std::min(graph.cell_size(g.cell[0])[0], graph.cell_size(g.cell[1])[0]));
        LIQUID_VERIFY(st.usable(), "face {} between cells {} and {}: RBF-FD gradient weights unusable: {}", f,
                      g.cell[0], g.cell[1], st.describe());
        double v = 0.0;
        for (std::size_t j = 0; j < nodes.size(); ++j)
          v += w[j] * (nodes[j].dof >= 0 ? p[nodes[j].dof] : nodes[j].value);
        out[f] = v;
      } catch (const std::exception& e) {
#pragma omp critical(liquid_gradient_failure)
        if (failure.empty()) failure = e.what();
      }
    }
  }
  if (!failure.empty()) throw Error(failure);
  return out;
}

template PoissonSystem<2> assemble_poisson<2>(const CellGraph<2>&, const PoissonProblem<2>&,
                                              const PoissonOptions&);
template PoissonSystem<3> assemble_poisson<3>(const CellGraph<3>&, const PoissonProblem<3>&,
                                              const PoissonOptions&);
template std::vector<double> face_normal_derivative<2>(const CellGraph<2>&, const PoissonSystem<2>&,
                                                       const PoissonOptions&, const linalg::Vector&);
template std::vector<double> face_normal_derivative<3>(const CellGraph<3>&, const PoissonSystem<3>&,
                                                       const PoissonOptions&, const linalg::Vector&);

}  // namespace liquid::mac
