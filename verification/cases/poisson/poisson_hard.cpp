// Case poisson-hard: numerical stability of the Poisson discretisation on hard trees and stencils.
//
// Problems (2D): the Neumann problem of poisson-neumann-2d (p = cos x cos y - 1 on [0, pi]^2,
// pinned near the centre) and a level-set Dirichlet problem (p = exp(x) sin(y) + 1 inside a circle
// of radius R around (pi/2, pi/2), p = exact on the circle), on
//   - seeded random non-graded trees with level jumps up to 1, 3 and 4 (levels L-1 .. L+3), against
//     the uniform grid of their coarsest level L-1, which every cell refines. Their error against the
//     graded tree (jump 1) of the same seed is reported, not checked: grading refines about twice the
//     cells and leaves a quarter of the coarse ones, and the pinned Neumann error is a smooth field set
//     by those coarse cells, the same at every cell level of the tree;
//   - a narrow band where the finest cells touch cells four levels coarser;
//   - a circle passing within 1e-6 h of a cell centre, against one passing 0.37 h from it;
//   - a flat domain [0, pi] x [0, pi/64] whose cells are 64 times wider than tall, so every
//     RBF-FD stencil is nearly collinear (p = cos x - 1 there), against the uniform grid of the
//     tree's coarsest level.
// Expected: nothing throws, no NaN, every solve converges, and the L-inf error of p stays within a
// factor 4 of its reference row. The table reports the worst estimated condition number of the
// scaled RBF-FD systems and what the engine did: rows whose stencil could not carry the requested
// degree (lowered), rows that needed a node dropped (retried), centres within 1e-3 h of the interface.

#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "liquid/core/error.hpp"
#include "liquid/levelset/levelset.hpp"
#include "liquid/tree/builders.hpp"
#include "studies/poisson_study.hpp"
#include "support/manufactured.hpp"

