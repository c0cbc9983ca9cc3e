#include "studies/poisson_study.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
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

/// The errors of one solution x: p at the unknowns (mean shift removed for zero-mean systems) and
/// dp/dn at the faces between two unknowns.
template <int Dim>
struct Measured {
  double shift = 0.0, err_p = 0.0, err_grad = 0.0;
  double p_scale = 0.0, grad_scale = 0.0;  ///< max |p| at the unknowns, max |dp/dn| at the faces measured
  tree::CellId worst_cell = tree::no_cell;
  tree::FaceId worst_face = tree::no_face;
  std::vector<double> dpdn;
};

template <int Dim>
Measured<Dim> measure(const tree::CellGraph<Dim>& graph, const PoissonStudy<Dim>& study,
                      const mac::PoissonSystem<Dim>& system, const linalg::Vector& x) {
  Measured<Dim> m;
  const auto& cells = system.layout.cell_of_dof;
  m.shift = mean_shift<Dim>(graph, study, system, x);
  for (std::size_t i = 0; i < cells.size(); ++i) {
    const double exact = study.exact(graph.centre(cells[i]));
    const double e = std::abs(x[i] - m.shift - exact);
    m.p_scale = std::max(m.p_scale, std::abs(exact));
    if (e > m.err_p || m.worst_cell == tree::no_cell) m.err_p = e, m.worst_cell = cells[i];
  }
  m.dpdn = mac::face_normal_derivative<Dim>(graph, system, study.discretisation, x);
  graph.for_each_face([&](tree::FaceId f) {
    if (std::isnan(m.dpdn[f])) return;
    const double exact = study.gradient(graph.face_centre(f))[graph.face(f).axis];
    const double e = std::abs(m.dpdn[f] - exact);
    m.grad_scale = std::max(m.grad_scale, std::abs(exact));
    if (e > m.err_grad || m.worst_face == tree::no_face) m.err_grad = e, m.worst_face = f;
  });
  return m;
}

/// The error a share is taken of: the row's, but never below the round-off level of a double solve
/// (kRoundoffFraction of the solution's scale), where a solver's last digits are all that is left.
template <int Dim>
std::pair<double, double> share_denominators(const Measured<Dim>& m) {
  return {std::max({m.err_p, kRoundoffFraction * m.p_scale, exact_error_level}),
          std::max({m.err_grad, kRoundoffFraction * m.grad_scale, exact_error_level})};
}

/// |x - y|_inf and |dp/dn(x) - dp/dn(y)|_inf over the faces both measure: how far two solves apart.
template <int Dim>
std::pair<double, double> distance(std::size_t n_unknowns, const linalg::Vector& x, const Measured<Dim>& mx,
                                   const linalg::Vector& y, const Measured<Dim>& my) {
  double dp = 0.0, dg = 0.0;
  for (std::size_t i = 0; i < n_unknowns; ++i)
    dp = std::max(dp, std::abs((x[i] - mx.shift) - (y[i] - my.shift)));
  for (std::size_t f = 0; f < mx.dpdn.size(); ++f)
    if (!std::isnan(mx.dpdn[f]) && !std::isnan(my.dpdn[f]))
      dg = std::max(dg, std::abs(mx.dpdn[f] - my.dpdn[f]));
  return {dp, dg};
}

/// Relative residuals below this are not asked of an iterative solver (round-off in |b - Ax|).
constexpr double kToleranceFloor = 1e-15;
constexpr int kMaxControlRounds = 4;

