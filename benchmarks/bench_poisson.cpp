// Pressure Poisson assembly on non-graded octrees (jump 2), with and without the RBF-FD weight
// cache (PoissonOptions::cache_weights), polynomial degree 2 and 3; and the PPE solvers on 2D
// matrices (BM_PpeSolve).
//
//   liquid-bench --benchmark_filter=PoissonAssembly
//   liquid-bench --benchmark_filter=PpeSolve
//
// Args: cache (0 off, 1 on); degree; scene: 0 a band around a sphere (the poisson-neumann-3d
// tree: T-junction layouts vary along the curved band), 1 a band around a plane (a still pool's
// surface: the layouts repeat along it). Counters (of the last iteration): unknowns, RBF-FD
// rows, weight lookups the cache served.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <cmath>

#include "liquid/levelset/levelset.hpp"
#include "liquid/linalg/solver.hpp"
#include "liquid/mac/poisson.hpp"
#include "liquid/tree/builders.hpp"

namespace liquid {
namespace {

CellGraph<3> scene_tree(int scene) {
  const Box<3> unit;
  if (scene == 0)
    return tree::narrow_band<3>(unit, levelset::sphere<3>(Vec<3>::Constant(0.5), 0.29), 4, 6, 2.0);
  // A plane just off the cell faces, so the band is a slab of whole cells.
  return tree::narrow_band<3>(
      unit, [](const Vec<3>& x) { return x[2] - 0.4; }, 4, 6, 2.0);
}

void BM_PoissonAssembly(benchmark::State& state) {
  const bool cache = state.range(0) != 0;
  const int degree = static_cast<int>(state.range(1));
  const CellGraph<3> g = scene_tree(static_cast<int>(state.range(2)));
  mac::PoissonProblem<3> problem;
  problem.f = [](const Vec<3>& x) { return -3.0 * std::cos(x[0]) * std::cos(x[1]) * std::cos(x[2]); };
  problem.pin_value = [](const Vec<3>& x) { return std::cos(x[0]) * std::cos(x[1]) * std::cos(x[2]); };
  mac::PoissonOptions options;
  options.rbf.degree = degree;
  options.cache_weights = cache;
  mac::AssemblyStats stats;
  for (auto _ : state) {
    const auto sys = mac::assemble_poisson<3>(g, problem, options);
    stats = sys.stats;
    benchmark::DoNotOptimize(sys.b.data());
  }
  state.counters["unknowns"] = static_cast<double>(stats.n_unknowns);
  state.counters["rbf_rows"] = static_cast<double>(stats.n_rbf_rows);
  state.counters["cache_hits"] = static_cast<double>(stats.n_cache_hits);
  state.counters["threads"] = omp_get_max_threads();
}
BENCHMARK(BM_PoissonAssembly)
    ->ArgNames({"cache", "degree", "scene"})
    ->ArgsProduct({{0, 1}, {2, 3}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// BM_PpeSolve/solver/tree/level: one solve (setup included) of the 2D Neumann PPE of
// poisson-neumann-2d (p = cos x cos y - 1 on [0, pi]^2, pinned), tolerance 1e-8, from zero.
// solver: 0 bicgstab-ilut (the default), 1 bicgstab-amg, 2 gmres-amg, 3 cg-amg (uniform only);
// tree: 0 uniform at `level`, 1 a band around a circle at `level`, level - 2 elsewhere (cg-amg on
// the uniform tree only: it needs a symmetric matrix). The first AMG solve of a process also starts
// MPI (about 0.3 s): run with --benchmark_min_time large enough to repeat.
// Counters: unknowns, iterations.
void BM_PpeSolve(benchmark::State& state) {
  const linalg::SolverKind kinds[] = {linalg::SolverKind::bicgstab_ilut, linalg::SolverKind::bicgstab_amg,
                                      linalg::SolverKind::gmres_amg, linalg::SolverKind::cg_amg};
  const auto kind = kinds[state.range(0)];
  const bool adaptive = state.range(1) != 0;
  const int level = static_cast<int>(state.range(2));
  const Box<2> domain{Vec<2>::Zero(), Vec<2>::Constant(M_PI)};
  const CellGraph<2> g =
      adaptive ? tree::narrow_band<2>(domain, levelset::sphere<2>(Vec<2>::Constant(0.5 * M_PI), 0.9),
                                      level - 2, level, 2.0)
               : tree::uniform<2>(domain, level);
  mac::PoissonProblem<2> problem;
  problem.f = [](const Vec<2>& x) { return -2.0 * std::cos(x[0]) * std::cos(x[1]); };
  problem.pin_value = [](const Vec<2>& x) { return std::cos(x[0]) * std::cos(x[1]) - 1.0; };
  const auto sys = mac::assemble_poisson<2>(g, problem, mac::PoissonOptions{});
  linalg::SolveStats stats;
  for (auto _ : state) {
    linalg::Vector x;
    stats = linalg::solve(sys.A, sys.b, x, {kind, 1e-8, 20000});
    benchmark::DoNotOptimize(x.data());
  }
  if (!stats.converged()) state.SkipWithError(stats.describe().c_str());
  state.counters["unknowns"] = static_cast<double>(sys.n_unknowns());
  state.counters["iterations"] = stats.iterations;
}
BENCHMARK(BM_PpeSolve)
    ->ArgNames({"solver", "tree", "level"})
    ->Apply([](benchmark::internal::Benchmark* b) {
      for (int solver = 0; solver < 4; ++solver)
        for (int tree = 0; tree < 2; ++tree)
          for (int level : {6, 7, 8})
            if (solver != 3 || tree == 0) b->Args({solver, tree, level});
    })
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace liquid
