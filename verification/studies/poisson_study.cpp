#include "studies/poisson_study.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <tuple>

#include <fmt/format.h>

#include "common/fit.hpp"
#include "liquid/core/error.hpp"
#include "liquid/core/timer.hpp"
#include "liquid/tree/builders.hpp"

namespace liquid::verification {
namespace {

template <int Dim>
std::string format_point(const Vec<Dim>& x) {
  std::string s = "(";
  for (int k = 0; k < Dim; ++k) s += fmt::format("{}{:.4g}", k ? ", " : "", x[k]);
  return s + ")";
}

template <int Dim>
std::string describe_cell(const tree::CellGraph<Dim>& graph, const PoissonStudy<Dim>& study, tree::CellId c) {
  if (c == tree::no_cell) return {};
  std::string s =
      fmt::format("cell {} at {}, level {}", c, format_point<Dim>(graph.centre(c)), graph.level(c));
  if (study.levelset) s += fmt::format(", phi {:.3g}", study.levelset(graph.centre(c)));
  return s;
}

}  // namespace

template <int Dim>
tree::CellGraph<Dim> row_tree(const PoissonStudy<Dim>& study, const tree::CellGraph<Dim>& first, int level,
                              const tree::CellGraphOptions<Dim>& options) {
  if (study.rows == RowProtocol::rebuild) return study.make_tree(level, options);
  return tree::refined<Dim>(first, level - study.level_min, options);
}

template <int Dim>
mac::PoissonProblem<Dim> poisson_problem(const PoissonStudy<Dim>& study) {
  mac::PoissonProblem<Dim> problem;
  problem.f = study.laplacian;
  problem.boundary.levelset = study.levelset;
  problem.boundary.dirichlet = study.exact;
  problem.boundary.dirichlet_walls = study.dirichlet_walls;
  problem.pin_value = study.exact;
  if (!study.dirichlet_walls) {
    // Neumann walls carry the exact solution's flux, so any smooth p converges (zero for the paper's).
    const auto gradient = study.gradient;
    problem.boundary.wall_flux = [gradient](const Vec<Dim>& x, const Vec<Dim>& n) {
      return gradient(x).dot(n);
    };
  }
  return problem;
}

/// For a zero-mean (bordered) system, the volume-weighted mean of x - p over the unknowns: the
/// constant an error is measured after removing. 0 for the others.
template <int Dim>
double mean_shift(const tree::CellGraph<Dim>& graph, const PoissonStudy<Dim>& study,
                  const mac::PoissonSystem<Dim>& system, const linalg::Vector& x) {
  if (!system.bordered) return 0.0;
  const auto& cells = system.layout.cell_of_dof;
  double shift = 0.0, volume = 0.0;
  for (std::size_t i = 0; i < cells.size(); ++i) {
    shift += graph.volume(cells[i]) * (x[i] - study.exact(graph.centre(cells[i])));
    volume += graph.volume(cells[i]);
  }
  return shift / volume;
}

template <int Dim>
double max_error(const tree::CellGraph<Dim>& graph, const PoissonStudy<Dim>& study,
                 const mac::PoissonSystem<Dim>& system, const linalg::Vector& x) {
  const auto& cells = system.layout.cell_of_dof;
  const double shift = mean_shift<Dim>(graph, study, system, x);
  double e = 0.0;
  for (std::size_t i = 0; i < cells.size(); ++i)
    e = std::max(e, std::abs(x[i] - shift - study.exact(graph.centre(cells[i]))));
  return e;
}

template <int Dim>
PoissonRun solve_poisson(const tree::CellGraph<Dim>& graph, const PoissonStudy<Dim>& study) {
  const mac::PoissonSystem<Dim> system =
      mac::assemble_poisson<Dim>(graph, poisson_problem<Dim>(study), study.discretisation);

  PoissonRun run;
  run.n_cells = graph.n_cells();
  run.n_unknowns = system.n_unknowns();
  run.assembly = system.stats;
  run.assembly_seconds = system.stats.seconds;
  linalg::Vector x;
  run.solve = linalg::solve(system.A, system.b, x, study.solver);
  run.solve_seconds = run.solve.setup_seconds + run.solve.solve_seconds;
  if (!run.solve.converged()) return run;

  // L-inf of p over the unknowns (minus the volume-weighted mean difference for zero-mean systems).
  const auto& cells = system.layout.cell_of_dof;
  const double shift = mean_shift<Dim>(graph, study, system, x);
  tree::CellId worst_cell = tree::no_cell;
  for (std::size_t i = 0; i < cells.size(); ++i) {
    const double e = std::abs(x[i] - shift - study.exact(graph.centre(cells[i])));
    if (e > run.err_p || worst_cell == tree::no_cell) run.err_p = e, worst_cell = cells[i];
  }
  run.worst_p = describe_cell(graph, study, worst_cell);
  std::vector<std::pair<long, double>> by_level;
  for (std::size_t i = 0; i < cells.size(); ++i) {
    const int l = graph.level(cells[i]);
    if (static_cast<int>(by_level.size()) <= l) by_level.resize(l + 1, {0, 0.0});
    by_level[l].first += 1;
    by_level[l].second =
        std::max(by_level[l].second, std::abs(x[i] - shift - study.exact(graph.centre(cells[i]))));
  }
  for (int l = 0; l < static_cast<int>(by_level.size()); ++l)
    if (by_level[l].first > 0) run.err_by_level.emplace_back(l, by_level[l].first, by_level[l].second);

  const std::vector<double> dpdn = mac::face_normal_derivative<Dim>(graph, system, study.discretisation, x);
  tree::FaceId worst_face = tree::no_face;
  graph.for_each_face([&](tree::FaceId f) {
    if (std::isnan(dpdn[f])) return;
    const double exact = study.gradient(graph.face_centre(f))[graph.face(f).axis];
    const double e = std::abs(dpdn[f] - exact);
    if (e > run.err_grad || worst_face == tree::no_face) run.err_grad = e, worst_face = f;
    const auto& g = graph.face(f);
    if (!g.is_boundary())
      run.max_level_jump = std::max(run.max_level_jump, std::abs(g.side_level[0] - g.side_level[1]));
  });
  if (worst_face != tree::no_face) {
    const auto& g = graph.face(worst_face);
    run.worst_grad =
        fmt::format("face {} at {}, levels {}|{}, {}", worst_face,
                    format_point<Dim>(graph.face_centre(worst_face)), g.side_level[0], g.side_level[1],
                    !g.hanging() && g.side_level[0] == g.side_level[1] ? "two-point FD" : "RBF-FD");
  }
  run.h = graph.cell_size(cells.front()).maxCoeff();
  graph.for_each_cell([&](tree::CellId c) { run.h = std::min(run.h, graph.cell_size(c).maxCoeff()); });
  return run;
}

template <int Dim>
CaseResult run_poisson_study(PoissonStudy<Dim> study, const CaseOptions& options) {
  if (options.levels) study.level_min = options.levels->first, study.level_max = options.levels->last;
  if (options.max_jump) study.max_jump = *options.max_jump;
  if (options.solver) study.solver.kind = *options.solver;
  if (options.stencil) study.discretisation.rule = *options.stencil;
  if (options.rbf_exponent) study.discretisation.rbf.exponent = *options.rbf_exponent;
  if (options.rbf_degree) study.discretisation.rbf.degree = *options.rbf_degree;
  if (options.gradient_degree) study.discretisation.gradient_degree = *options.gradient_degree;
  if (options.stencil_growth) study.discretisation.growth = *options.stencil_growth;
  if (options.ring_cap) study.discretisation.ring_cap = *options.ring_cap;
  if (options.rows) study.rows = *options.rows;
  if (options.nullspace) {
    LIQUID_VERIFY(!study.levelset && !study.dirichlet_walls,
                  "--nullspace applies to pure Neumann problems; this study has Dirichlet values{}, so "
                  "its system is not singular",
                  study.levelset ? " on a level set" : " on its walls");
    study.discretisation.nullspace = *options.nullspace;
  }
  if (options.tolerance) study.solver.tolerance = *options.tolerance;
  if (options.perturb) {
    // A deliberately inconsistent scheme for showing that the gate catches regressions: degree-1
    // polynomials cannot reproduce the Laplacian of quadratics at T-junctions.
    study.discretisation.rbf.degree = 1;
  }
  LIQUID_VERIFY(study.level_min >= 0 && study.level_max + study.finest_offset <= morton::max_level<Dim>,
                "--levels {}:{} out of range for {}D (finest level at most {})", study.level_min,
                study.level_max, Dim, morton::max_level<Dim> - study.finest_offset);
  LIQUID_VERIFY(study.level_min < study.level_max,
                "--levels {}:{}: a convergence study needs at least two rows (A < B)", study.level_min,
                study.level_max);
  LIQUID_VERIFY(study.max_jump >= 1, "--max-jump must be at least 1, got {}", study.max_jump);
  // Every cell of a row sits at its base level or finer, so 2^(Dim * base) bounds its cells from
  // below: refuse before building anything that large.
  if (options.max_cells > 0) {
    const double lower = std::ldexp(1.0, Dim * study.level_max);
    LIQUID_VERIFY(lower <= double(options.max_cells),
                  "--levels {}:{}: the row at base level {} has at least {:.3g} cells, over the budget of {} "
                  "cells (--max-cells N raises it)",
                  study.level_min, study.level_max, study.level_max, lower, options.max_cells);
  }
  study.max_cells = options.max_cells;

  CaseResult result;
  tree::CellGraphOptions<Dim> tree_options;
  tree_options.max_jump = study.max_jump;
  Table adaptive("adaptive tree (FD where regular, RBF-FD at T-junctions)",
                 {"level", "h", "unknowns", "rbf rows", "jump", "err p", "order p", "err dp/dn",
                  "order dp/dn", "assembly s", "solve s", "iterations"});
  Table levels("where the error lives: L-inf error of p on the unknowns of each cell level",
               {"row", "cell level", "unknowns", "err p", "share of row err"});
  Table uniform("uniform grid at the same finest h",
                {"level", "h", "unknowns", "err p", "err dp/dn", "assembly s", "solve s", "iterations"});
  std::vector<double> hs, ep, eg, nd, uh, uep, ueg, at, ut;  // at/ut: time to solution
  solve_rows<Dim>(study, result, "", [&](int level, const PoissonRun& run) {
    const std::size_t k = hs.size();
    hs.push_back(run.h), ep.push_back(run.err_p), eg.push_back(run.err_grad), nd.push_back(run.n_unknowns);
    at.push_back(run.assembly_seconds + run.solve_seconds);
    const Table::Cell op = k ? Table::Cell(pair_order(hs[k - 1], ep[k - 1], hs[k], ep[k])) : Table::Cell{};
    const Table::Cell og = k ? Table::Cell(pair_order(hs[k - 1], eg[k - 1], hs[k], eg[k])) : Table::Cell{};
    result.gate.push_back({fmt::format("level {} err p", level), GateFigure::Kind::error, run.err_p});
    result.gate.push_back({fmt::format("level {} err dp/dn", level), GateFigure::Kind::error, run.err_grad});
    result.gate.push_back({fmt::format("level {} iterations", level), GateFigure::Kind::iterations,
                           double(run.solve.iterations)});
    adaptive.add_row({long(level), run.h, run.n_unknowns, run.assembly.n_rbf_rows, long(run.max_level_jump),
                      run.err_p, op, run.err_grad, og, run.assembly_seconds, run.solve_seconds,
                      long(run.solve.iterations)});
    result.notes.push_back(
        fmt::format("level {}: worst p at {}; worst dp/dn at {}; weight cache: {} hits for {} RBF-FD rows",
                    level, run.worst_p, run.worst_grad, run.assembly.n_cache_hits, run.assembly.n_rbf_rows));
    result.expect(std::isfinite(run.err_p) && std::isfinite(run.err_grad),
                  fmt::format("level {}: NaN error", level));
    for (const auto& [l, n, e] : run.err_by_level)
      levels.add_row(
          {long(level), long(l), n, e, run.err_p > 0.0 ? Table::Cell(e / run.err_p) : Table::Cell{}});
    if (k > 0) {
      result.expect(run.h < hs[k - 1], fmt::format("level {}: its finest h {:.4g} is not below the previous "
                                                   "row's ({:.4g}): the rows are not a refinement sequence",
                                                   level, run.h, hs[k - 1]));
      if (!(run.err_p < ep[k - 1]) && ep[k - 1] >= exact_error_level)
        result.warnings.push_back(fmt::format(
            "level {}: the error of p ({:.3e}) did not fall from the row before ({:.3e}); the study is not "
            "in its asymptotic range there{}",
            level, run.err_p, ep[k - 1],
            study.rows == RowProtocol::rebuild ? " (rows rebuilt per level are not nested: try --rows refine)"
                                               : ""));
    }

    const int fine = level + study.finest_offset;
    const double limit = options.full ? 4.0 * study.uniform_limit : study.uniform_limit;
    if (std::pow(2.0, Dim * fine) > limit) return;
    // A uniform row's unknowns are at most its cells.
    if (study.max_cells > 0 &&
        budget_cost<Dim>(std::ldexp(1.0, Dim * fine), std::ldexp(1.0, Dim * fine)) > double(study.max_cells))
      return;
    const tree::CellGraph<Dim> flat = tree::uniform<Dim>(study.domain, fine, tree_options);
    const PoissonRun u = solve_poisson<Dim>(flat, study);
    if (!u.solve.converged()) return;
    uh.push_back(u.h), uep.push_back(u.err_p), ueg.push_back(u.err_grad);
    ut.push_back(u.assembly_seconds + u.solve_seconds);
    uniform.add_row({long(fine), u.h, u.n_unknowns, u.err_p, u.err_grad, u.assembly_seconds, u.solve_seconds,
                     long(u.solve.iterations)});
  });
  result.tables.push_back(std::move(adaptive));
  result.tables.push_back(std::move(uniform));
  result.tables.push_back(std::move(levels));
  // Per-step orders that spread by more than 0.5 mean a pre-asymptotic study: the fit is not an order.
  if (hs.size() >= 3 && *std::min_element(ep.begin(), ep.end()) >= exact_error_level) {
    std::vector<double> steps;
    for (std::size_t k = 1; k < hs.size(); ++k)
      steps.push_back(pair_order(hs[k - 1], ep[k - 1], hs[k], ep[k]));
    const auto [lo, hi] = std::minmax_element(steps.begin(), steps.end());
    if (*hi - *lo > 0.5)
      result.warnings.push_back(fmt::format(
          "the per-step orders of p spread from {:.2f} (rows {} to {}) to {:.2f} (rows {} to {}): the study "
          "is "
          "pre-asymptotic, and its fitted order is not yet the scheme's",
          *lo, study.level_min + (lo - steps.begin()), study.level_min + (lo - steps.begin()) + 1, *hi,
          study.level_min + (hi - steps.begin()), study.level_min + (hi - steps.begin()) + 1));
  }

  const double order = fit_order(hs, ep), order_grad = fit_order(hs, eg);
  // Against unknowns: err ~ N^(-q/Dim), so q = -Dim * slope of log err against log N.
  const double order_dofs = -Dim * fit_order(nd, ep);
  result.gate.push_back({"order p", GateFigure::Kind::order, order});
  result.gate.push_back({"order dp/dn", GateFigure::Kind::order, order_grad});
  result.fields.set("order", order);
  result.fields.set("order_grad", order_grad);
  result.fields.set("order_dofs", order_dofs);
  result.expect(hs.size() >= 2, "fewer than two levels: no order");
  // A scheme that reproduces p exactly (a polynomial it is exact for) has errors at round-off and
  // no order to speak of: that is a pass, said in a note, not a NaN order below a floor.
  const auto at_roundoff = [](const std::vector<double>& e) {
    return !e.empty() && *std::max_element(e.begin(), e.end()) < exact_error_level;
  };
  result.asserted = study.asserted;
  if (study.error_ceiling && !ep.empty())
    result.expect(ep.back() <= *study.error_ceiling,
                  fmt::format("the finest row's error of p {:.3e} is above the expected {:.3e}", ep.back(),
                              *study.error_ceiling));
  if (at_roundoff(ep) && at_roundoff(eg)) {
    result.notes.push_back(
        fmt::format("every error is below {:.0e}: the scheme is exact for this p", exact_error_level));
  } else {
    result.expect(std::isfinite(order) && std::isfinite(order_grad),
                  "the fitted orders are not finite (rows with equal errors or h)");
    result.expect(order >= study.order_floor,
                  fmt::format("order of p {:.2f} below the floor {:.2f}", order, study.order_floor));
    result.expect(
        order_grad >= study.order_grad_floor,
        fmt::format("order of dp/dn {:.2f} below the floor {:.2f}", order_grad, study.order_grad_floor));
  }
  result.notes.push_back(fmt::format(
      "observed orders (least-squares against h): p {:.2f}, dp/dn {:.2f}; against unknowns (-{} "
      "d log e / d log N): "
      "{:.2f}; solver {}, tolerance {:.0e}; stencil rule {} (growth {:g}), PHS r^{} + degree {}; rows {}{}",
      order, order_grad, Dim, order_dofs, linalg::to_string(study.solver.kind), study.solver.tolerance,
      mac::to_string(study.discretisation.rule), study.discretisation.growth,
      study.discretisation.rbf.exponent, study.discretisation.rbf.degree,
      study.rows == RowProtocol::refine ? "refine the first tree" : "rebuilt per level",
      study.levelset || study.dirichlet_walls ? ""
      : study.discretisation.nullspace == mac::Nullspace::pin
          ? "; singular Neumann system: one unknown pinned near the centre"
          : "; singular Neumann system: zero mean (bordered)"));
  Json series = Json::array();
  series.push(series_entry("L-inf error of p", "adaptive", hs, ep));
  series.push(series_entry("L-inf error of dp/dn", "adaptive", hs, eg));
  if (!uh.empty()) {
    series.push(series_entry("L-inf error of p", "uniform", uh, uep));
    series.push(series_entry("L-inf error of dp/dn", "uniform", uh, ueg));
  }
  // Speed against error: seconds to assemble and solve, against the L-inf error of p reached.
  for (auto [label, e, t] : {std::tuple{"adaptive", &ep, &at}, std::tuple{"uniform", &uep, &ut}}) {
    if (e->empty()) continue;
    series.push(series_entry("time to solution against the L-inf error of p", label, *e, *t,
                             "L-inf error of p", "assembly + solve seconds"));
  }
  result.fields.set("series", std::move(series));
  return result;
}

template <int Dim>
std::vector<PoissonRun> solve_rows(const PoissonStudy<Dim>& study, CaseResult& result,
                                   const std::string& label,
                                   const std::function<void(int, const PoissonRun&)>& on_row) {
  tree::CellGraphOptions<Dim> options;
  options.max_jump = study.max_jump;
  const tree::CellGraph<Dim> first = study.make_tree(study.level_min, options);
  const std::string prefix = label.empty() ? "" : label + " ";
  std::vector<PoissonRun> runs;
  for (int level = study.level_min; level <= study.level_max; ++level) {
    // The first row solves `first` itself: no second build, no copy.
    std::optional<tree::CellGraph<Dim>> later;
    if (level > study.level_min) later.emplace(row_tree<Dim>(study, first, level, options));
    PoissonRun run = solve_poisson<Dim>(later ? *later : first, study);
    if (level == study.level_min && study.max_cells > 0) {
      // Each row splits (or rebuilds at one level finer) about every cell of the one before, and
      // so every unknown: the first row's counts scale to the last's.
      const double growth = std::ldexp(1.0, Dim * (study.level_max - study.level_min));
      const double cells = double(first.n_cells()) * growth, unknowns = double(run.n_unknowns) * growth;
      const double cost = budget_cost<Dim>(cells, unknowns);
      LIQUID_VERIFY(
          cost <= double(study.max_cells),
          "--levels {}:{}: the first row has {} cells and {} unknowns, so the row at base level {} "
          "would have about {:.3g} cells and {:.3g} unknowns, about {:.1f} GB, over the budget of {} "
          "cells ({:.1f} GB at {:g} B a cell, an unknown {:g} cells more; --max-cells N raises it)",
          study.level_min, study.level_max, first.n_cells(), run.n_unknowns, study.level_max, cells, unknowns,
          cost * kCellBytes * 1e-9, study.max_cells, double(study.max_cells) * kCellBytes * 1e-9, kCellBytes,
          kUnknownCells<Dim>);
    }
    result.expect(run.solve.converged(), fmt::format("{}level {}: {}", prefix, level, run.solve.describe()));
    if (!run.solve.converged()) break;
    if (on_row) on_row(level, run);
    runs.push_back(std::move(run));
  }
  return runs;
}

template mac::PoissonProblem<2> poisson_problem<2>(const PoissonStudy<2>&);
template mac::PoissonProblem<3> poisson_problem<3>(const PoissonStudy<3>&);
template double max_error<2>(const tree::CellGraph<2>&, const PoissonStudy<2>&, const mac::PoissonSystem<2>&,
                             const linalg::Vector&);
template double max_error<3>(const tree::CellGraph<3>&, const PoissonStudy<3>&, const mac::PoissonSystem<3>&,
                             const linalg::Vector&);
template std::vector<PoissonRun> solve_rows<2>(const PoissonStudy<2>&, CaseResult&, const std::string&,
                                               const std::function<void(int, const PoissonRun&)>&);
template std::vector<PoissonRun> solve_rows<3>(const PoissonStudy<3>&, CaseResult&, const std::string&,
                                               const std::function<void(int, const PoissonRun&)>&);
template tree::CellGraph<2> row_tree<2>(const PoissonStudy<2>&, const tree::CellGraph<2>&, int,
                                        const tree::CellGraphOptions<2>&);
template tree::CellGraph<3> row_tree<3>(const PoissonStudy<3>&, const tree::CellGraph<3>&, int,
                                        const tree::CellGraphOptions<3>&);
template PoissonRun solve_poisson<2>(const tree::CellGraph<2>&, const PoissonStudy<2>&);
template PoissonRun solve_poisson<3>(const tree::CellGraph<3>&, const PoissonStudy<3>&);
template CaseResult run_poisson_study<2>(PoissonStudy<2>, const CaseOptions&);
template CaseResult run_poisson_study<3>(PoissonStudy<3>, const CaseOptions&);

}  // namespace liquid::verification