template <int Dim>
PoissonRun solve_poisson(const tree::CellGraph<Dim>& graph, const PoissonStudy<Dim>& study) {
  const mac::PoissonSystem<Dim> system =
      mac::assemble_poisson<Dim>(graph, poisson_problem<Dim>(study), study.discretisation);

  PoissonRun run;
  run.n_cells = graph.n_cells();
  run.n_unknowns = system.n_unknowns();
  run.assembly = system.stats;
  run.assembly_seconds = system.stats.seconds;
  // One solver for every solve of this matrix: the Krylov solvers and the direct one keep their
  // factorisation, so the later solves below cost their iterations only.
  const std::unique_ptr<linalg::LinearSolver> solver = linalg::make_solver(study.solver);
  linalg::Vector x;
  run.solve = solver->solve(system.A, system.b, x);
  run.solve_seconds = run.solve.setup_seconds + run.solve.solve_seconds;
  run.tolerance = study.solver.tolerance;
  if (!run.solve.converged()) return run;
  // A pinned system leaves the discrete incompatibility of f and the wall fluxes at the pinned
  // cell; spread it (z: the response to a uniform source, solved once at the study's tolerance:
  // its algebraic error enters x scaled by the shift, which is of the order of the scheme's error).
  linalg::Vector z;
  if (system.pinned != tree::no_cell && study.spread_pin_source) {
    Stopwatch watch;
    const linalg::SolveStats zs = solver->solve(system.A, mac::uniform_source<Dim>(system), z);
    run.solve_seconds += watch.seconds();
    if (zs.info == linalg::SolveInfo::non_finite || zs.info == linalg::SolveInfo::setup_failed) {
      run.solve = zs;
      return run;
    }
    run.incompatibility = mac::make_compatible<Dim>(system, z, x);
  }
  Measured<Dim> m = measure<Dim>(graph, study, system, x);

  // Algebraic control: continue the solve from x to 100x tighter tolerances. The distance between
  // two solves bounds the algebraic error of the looser one from above (the tighter one's is
  // smaller still): after one round the share is that bound, after more an extrapolation.
  if (study.algebraic != AlgebraicControl::off && study.solver.kind != linalg::SolverKind::direct) {
    // A solver that cannot change its tolerance is replaced by one per round.
    std::unique_ptr<linalg::LinearSolver> fresh;
    double tolerance = study.solver.tolerance;
    double residual = run.solve.relative_residual;
    double distance_before = 0.0;
    for (int round = 0; round < kMaxControlRounds; ++round) {
      tolerance /= 100.0;
      if (tolerance < kToleranceFloor) break;
      linalg::LinearSolver* s = solver.get();
      if (!solver->set_tolerance(tolerance)) {
        linalg::SolveOptions o = study.solver;
        o.tolerance = tolerance;
        fresh = linalg::make_solver(o);
        s = fresh.get();
      }
      linalg::Vector y = x;
      const linalg::SolveStats stats = s->solve(system.A, system.b, y);
      run.control_seconds += stats.setup_seconds + stats.solve_seconds;
      run.control_iterations += stats.iterations;
      if (stats.info == linalg::SolveInfo::non_finite || stats.info == linalg::SolveInfo::setup_failed) break;
      if (z.size() > 0) mac::make_compatible<Dim>(system, z, y);
      Measured<Dim> my = measure<Dim>(graph, study, system, y);
      const auto [dp, dg] = distance<Dim>(system.layout.cell_of_dof.size(), x, m, y, my);
      const auto [ep, eg] = share_denominators<Dim>(study.algebraic == AlgebraicControl::check ? m : my);
      const double d = std::max(dp / ep, dg / eg);
      // After the first round, d bounds the error of the solve before; the one kept (100x
      // tighter) is estimated by how fast the distances fall: d * (d / d_before), at most d.
      run.algebraic_share = round == 0 ? d : d * std::min(1.0, d / std::max(distance_before, 1e-300));
      // Distances that fall by less than 10x for a 100x tighter solve (or a solve that stalls) are the
      // round-off of the solve, not an iteration error a tighter tolerance would remove.
      run.solve_at_roundoff = (round > 0 && d > 0.1 * distance_before) || !stats.converged();
      distance_before = d;
      if (study.algebraic == AlgebraicControl::check) break;
      // A solve that stalls short of the tighter tolerance still improves x when its residual fell.
      if (stats.converged() || stats.relative_residual < residual) {
        x = std::move(y);
        m = std::move(my);
        residual = stats.relative_residual;
        run.tolerance = stats.converged() ? tolerance : stats.relative_residual;
      }
      if (!stats.converged() || run.algebraic_share <= study.algebraic_bound) break;
    }
  }

  const auto& cells = system.layout.cell_of_dof;
  run.err_p = m.err_p;
  run.err_grad = m.err_grad;
  run.p_scale = m.p_scale;
  run.grad_scale = m.grad_scale;
  run.worst_p = describe_cell(graph, study, m.worst_cell);
  std::vector<std::pair<long, double>> by_level;
  for (std::size_t i = 0; i < cells.size(); ++i) {
    const double exact = study.exact(graph.centre(cells[i]));
    const int l = graph.level(cells[i]);
    if (static_cast<int>(by_level.size()) <= l) by_level.resize(l + 1, {0, 0.0});
    by_level[l].first += 1;
    by_level[l].second = std::max(by_level[l].second, std::abs(x[i] - m.shift - exact));
  }
  for (int l = 0; l < static_cast<int>(by_level.size()); ++l)
    if (by_level[l].first > 0) run.err_by_level.emplace_back(l, by_level[l].first, by_level[l].second);

  graph.for_each_face([&](tree::FaceId f) {
    if (std::isnan(m.dpdn[f])) return;
    const auto& g = graph.face(f);
    if (!g.is_boundary())
      run.max_level_jump = std::max(run.max_level_jump, std::abs(g.side_level[0] - g.side_level[1]));
  });
  if (m.worst_face != tree::no_face) {
    const auto& g = graph.face(m.worst_face);
    run.worst_grad =
        fmt::format("face {} at {}, levels {}|{}, {}", m.worst_face,
                    format_point<Dim>(graph.face_centre(m.worst_face)), g.side_level[0], g.side_level[1],
                    !g.hanging() && g.side_level[0] == g.side_level[1] ? "two-point FD" : "RBF-FD");
  }
  run.h = graph.cell_size(cells.front()).maxCoeff();
  graph.for_each_cell([&](tree::CellId c) { run.h = std::min(run.h, graph.cell_size(c).maxCoeff()); });
  return run;
}