namespace liquid::verification {
namespace {

constexpr double kFactor = 4.0;
constexpr double pi = std::numbers::pi;

PoissonStudy<2> neumann(const Box<2>& domain) {
  PoissonStudy<2> s;
  s.domain = domain;
  s.use(support::cosine_product<2>());
  return s;
}

// p = cos x - 1: no y dependence, so Neumann on the walls of a flat domain too.
PoissonStudy<2> neumann_x(const Box<2>& domain) {
  PoissonStudy<2> s;
  s.domain = domain;
  s.use(support::cosine_x<2>());
  return s;
}

PoissonStudy<2> dirichlet_circle(double radius) {
  PoissonStudy<2> s;
  s.domain = Box<2>{Vec<2>::Zero(), Vec<2>::Constant(pi)};
  s.use(support::exp_sin());
  s.levelset = levelset::sphere<2>(Vec<2>::Constant(0.5 * pi), radius);
  return s;
}

struct Scenario {
  std::string name;
  PoissonStudy<2> study;
  tree::CellGraph<2> graph;
  std::string reference;    // name of the reference scenario ("" for a reference itself)
  std::string graded = {};  // a random tree's graded twin (same seed, jump 1): its ratio is reported
};

CaseResult run(const CaseOptions& options) {
  // The scenarios fix their own jumps, solver and scheme (only --levels A:B sets the base level A).
  const int L = options.levels ? options.levels->first : (options.full ? 6 : 5);
  LIQUID_VERIFY(L >= 2 && L <= 12,
                "poisson-hard: --levels A:B sets the base level A, which must be in 2..12 (got {})", L);
  const Box<2> square{Vec<2>::Zero(), Vec<2>::Constant(pi)};
  std::vector<Scenario> scenarios;
  {
    // Every cell of the random trees refines the uniform grid of their coarsest level, L - 1.
    tree::CellGraphOptions<2> o;
    scenarios.push_back(
        {fmt::format("uniform, level {}", L - 1), neumann(square), tree::uniform<2>(square, L - 1, o), ""});
  }
  for (std::uint64_t seed : {11u, 12u}) {
    for (int jump : {1, 3, 4}) {
      tree::CellGraphOptions<2> o;
      o.max_jump = jump;
      scenarios.push_back({fmt::format("random seed {} jump {}", seed, jump), neumann(square),
                           tree::random<2>(square, seed, L - 1, L + 3, 0.35, o),
                           fmt::format("uniform, level {}", L - 1),
                           jump == 1 ? "" : fmt::format("random seed {} jump 1", seed)});
    }
  }
  {
    const auto circle = levelset::sphere<2>(Vec<2>::Constant(0.5 * pi), 0.9);
    tree::CellGraphOptions<2> graded, jump4;
    graded.max_jump = 1;
    jump4.max_jump = 4;
    scenarios.push_back({"band, graded", neumann(square),
                         tree::narrow_band<2>(square, circle, L - 1, L + 3, 2.0, graded), ""});
    scenarios.push_back({"band, fine next to 4 levels coarser", neumann(square),
                         tree::narrow_band<2>(square, circle, L - 1, L + 3, 0.5, jump4), "band, graded"});
  }
  {
    // Put the circle 1e-6 h (and, for reference, 0.37 h) beyond a cell centre near radius 0.9.
    tree::CellGraphOptions<2> o;
    const auto base = dirichlet_circle(0.9);
    tree::CellGraph<2> g = tree::narrow_band<2>(square, base.levelset, L, L + 2, 2.0, o);
    const tree::CellId c = g.locate(Vec<2>(0.5 * pi + 0.9, 0.5 * pi + 0.013));
    const double h = g.cell_size(c).maxCoeff();
    const double r = (g.centre(c) - Vec<2>::Constant(0.5 * pi)).norm();
    scenarios.push_back({"circle 0.37 h from a centre", dirichlet_circle(r + 0.37 * h), g, ""});
    scenarios.push_back(
        {"circle 1e-6 h from a centre", dirichlet_circle(r + 1e-6 * h), g, "circle 0.37 h from a centre"});
  }
  {
    const Box<2> flat{Vec<2>::Zero(), Vec<2>(pi, pi / 64)};
    const auto line = levelset::sphere<2>(Vec<2>(0.5 * pi, 0.0), 0.9);
    tree::CellGraphOptions<2> o;
    scenarios.push_back({"flat cells, uniform", neumann_x(flat), tree::uniform<2>(flat, L, o), ""});
    scenarios.push_back({"flat cells, nearly collinear stencils", neumann_x(flat),
                         tree::narrow_band<2>(flat, line, L, L + 2, 2.0, o), "flat cells, uniform"});
  }

  CaseResult result;
  Table table("hard trees and stencils (2D)",
              {"scenario", "unknowns", "jump", "rbf rows", "lowered", "retried", "on interface", "worst cond",
               "iterations", "err p", "reference err", "ratio", "check", "vs graded"});
  std::vector<std::pair<std::string, double>> errors;
  double worst_condition = 0.0;
  for (auto& sc : scenarios) {
    PoissonRun run;
    try {
      run = solve_poisson<2>(sc.graph, sc.study);
    } catch (const std::exception& e) {
      result.expect(false, fmt::format("{}: threw: {}", sc.name, e.what()));
      continue;
    }
    const bool converged = run.solve.converged() && std::isfinite(run.err_p) && std::isfinite(run.err_grad);
    result.expect(converged, fmt::format("{}: {}", sc.name, run.solve.describe()));
    double reference = std::numeric_limits<double>::quiet_NaN();
    for (const auto& [name, e] : errors)
      if (name == sc.reference) reference = e;
    const double ratio = run.err_p / reference;
    const bool ok = converged && (sc.reference.empty() || ratio <= kFactor);
    if (!sc.reference.empty())
      result.expect(ratio <= kFactor,
                    fmt::format("{}: error {:.3e} is {:.1f} times its reference's (worst p {})", sc.name,
                                run.err_p, ratio, run.worst_p));
    double graded = std::numeric_limits<double>::quiet_NaN();
    for (const auto& [name, e] : errors)
      if (name == sc.graded) graded = run.err_p / e;
    errors.emplace_back(sc.name, run.err_p);
    worst_condition = std::max(worst_condition, run.assembly.worst_condition);
    result.gate.push_back({sc.name + " err p", GateFigure::Kind::error, run.err_p});
    table.add_row({sc.name, run.n_unknowns, long(run.max_level_jump), run.assembly.n_rbf_rows,
                   run.assembly.n_degree_reduced, run.assembly.n_retried, run.assembly.n_on_interface,
                   run.assembly.worst_condition, long(run.solve.iterations), run.err_p,
                   sc.reference.empty() ? Table::Cell{} : Table::Cell(reference),
                   sc.reference.empty() ? Table::Cell{} : Table::Cell(ratio), std::string(ok ? "ok" : "FAIL"),
                   sc.graded.empty() ? Table::Cell{} : Table::Cell(graded)});
  }
  result.tables.push_back(std::move(table));
  result.fields.set("worst_condition", worst_condition);
  result.notes.push_back(
      fmt::format("worst estimated condition number of a scaled RBF-FD system: {:.2e}; lowered = rows whose "
                  "stencil could not carry the requested degree ({}), so the engine used a lower one; "
                  "retried = rows whose system was refused (coincident or singular) and solved again "
                  "without the offending node; expected error factor at most {}",
                  worst_condition, mac::PoissonOptions{}.rbf.degree, kFactor));
  return result;
}

}  // namespace

LIQUID_VERIFICATION_CASE(
    {"poisson-hard",
     "stability: jumps 3-4, random trees, interface 1e-6 h from a centre, near-collinear stencils",
     true,
     run,
     {Option::levels}});

}  // namespace liquid::verification
