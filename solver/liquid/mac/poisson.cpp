#include "liquid/mac/poisson.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "liquid/core/error.hpp"
#include "liquid/core/parallel.hpp"
#include "liquid/core/timer.hpp"

namespace liquid::mac {

namespace {

/// The unknown nearest the domain's centre.
template <int Dim>
tree::CellId pin_cell(const tree::CellGraph<Dim>& graph, const DofLayout<Dim>& layout) {
  const Vec<Dim> mid = graph.domain().centre();
  double best = std::numeric_limits<double>::infinity();
  tree::CellId pinned = tree::no_cell;
  for (tree::CellId c : layout.cell_of_dof) {
    const double d = (graph.centre(c) - mid).squaredNorm();
    if (d < best) best = d, pinned = c;
  }
  return pinned;
}

/// Adds a row that used RBF-FD weights (their weakest status `st`) to the statistics.
void count_rbf_row(AssemblyStats& s, const rbf::Status& st, tree::CellId c) {
  ++s.n_rbf_rows;
  if (st.info == rbf::Info::degree_reduced) ++s.n_degree_reduced;
  s.min_degree = std::min(s.min_degree, st.degree_used);
  s.max_stencil = std::max(s.max_stencil, st.n_nodes);
  if (st.condition > s.worst_condition) s.worst_condition = st.condition, s.worst_condition_cell = c;
}

/// Every row of -Lap p = -f, in parallel; the row statistics go to `stats`.
template <int Dim>
std::vector<Row> laplacian_rows(const tree::CellGraph<Dim>& graph, const PoissonSystem<Dim>& sys,
                                const PoissonProblem<Dim>& problem, const PoissonOptions& options,
                                rbf::WeightCache<Dim>* shared, AssemblyStats& stats) {
  const long n = sys.n_unknowns();
  std::vector<Row> rows(n);
  rbf::WeightCache<Dim> weight_cache;
  rbf::WeightCache<Dim>* const cache = options.cache_weights ? (shared ? shared : &weight_cache) : nullptr;
  const long hits_before = cache ? cache->hits() : 0;
  struct Local {
    RowScratch<Dim> scratch;
    AssemblyStats stats;
  };
  parallel_for(
      n, [] { return Local{}; },
      [&](Local& local, long i) {
        const tree::CellId c = sys.layout.cell_of_dof[i];
        Row& row = rows[i];
        row.rhs = problem.f_cells.empty() ? -problem.f(graph.centre(c)) : -problem.f_cells[c];
        if (!std::isfinite(row.rhs)) {
          const Vec<Dim> x = graph.centre(c);
          throw Error(fmt::format("the right-hand side f is {} at the centre ({:.6g}) of cell {}", row.rhs,
                                  fmt::join(x.data(), x.data() + Dim, ", "), c));
        }
        AssemblyStats& s = local.stats;
        if (options.irregular == IrregularRows::flux) {
          rbf::Status st;
          const RowKind kind = flux_row(graph, sys.layout, sys.boundary, c, options, cache, local.scratch,
                                        row, st, problem.face_coefficient);
          if (kind == RowKind::fd) {
            ++s.n_fd_rows;
            return;
          }
          count_rbf_row(s, st, c);
          return;
        }
        if (options.regular_fd && regular_neighbourhood(graph, c)) {
          ++(fd_row(graph, sys.layout, sys.boundary, c, row, problem.face_coefficient) == RowKind::fd
                 ? s.n_fd_rows
                 : s.n_on_interface);
          return;
        }
        if (!problem.face_coefficient.empty()) {
          const Vec<Dim> x = graph.centre(c);
          throw Error(fmt::format(
              "cell {} at ({:.6g}) needs an RBF-FD row, which takes no face coefficients (a variable-density "
              "PPE needs a uniform tree and regular_fd, or flux rows)",
              c, fmt::join(x.data(), x.data() + Dim, ", ")));
        }
        rbf::Status st;
        if (rbf_row(graph, sys.layout, sys.boundary, c, options, cache, local.scratch, row, st) ==
            RowKind::on_interface) {
          ++s.n_on_interface;
          return;
        }
        count_rbf_row(s, st, c);
      },
      [&](Local& local) {
        const AssemblyStats& s = local.stats;
        stats.n_fd_rows += s.n_fd_rows;
        stats.n_rbf_rows += s.n_rbf_rows;
        stats.n_on_interface += s.n_on_interface;
        stats.n_degree_reduced += s.n_degree_reduced;
        stats.n_retried += local.scratch.n_retried;
        stats.min_degree = std::min(stats.min_degree, s.min_degree);
        stats.max_stencil = std::max(stats.max_stencil, s.max_stencil);
        if (s.worst_condition > stats.worst_condition)
          stats.worst_condition = s.worst_condition, stats.worst_condition_cell = s.worst_condition_cell;
      });
  stats.n_cache_hits = cache ? cache->hits() - hits_before : 0;
  return rows;
}

/// The sparse matrix from the rows: the pinned unknown's column moves to the right-hand side (the
/// rest is a Laplacian with one Dirichlet node, its FD part symmetric), and a zero-mean system
/// gets a multiplier column and a last row asking for zero volume-weighted mean. The rows go
/// straight into compressed row storage: each row's entries sorted by column, the entries of one
/// column summed in the order the row lists them (the sums setFromTriplets forms, without its
/// column-major copy and transposition). `rows` is consumed.
template <int Dim>
void fill_matrix(const tree::CellGraph<Dim>& graph, std::vector<Row>& rows, PoissonSystem<Dim>& sys) {
  const long n = sys.n_unknowns();
  const long size = n + (sys.bordered ? 1 : 0);
  sys.b.resize(size);
  const int pinned_dof = sys.pinned == tree::no_cell ? -1 : sys.layout.dof_of_cell[sys.pinned];
  const double pinned_value = pinned_dof < 0 ? 0.0 : rows[pinned_dof].rhs;
  // Per row, in parallel: the pinned column to the right-hand side, then the entries sorted by
  // column (stable, so that a column's values keep their order) and each column's values summed.
  parallel_for(n, [&](long i) {
    Row& row = rows[i];
    sys.b[i] = row.rhs;
    auto& e = row.entries;
    std::size_t kept = 0;
    for (std::size_t k = 0; k < e.size(); ++k) {
      if (e[k].first == pinned_dof && i != pinned_dof)
        sys.b[i] -= e[k].second * pinned_value;
      else
        e[kept++] = e[k];
    }
    e.resize(kept);
    std::stable_sort(e.begin(), e.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    std::size_t out = 0;
    for (std::size_t k = 0; k < e.size(); ++k) {
      if (out > 0 && e[out - 1].first == e[k].first)
        e[out - 1].second += e[k].second;
      else
        e[out++] = e[k];
    }
    e.resize(out);
  });
  std::vector<int> outer(size + 1, 0);
  for (long i = 0; i < n; ++i)
    outer[i + 1] = outer[i] + static_cast<int>(rows[i].entries.size()) + (sys.bordered ? 1 : 0);
  if (sys.bordered) outer[n + 1] = outer[n] + static_cast<int>(n);
  std::vector<int> inner(outer[size]);
  std::vector<double> value(outer[size]);
  parallel_for(n, [&](long i) {
    int at = outer[i];
    for (const auto& [j, v] : rows[i].entries) inner[at] = j, value[at++] = v;
    if (sys.bordered) inner[at] = static_cast<int>(n), value[at] = 1.0;
  });
  if (sys.bordered) {
    const double h_min = graph.cell_size(sys.layout.cell_of_dof.front()).minCoeff();
    double volume = 0.0;
    for (tree::CellId c : sys.layout.cell_of_dof) volume += graph.volume(c);
    const double scale = 1.0 / (h_min * h_min);
    for (long i = 0; i < n; ++i) {
      inner[outer[n] + i] = static_cast<int>(i);
      value[outer[n] + i] = scale * graph.volume(sys.layout.cell_of_dof[i]) / volume;
    }
    sys.b[n] = 0.0;
  }
  sys.A = Eigen::Map<const linalg::SparseMatrix>(size, size, outer[size], outer.data(), inner.data(),
                                                 value.data());
  for (long i = 0; i < size; ++i)
    LIQUID_VERIFY(std::isfinite(sys.b[i]),
                  "the Poisson right-hand side is {} in the row of unknown {} (cell {}): check the boundary "
                  "values",
                  sys.b[i], i, i < n ? sys.layout.cell_of_dof[i] : tree::no_cell);
}

}  // namespace

template <int Dim>
PoissonSystem<Dim> assemble_poisson(const tree::CellGraph<Dim>& graph, const PoissonProblem<Dim>& problem,
                                    const PoissonOptions& options, rbf::WeightCache<Dim>* cache) {
  LIQUID_VERIFY(problem.f || !problem.f_cells.empty(), "Poisson problem without a right-hand side");
  LIQUID_VERIFY(problem.f_cells.empty() || static_cast<int>(problem.f_cells.size()) >= graph.cell_capacity(),
                "Poisson problem: {} right-hand-side values for {} cell ids", problem.f_cells.size(),
                graph.cell_capacity());
  LIQUID_VERIFY(!problem.boundary.levelset || problem.boundary.dirichlet,
                "a level-set problem needs its Dirichlet value function");
  LIQUID_VERIFY(!problem.boundary.air_cells() || problem.boundary.dirichlet,
                "air cells need their Dirichlet value function");
  LIQUID_VERIFY(!problem.boundary.dirichlet_walls || problem.boundary.dirichlet,
                "Dirichlet walls need their value function");
  LIQUID_VERIFY(problem.face_coefficient.empty() ||
                    static_cast<int>(problem.face_coefficient.size()) >= graph.face_capacity(),
                "Poisson problem: {} face coefficients for {} face ids", problem.face_coefficient.size(),
                graph.face_capacity());
  if (!problem.face_coefficient.empty())
    for (tree::FaceId f : graph.face_ids())
      LIQUID_VERIFY(problem.face_coefficient[f] > 0.0 && std::isfinite(problem.face_coefficient[f]),
                    "Poisson problem: face {} has coefficient {} (must be positive and finite)", f,
                    problem.face_coefficient[f]);
  Stopwatch watch;
  PoissonSystem<Dim> sys;
  sys.boundary = problem.boundary;
  sys.layout =
      problem.boundary.unknown_cells.empty()
          ? number_unknowns<Dim>(graph, problem.boundary.levelset)
          : number_unknowns<Dim>(graph, std::span<const std::uint8_t>(problem.boundary.unknown_cells));
  // No Dirichlet value anywhere: Neumann walls and every cell an unknown.
  sys.singular = !problem.boundary.dirichlet_walls && sys.n_unknowns() == graph.n_cells();
  sys.bordered = sys.singular && options.nullspace == Nullspace::zero_mean;
  if (sys.singular && options.nullspace == Nullspace::pin) {
    LIQUID_VERIFY(problem.pin_value, "pinning a singular Neumann problem needs the value at the pinned cell");
    sys.pinned = pin_cell(graph, sys.layout);
  }
  AssemblyStats stats;
  std::vector<Row> rows = laplacian_rows(graph, sys, problem, options, cache, stats);
  if (sys.pinned != tree::no_cell) {
    // The pinned cell's row becomes p = value; its Laplacian row is kept for make_compatible().
    const int d = sys.layout.dof_of_cell[sys.pinned];
    sys.pinned_equation = std::move(rows[d]);
    rows[d].entries = {{d, 1.0}};
    rows[d].rhs = problem.pin_value(graph.centre(sys.pinned));
  }
  fill_matrix(graph, rows, sys);
  stats.n_unknowns = sys.n_unknowns();
  stats.seconds = watch.seconds();
  sys.stats = stats;
  return sys;
}

template <int Dim>
linalg::Vector uniform_source(const PoissonSystem<Dim>& system) {
  linalg::Vector c = linalg::Vector::Ones(system.b.size());
  if (system.pinned != tree::no_cell) c[system.layout.dof_of_cell[system.pinned]] = 0.0;
  return c;
}

template <int Dim>
double make_compatible(const PoissonSystem<Dim>& system, const linalg::Vector& z, linalg::Vector& x) {
  if (system.pinned == tree::no_cell || system.pinned_equation.entries.empty()) return 0.0;
  LIQUID_VERIFY(z.size() == x.size() && x.size() == system.b.size(),
                "make_compatible: {} and {} values for {} unknowns", z.size(), x.size(), system.b.size());
  // x - a z solves every row but the pin's with the source shifted by -a (z_pin = 0 keeps the
  // pinned value); a is chosen so that the pin's own row holds too: r(x) - a (row . z - 1) = 0.
  double rx = -system.pinned_equation.rhs, rz = -1.0;
  for (const auto& [j, v] : system.pinned_equation.entries) rx += v * x[j], rz += v * z[j];
  if (!(std::abs(rz) > 0.0) || !std::isfinite(rx / rz)) return 0.0;
  const double a = rx / rz;
  x -= a * z;
  return a;
}

template linalg::Vector uniform_source<2>(const PoissonSystem<2>&);
template linalg::Vector uniform_source<3>(const PoissonSystem<3>&);
template double make_compatible<2>(const PoissonSystem<2>&, const linalg::Vector&, linalg::Vector&);
template double make_compatible<3>(const PoissonSystem<3>&, const linalg::Vector&, linalg::Vector&);

template PoissonSystem<2> assemble_poisson<2>(const tree::CellGraph<2>&, const PoissonProblem<2>&,
                                              const PoissonOptions&, rbf::WeightCache<2>*);
template PoissonSystem<3> assemble_poisson<3>(const tree::CellGraph<3>&, const PoissonProblem<3>&,
                                              const PoissonOptions&, rbf::WeightCache<3>*);

}  // namespace liquid::mac