std::string OrderDiagnosis::line() const {
  return fmt::format("diagnosis: p {}: {}; dp/dn {}: {}", p_kind, p, grad_kind, grad);
}

namespace {

std::string join_orders(const std::vector<double>& steps) {
  std::string s;
  for (std::size_t k = 0; k < steps.size(); ++k) s += fmt::format("{}{:.2f}", k ? " -> " : "", steps[k]);
  return s;
}

/// One quantity's classification; `where` says where the finest row's error sits.
std::pair<std::string, std::string> classify(const std::vector<int>& levels, const std::vector<double>& h,
                                             const std::vector<double>& e, const std::vector<double>& share,
                                             const std::vector<bool>& roundoff, double scale, double floor,
                                             double bound, const std::string& where) {
  const std::size_t n = e.size();
  if (n == 0) return {"too-few-rows", "no row converged"};
  if (*std::max_element(e.begin(), e.end()) < exact_error_level)
    return {"exact", fmt::format("every error is below {:.0e}: the scheme reproduces this solution",
                                 exact_error_level)};
  for (std::size_t k = 0; k < n; ++k)
    if (!std::isnan(share[k]) && share[k] > bound && roundoff[k])
      return {"round-off",
              fmt::format("at level {} the solve's last digits move the row's error by up to {:.2g} "
                          "and tighter solves no longer reduce it: the errors ({:.2e} at the finest "
                          "row, {:.1e} of the solution's scale) are at the round-off floor of this "
                          "system; drop the finest rows or take a less flat solution",
                          levels[k], share[k], e.back(), e.back() / std::max(scale, 1e-300))};
  for (std::size_t k = 0; k < n; ++k)
    if (!std::isnan(share[k]) && share[k] > bound)
      return {"algebraic",
              fmt::format("at level {} the solver's error is up to {:.2g} of the row's error (bound "
                          "{:.2g}): the errors are partly the solver's; use --solver direct or a "
                          "smaller --tolerance",
                          levels[k], share[k], bound)};
  if (n == 1) return {"too-few-rows", "one row: no order"};
  std::vector<double> steps;
  for (std::size_t k = 1; k < n; ++k) steps.push_back(pair_order(h[k - 1], e[k - 1], h[k], e[k]));
  // The order the study has reached: fitted over its three finest rows, so that coarse rows still
  // far from the asymptotic range do not hide a study that has arrived (the fit over every row is
  // shown too).
  const std::size_t tail = std::min<std::size_t>(n, 3);
  const double fitted = fit_order(std::span(h).last(tail), std::span(e).last(tail)), last = steps.back();
  const std::string orders =
      n > tail ? fmt::format("fitted {:.2f} over the finest {} rows ({:.2f} over all), step orders {}",
                             fitted, tail, fit_order(h, e), join_orders(steps))
               : fmt::format("fitted {:.2f}, step orders {}", fitted, join_orders(steps));
  if (e.back() < kRoundoffFraction * scale && last < floor)
    return {"round-off",
            fmt::format("{}; the finest error {:.2e} is below {:.0e} of the solution's scale {:.3g}: "
                        "the rows reach the round-off floor, drop the finest",
                        orders, e.back(), kRoundoffFraction, scale)};
  if (fitted >= floor && last >= floor - kSettledSpread) {
    if (fitted > kSchemeOrder + 0.5)
      return {"above-order",
              fmt::format("{}: more than 0.5 above the scheme's order {:g}, so the rows are not "
                          "yet asymptotic; add a finer row",
                          orders, kSchemeOrder)};
    return {"converges", fmt::format("{} (floor {:.2f})", orders, floor)};
  }
  if (steps.size() == 1)
    return {"too-few-rows",
            fmt::format("{}: one step order below {:.2f} cannot tell a pre-asymptotic study from a "
                        "loss of order; add a row",
                        orders, floor)};
  // A loss of order is two settled step orders, both below the floor; anything else may still turn.
  const double before = steps[steps.size() - 2], change = last - before;
  if (std::abs(change) > kSettledSpread || before >= floor || last >= floor)
    return {
        "pre-asymptotic",
        fmt::format(
            "{}: the last two step orders {}, so the rows are not yet asymptotic; add a finer row "
            "(--levels {}:{})",
            orders,
            std::abs(change) > kSettledSpread
                ? fmt::format("differ by {:.2f} (more than {:g})", std::abs(change), kSettledSpread)
                : fmt::format("{:.2f} and {:.2f} are not both below the floor {:.2f}", before, last, floor),
            levels.front(), levels.back() + 1)};
  if (steps.size() < 3)
    return {"too-few-rows",
            fmt::format("{}: two step orders below {:.2f} that agree are not yet a loss of order; "
                        "add a finer row (--levels {}:{}) to tell it from a pre-asymptotic study",
                        orders, floor, levels.front(), levels.back() + 1)};
  return {
      "loss-of-order",
      fmt::format("{}: the last two step orders agree within {:g} at about {:.2f}, below {:.2f}: a loss of "
                  "order of the discretisation; {}",
                  orders, kSettledSpread, last, floor, where)};
}

}  // namespace

