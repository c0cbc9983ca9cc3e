// Case ppe-solvers: every PPE solver on the paper's Poisson matrices, adaptive and uniform.
//
// Problem. The matrices of the paper's four Poisson studies (poisson-neumann-2d/3d: Neumann,
// p = prod cos x_k - 1 on [0, pi]^d; poisson-dirichlet-levelset-2d/3d: p = 0 on a level set),
// each row's non-graded tree as those cases build it, and for the Neumann studies the uniform grid
// at the row's finest level (the regular solver's matrix: 5/7-point FD). Rows (base levels, quick /
// full): Neumann 2D 5:7 / 5:8, 3D 3:4 / 3:5; Dirichlet 2D 7:9 / 7:10, 3D 4:5 / 4:6; uniform rows
// up to 70k (quick) / 300k (full) unknowns.
// Solvers: BiCGSTAB with Jacobi, ILUT and BoomerAMG, and GMRES+AMG on the adaptive matrices; CG
// with Jacobi, IC and AMG, and BiCGSTAB+AMG on the uniform ones; the direct solver as the
// reference up to 30k unknowns. Tolerances 1e-6 (the paper's) and 1e-10; in the quick tier the
// Jacobi and IC solvers run at 1e-6 only.
// On the 3D adaptive Neumann matrices BiCGSTAB+AMG also runs with untruncated interpolation
// (PMax 0, the rows "bicgstab-amg pmax0"): see "Flat iterations" below.
// Measured per solve: iterations, setup and solve seconds, SpMV-equivalents (setup + solve over the
// time of one product with that matrix, the product timed on as many threads as the solver uses:
// one for hypre, which Debian builds without OpenMP, all of Eigen's for the others), the true
// relative residual, the L-inf error of p, and assembly + setup + solve seconds against that error
// at 1e-10 (the report's speed-against-error plots, one curve per tree and solver).
// Expected: every AMG solve converges; BiCGSTAB+AMG's iterations are flat: the finest row within
// 1.3 times the coarsest row's, per study, tree and tolerance; at 1e-10 its error equals the direct
// solver's to 3 significant digits.
// Flat iterations on the 3D adaptive Neumann matrices: with the default truncation (PMax 4)
// BiCGSTAB+AMG's iterations grow with the level, from interpolation truncation on the pinned
// singular system; untruncated interpolation is flat but slower. The default stays PMax 4, warned
// about when it grows; flatness is asserted on the pmax0 rows. In the full tier even those grow at
// 1e-10, so the full tier fails here. Figures and what was tried: docs/findings/amg.md.
// Printed beside the paper's comparison (Sec. 6): adaptive BiCGSTAB+Jacobi against regular
// PCG+Jacobi (paper: 2.6x faster), adaptive BiCGSTAB+ILU against regular PCG+IC (2.5x faster, 3x
// fewer iterations), and the same with AMG on both sides.

#include <algorithm>
#include <cmath>
#include <map>

#include <fmt/format.h>

#include "common/case.hpp"
#include "liquid/core/timer.hpp"
#include "liquid/tree/builders.hpp"
#include "studies/paper_studies.hpp"
#include "studies/poisson_study.hpp"