OrderDiagnosis diagnose_orders(const std::vector<int>& levels, const std::vector<PoissonRun>& runs,
                               double floor_p, double floor_grad, double bound) {
  std::vector<double> h, ep, eg, share;
  std::vector<bool> roundoff;
  double sp = 0.0, sg = 0.0;
  for (const PoissonRun& r : runs) {
    h.push_back(r.h), ep.push_back(r.err_p), eg.push_back(r.err_grad), share.push_back(r.algebraic_share);
    roundoff.push_back(r.solve_at_roundoff);
    sp = std::max(sp, r.p_scale), sg = std::max(sg, r.grad_scale);
  }
  std::string where_p, where_g;
  if (!runs.empty()) {
    const PoissonRun& last = runs.back();
    int worst_level = -1;
    double worst = -1.0;
    for (const auto& [l, count, e] : last.err_by_level)
      if (e > worst) worst = e, worst_level = l;
    where_p = fmt::format(
        "in the finest row the error of p peaks on cell level {} (the table of levels shows each), "
        "worst at {}",
        worst_level, last.worst_p);
    where_g = fmt::format("in the finest row the worst dp/dn is at {}", last.worst_grad);
  }
  OrderDiagnosis d;
  std::tie(d.p_kind, d.p) = classify(levels, h, ep, share, roundoff, sp, floor_p, bound, where_p);
  std::tie(d.grad_kind, d.grad) = classify(levels, h, eg, share, roundoff, sg, floor_grad, bound, where_g);
  return d;
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
  if (options.gradient_cap) study.discretisation.gradient_ring_cap = *options.gradient_cap;
  if (options.rows) study.rows = *options.rows;
  if (options.nullspace) {
    LIQUID_VERIFY(!study.levelset && !study.dirichlet_walls,
                  "--nullspace applies to pure Neumann problems; this study has Dirichlet values{}, so "
                  "its system is not singular",
                  study.levelset ? " on a level set" : " on its walls");
    study.discretisation.nullspace =
        *options.nullspace == NullspaceChoice::zero_mean ? mac::Nullspace::zero_mean : mac::Nullspace::pin;
    study.spread_pin_source = *options.nullspace == NullspaceChoice::pin;
  }
  if (options.tolerance) study.solver.tolerance = *options.tolerance;
  if (options.algebraic) study.algebraic = *options.algebraic;
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
                  "order dp/dn", "alg share", "assembly s", "solve s", "iterations", "check s"});
  Table levels("where the error lives: L-inf error of p on the unknowns of each cell level",
               {"row", "cell level", "unknowns", "err p", "share of row err"});
  Table uniform("uniform grid at the same finest h",
                {"level", "h", "unknowns", "err p", "err dp/dn", "alg share", "assembly s", "solve s",
                 "iterations", "check s"});
  std::vector<double> hs, ep, eg, nd, uh, uep, ueg, at, ut;  // at/ut: time to solution
  std::vector<int> row_levels;
  std::vector<PoissonRun> rows;
  // The share as a table cell: "-" where it was not measured.
  const auto share_cell = [](const PoissonRun& r) {
    return std::isnan(r.algebraic_share) ? Table::Cell{} : Table::Cell(r.algebraic_share);
  };
  const auto check_share = [&](const std::string& row, const PoissonRun& r) {
    if (std::isnan(r.algebraic_share) || r.algebraic_share <= study.algebraic_bound) return;
    if (r.solve_at_roundoff) {
      result.warnings.push_back(
          fmt::format("{}: the solve's round-off moves the row's error by up to {:.2g} (tighter solves no "
                      "longer reduce it): "
                      "its error {:.2e} is at the round-off floor of this system",
                      row, r.algebraic_share, r.err_p));
      return;
    }
    const std::string what = fmt::format(
        "{}: the algebraic error is up to {:.2g} of the row's error (bound {:.2g}) at relative residual "
        "{:.0e}{}: "
        "its errors are partly the solver's (--solver direct, or a smaller --tolerance)",
        row, r.algebraic_share, study.algebraic_bound, r.tolerance,
        study.algebraic == AlgebraicControl::check ? " (--algebraic check reports the first solve's errors)"
                                                   : ", the tightest this solver reached");
    result.warnings.push_back(what);
    if (study.asserted) result.expect(false, what);
  };
  solve_rows<Dim>(study, result, "", [&](int level, const PoissonRun& run) {
    row_levels.push_back(level);
    rows.push_back(run);
    check_share(fmt::format("level {}", level), run);
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
                      run.err_p, op, run.err_grad, og, share_cell(run), run.assembly_seconds,
                      run.solve_seconds, long(run.solve.iterations), run.control_seconds});
    result.notes.push_back(
        fmt::format("level {}: worst p at {}; worst dp/dn at {}; weight cache: {} hits for {} RBF-FD rows",
                    level, run.worst_p, run.worst_grad, run.assembly.n_cache_hits, run.assembly.n_rbf_rows));
    result.expect(std::isfinite(run.err_p) && std::isfinite(run.err_grad),
                  fmt::format("level {}: NaN error", level));
    for (const auto& [l, n, e] : run.err_by_level) {
      Table::Cell share;  // "-" for an exact row
      if (run.err_p > 0.0) share = e / run.err_p;
      levels.add_row({long(level), long(l), n, e, share});
    }
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
    check_share(fmt::format("uniform level {}", fine), u);
    uh.push_back(u.h), uep.push_back(u.err_p), ueg.push_back(u.err_grad);
    ut.push_back(u.assembly_seconds + u.solve_seconds);
    uniform.add_row({long(fine), u.h, u.n_unknowns, u.err_p, u.err_grad, share_cell(u), u.assembly_seconds,
                     u.solve_seconds, long(u.solve.iterations), u.control_seconds});
  });
  result.tables.push_back(std::move(adaptive));
  result.tables.push_back(std::move(uniform));
  result.tables.push_back(std::move(levels));
  const double order = fit_order(hs, ep), order_grad = fit_order(hs, eg);
  // Against unknowns: err ~ N^(-q/Dim), so q = -Dim * slope of log err against log N.
  const double order_dofs = -Dim * fit_order(nd, ep);
  result.gate.push_back({"order p", GateFigure::Kind::order, order});
  result.gate.push_back({"order dp/dn", GateFigure::Kind::order, order_grad});
  result.fields.set("order", order);
  result.fields.set("order_grad", order_grad);
  result.fields.set("order_dofs", order_dofs);
  {
    // The scheme's order is 2 for both; a study's own floors judge it where they are set.
    const double fp = std::isfinite(study.order_floor) ? study.order_floor : kSchemeOrderFloor,
                 fg = std::isfinite(study.order_grad_floor) ? study.order_grad_floor : kSchemeGradOrderFloor;
    const OrderDiagnosis d = diagnose_orders(row_levels, rows, fp, fg, study.algebraic_bound);
    const auto fine = [](const std::string& kind) { return kind == "converges" || kind == "exact"; };
    if (fine(d.p_kind) && fine(d.grad_kind))
      result.notes.insert(result.notes.begin(), d.line());
    else
      result.warnings.insert(result.warnings.begin(), d.line());
    Json dj = Json::object();
    dj.set("p", d.p_kind);
    dj.set("dp/dn", d.grad_kind);
    dj.set("p_reason", d.p);
    dj.set("dp/dn_reason", d.grad);
    result.fields.set("diagnosis", std::move(dj));
    double worst_share = 0.0;
    for (const PoissonRun& r : rows)
      if (!std::isnan(r.algebraic_share)) worst_share = std::max(worst_share, r.algebraic_share);
    result.fields.set("algebraic_share", worst_share);
    result.fields.set("algebraic_control", to_string(study.algebraic));
  }
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
      "{:.2f}; solver {}, tolerance {:.0e} (algebraic control: {}, bound {:g}); stencil rule {} (growth "
      "{:g}), PHS r^{} + degree {}; rows {}{}",
      order, order_grad, Dim, order_dofs, linalg::to_string(study.solver.kind), study.solver.tolerance,
      to_string(study.algebraic), study.algebraic_bound, mac::to_string(study.discretisation.rule),
      study.discretisation.growth, study.discretisation.rbf.exponent, study.discretisation.rbf.degree,
      study.rows == RowProtocol::refine ? "refine the first tree" : "rebuilt per level",
      study.levelset || study.dirichlet_walls ? ""
      : study.discretisation.nullspace == mac::Nullspace::zero_mean
          ? "; singular Neumann system: zero mean (bordered)"
      : study.spread_pin_source
          ? "; singular Neumann system: one unknown pinned near the centre, the discrete incompatibility "
            "spread as a uniform source"
          : "; singular Neumann system: one unknown pinned near the centre, the incompatibility left there"));
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
    std::string why;
    if (!run.solve.converged() && run.assembly.n_rbf_rows > 0 && linalg::needs_symmetric(study.solver.kind))
      why = fmt::format(
          " (conjugate gradients need a symmetric matrix; this row's {} RBF-FD rows are not "
          "symmetric: use a BiCGSTAB or GMRES solver)",
          run.assembly.n_rbf_rows);
    result.expect(run.solve.converged(),
                  fmt::format("{}level {}: {}{}", prefix, level, run.solve.describe(), why));
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