namespace liquid::verification {
namespace {

using linalg::SolverKind;

struct Job {
  SolverKind kind;
  double tolerance;
  int pmax = -1;  ///< BoomerAMG's interpolation entries per row; -1: AmgOptions' default
};

std::string solver_label(SolverKind kind, int pmax) {
  return linalg::to_string(kind) + (pmax >= 0 ? fmt::format(" pmax{}", pmax) : "");
}

/// One solve's figures, kept for the flatness check and the paper's comparison.
struct Solved {
  linalg::SolveStats stats;
  double error = 0.0, spmv_equivalents = 0.0, assembly_seconds = 0.0;
};

/// Seconds of one product A x on `threads` threads: the median of 5 timings of 10 products.
double spmv_seconds(const linalg::SparseMatrix& A, int threads) {
  const int before = Eigen::nbThreads();
  Eigen::setNbThreads(threads);
  const linalg::Vector x = linalg::Vector::Ones(A.cols());
  linalg::Vector y(A.rows());
  std::vector<double> t;
  for (int k = 0; k < 5; ++k) {
    Stopwatch w;
    for (int j = 0; j < 10; ++j) y.noalias() = A * x;
    t.push_back(w.seconds() / 10.0);
  }
  Eigen::setNbThreads(before);
  std::nth_element(t.begin(), t.begin() + 2, t.end());
  return std::max(t[2], 1e-9);
}

std::vector<Job> jobs(int dim, bool uniform, bool neumann, bool full, long unknowns) {
  std::vector<Job> out;
  const auto both = [&](SolverKind k) {
    out.push_back({k, 1e-6});
    out.push_back({k, 1e-10});
  };
  const auto slow = [&](SolverKind k) {
    out.push_back({k, 1e-6});
    if (full) out.push_back({k, 1e-10});
  };
  if (uniform) {
    slow(SolverKind::cg_jacobi);
    slow(SolverKind::cg_ic);
    both(SolverKind::cg_amg);
    both(SolverKind::bicgstab_amg);
  } else {
    slow(SolverKind::bicgstab_jacobi);
    if (dim == 2)
      both(SolverKind::bicgstab_ilut);
    else
      slow(SolverKind::bicgstab_ilut);  // its 3D factorisation takes seconds
    both(SolverKind::bicgstab_amg);
    both(SolverKind::gmres_amg);
    if (dim == 3 && neumann) {
      out.push_back({SolverKind::bicgstab_amg, 1e-6, 0});
      out.push_back({SolverKind::bicgstab_amg, 1e-10, 0});
    }
  }
  if (unknowns <= 30000 && (dim == 2 || full)) out.push_back({SolverKind::direct, 1e-10});
  return out;
}

struct Key {
  std::string study, tree;
  SolverKind kind;
  double tolerance;
  int pmax = -1;
  auto operator<=>(const Key&) const = default;
};
using Results = std::map<Key, std::vector<std::pair<int, Solved>>>;  // by row level

template <int Dim>
void solve_tree(const std::string& name, const PoissonStudy<Dim>& study, const tree::CellGraph<Dim>& graph,
                const std::string& tree, int level, bool full, Table& table, Results& results) {
  Stopwatch assembly;
  const mac::PoissonSystem<Dim> system =
      mac::assemble_poisson<Dim>(graph, poisson_problem<Dim>(study), study.discretisation);
  const double t_assembly = assembly.seconds();
  const double t_spmv_one = spmv_seconds(system.A, 1),
               t_spmv_all = spmv_seconds(system.A, Eigen::nbThreads());
  for (const Job& job : jobs(Dim, tree == "uniform", !study.levelset, full, system.n_unknowns())) {
    linalg::Vector x;
    linalg::SolveOptions o = study.solver;
    o.kind = job.kind;
    o.tolerance = job.tolerance;
    if (job.pmax >= 0) o.amg.max_interpolation_entries = job.pmax;
    Solved s;
    s.stats = linalg::solve(system.A, system.b, x, o);
    s.spmv_equivalents = (s.stats.setup_seconds + s.stats.solve_seconds) /
                         (linalg::uses_amg(job.kind) ? t_spmv_one : t_spmv_all);
    s.assembly_seconds = t_assembly;
    if (s.stats.converged()) s.error = max_error<Dim>(graph, study, system, x);
    table.add_row({name, tree, long(level), system.n_unknowns(), solver_label(job.kind, job.pmax),
                   job.tolerance, long(s.stats.iterations), s.stats.setup_seconds, s.stats.solve_seconds,
                   s.spmv_equivalents, s.stats.relative_residual,
                   s.stats.converged() ? Table::Cell(s.error) : Table::Cell(std::string("-")),
                   std::string(linalg::to_string(s.stats.info))});
    results[{name, tree, job.kind, job.tolerance, job.pmax}].emplace_back(level, s);
  }
}

template <int Dim>
void run_study(const std::string& name, PoissonStudy<Dim> study, int level_min, int level_max, bool uniform,
               bool full, Table& table, Results& results) {
  study.level_min = level_min;
  tree::CellGraphOptions<Dim> options;
  options.max_jump = study.max_jump;
  const tree::CellGraph<Dim> first = study.make_tree(level_min, options);
  // Full tier: the 2D uniform grid of 1M cells (the finest Neumann row's h), 3D up to 300k.
  const long uniform_limit = full ? (Dim == 2 ? 1100000 : 300000) : 70000;
  for (int level = level_min; level <= level_max; ++level) {
    const tree::CellGraph<Dim> graph =
        level == level_min ? first : row_tree<Dim>(study, first, level, options);
    solve_tree<Dim>(name, study, graph, "adaptive", level, full, table, results);
    const int fine = graph.deepest_level();
    if (uniform && std::ldexp(1.0, Dim * fine) <= double(uniform_limit)) {
      tree::CellGraphOptions<Dim> flat_options;
      flat_options.max_jump = study.max_jump;
      solve_tree<Dim>(name, study, tree::uniform<Dim>(study.domain, fine, flat_options), "uniform", level,
                      full, table, results);
    }
  }
}

CaseResult run(const CaseOptions& options) {
  CaseResult result;
  const bool full = options.full;
  Table table("every solver on every matrix",
              {"study", "tree", "level", "unknowns", "solver", "tolerance", "iterations", "setup s",
               "solve s", "SpMV-equiv", "residual", "L-inf err p", "result"});
  Results results;
  run_study<2>("neumann-2d", neumann_study<2>(full), 5, full ? 8 : 7, true, full, table, results);
  run_study<3>("neumann-3d", neumann_study<3>(full), 3, full ? 5 : 4, true, full, table, results);
  run_study<2>("dirichlet-2d", dirichlet_study<2>(full), 7, full ? 10 : 9, false, full, table, results);
  run_study<3>("dirichlet-3d", dirichlet_study<3>(full), 4, full ? 6 : 5, false, full, table, results);

  // Flat iterations and the direct solver's errors.
  // Beside the counts, the rate: the relative residual reached to the power 1 / iterations, and the
  // iterations that rate needs to reach the tolerance, log(tolerance) / log(rate). Counts of 3 or 4
  // round the rate's 2.9 and 3.2 to a ratio of 1.33; the rates say whether a solver really slows.
  Table flat("AMG iterations, coarsest to finest row",
             {"study", "tree", "solver", "tolerance", "iterations", "finest / coarsest", "rate per iteration",
              "iterations by rate", "finest / coarsest by rate"});
  for (const auto& [key, rows] : results) {
    if (!linalg::uses_amg(key.kind)) continue;
    std::string its, rates, by_rate;
    std::vector<double> needed;
    bool all = true;
    for (const auto& [level, s] : rows) {
      its += fmt::format("{}{}", its.empty() ? "" : " ", s.stats.iterations);
      const double r = s.stats.relative_residual;
      if (s.stats.converged() && s.stats.iterations > 0 && r > 0.0) {
        const double rate = std::pow(r, 1.0 / s.stats.iterations);
        needed.push_back(std::log(key.tolerance) / std::log(rate));
        rates += fmt::format("{}{:.3f}", rates.empty() ? "" : " ", rate);
        by_rate += fmt::format("{}{:.1f}", by_rate.empty() ? "" : " ", needed.back());
      }
      all = all && s.stats.converged();
      result.expect(s.stats.converged(),
                    fmt::format("{} {} level {}: {}", key.study, key.tree, level, s.stats.describe()));
      const std::string fig = fmt::format("{} {} L{} {} {:.0e}", key.study, key.tree, level,
                                          solver_label(key.kind, key.pmax), key.tolerance);
      result.gate.push_back({fig + " iterations", GateFigure::Kind::iterations, double(s.stats.iterations)});
    }
    const double ratio =
        double(rows.back().second.stats.iterations) / std::max(1, rows.front().second.stats.iterations);
    const bool rated = needed.size() == rows.size() && needed.size() >= 2;
    flat.add_row({key.study, key.tree, solver_label(key.kind, key.pmax), key.tolerance, its, ratio,
                  rated ? rates : std::string("-"), rated ? by_rate : std::string("-"),
                  rated ? Table::Cell(needed.back() / needed.front()) : Table::Cell(std::string("-"))});
    // The default truncation on the 3D adaptive Neumann matrices grows (see the top of the file):
    // a warning there; the same matrices' pmax0 rows and every other BiCGSTAB+AMG row are asserted.
    const bool known_growth = key.study == "neumann-3d" && key.tree == "adaptive" && key.pmax < 0;
    if (key.kind == SolverKind::bicgstab_amg && rows.size() >= 2) {
      const std::string what =
          fmt::format("{} {} {} at {:.0e}: iterations {} (finest / coarsest {:.2f})", key.study, key.tree,
                      solver_label(key.kind, key.pmax), key.tolerance, its, ratio);
      if (known_growth && ratio > 1.3)
        result.warnings.push_back(
            what + " are not flat with truncated interpolation (the pmax0 rows are; see the case)");
      else
        result.expect(all && ratio <= 1.3, what + " are not flat (> 1.3)");
    }
    // At 1e-10 the error is the discretisation's: the direct solver's, to 3 digits.
    if (key.tolerance == 1e-10) {
      const auto direct = results.find({key.study, key.tree, SolverKind::direct, 1e-10, -1});
      if (direct == results.end()) continue;
      for (const auto& [level, s] : rows)
        for (const auto& [dl, d] : direct->second)
          if (dl == level && s.stats.converged() && d.stats.converged())
            result.expect(
                std::abs(s.error - d.error) <= 1e-3 * d.error,
                fmt::format("{} {} level {} {}: error {:.6e} against the direct solver's {:.6e}", key.study,
                            key.tree, level, solver_label(key.kind, key.pmax), s.error, d.error));
    }
  }

  // The paper's comparison: adaptive against regular at the same finest h, tolerance 1e-6.
  Table paper(
      "the paper's comparison (Sec. 6): adaptive against regular at the same finest h, tolerance 1e-6",
      {"study", "level", "adaptive solver", "regular solver", "speed-up", "iterations regular / adaptive",
       "the paper"});
  for (const char* study : {"neumann-2d", "neumann-3d"})
    for (const SolverPair& pr : kPaperSolverPairs) {
      const auto a = results.find({study, "adaptive", pr.adaptive, 1e-6, -1});
      const auto r = results.find({study, "uniform", pr.regular, 1e-6, -1});
      if (a == results.end() || r == results.end()) continue;
      for (const auto& [level, sa] : a->second)
        for (const auto& [rl, sr] : r->second) {
          if (rl != level || !sa.stats.converged() || !sr.stats.converged()) continue;
          const double ta = sa.stats.setup_seconds + sa.stats.solve_seconds;
          const double tr = sr.stats.setup_seconds + sr.stats.solve_seconds;
          paper.add_row({std::string(study), long(level), linalg::to_string(pr.adaptive),
                         linalg::to_string(pr.regular), tr / ta,
                         double(sr.stats.iterations) / std::max(1, sa.stats.iterations),
                         std::string(pr.claim)});
        }
    }
  // Speed against error: assembly + setup + solve seconds against the L-inf error of p at 1e-10
  // (where the error is the discretisation's), one curve per tree and solver, one plot per study.
  Json series = Json::array();
  for (const auto& [key, rows] : results) {
    if (key.tolerance != 1e-10) continue;
    std::vector<double> err, seconds;
    for (const auto& [level, s] : rows)
      if (s.stats.converged() && s.error > 0.0) {
        err.push_back(s.error);
        seconds.push_back(s.assembly_seconds + s.stats.setup_seconds + s.stats.solve_seconds);
      }
    if (err.empty()) continue;
    series.push(series_entry(key.study + ": time to solution against the L-inf error of p (tolerance 1e-10)",
                             key.tree + " " + solver_label(key.kind, key.pmax), err, seconds,
                             "L-inf error of p", "assembly + setup + solve seconds"));
  }
  result.fields.set("series", std::move(series));
  result.notes.push_back(fmt::format(
      "SpMV-equivalents: (setup + solve) seconds over one product with the same matrix (median of 5 x 10 "
      "products), timed on 1 thread for the AMG solvers (hypre runs on one) and on {} for Eigen's; the "
      "regular matrices are FD only, so their products are cheaper and their equivalents higher for the "
      "same seconds",
      Eigen::nbThreads()));
  result.tables.push_back(std::move(table));
  result.tables.push_back(std::move(flat));
  result.tables.push_back(std::move(paper));
  return result;
}

}  // namespace

LIQUID_VERIFICATION_CASE(
    {"ppe-solvers",
     "every PPE solver (Jacobi, ILUT/IC, AMG) on the paper's Poisson matrices, adaptive and "
     "uniform: iterations, time, SpMV-equivalents, error",
     true, run, no_options});

}  // namespace liquid::verification
