// Pressure Poisson assembly on non-graded octrees (jump 2), with and without the RBF-FD weight
// cache (PoissonOptions::cache_weights), polynomial degree 2 and 3; and the PPE solvers on 2D
// matrices (BM_PpeSolve).
//
//   liquid-bench --benchmark_filter=PoissonAssembly
//   liquid-bench --benchmark_filter=PpeSolve
//
// Args: cache (0 off, 1 one per assembly, 2 one kept across assemblies and warm, as a PIC solver
// keeps its across steps); degree; scene: 0 a band around a sphere (the poisson-neumann-3d
// tree: T-junction layouts vary along the curved band), 1 a band around a plane (a still pool's
// surface: the layouts repeat along it). Counters (of the last iteration): unknowns, RBF-FD
// rows, weight lookups the cache served.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <cmath>

#include "liquid/core/timer.hpp"
#include "liquid/levelset/levelset.hpp"
#include "liquid/linalg/solver.hpp"
#include "liquid/mac/poisson.hpp"
#include "liquid/tree/builders.hpp"

namespace liquid {
namespace {

tree::CellGraph<3> scene_tree(int scene) {
  const Box<3> unit;
  if (scene == 0)
    return tree::narrow_band<3>(unit, levelset::sphere<3>(Vec<3>::Constant(0.5), 0.29), 4, 6, 2.0);
  // A plane just off the cell faces, so the band is a slab of whole cells.
  return tree::narrow_band<3>(
      unit, [](const Vec<3>& x) { return x[2] - 0.4; }, 4, 6, 2.0);
}

void BM_PoissonAssembly(benchmark::State& state) {
  const int cache = static_cast<int>(state.range(0));
  const int degree = static_cast<int>(state.range(1));
  const tree::CellGraph<3> g = scene_tree(static_cast<int>(state.range(2)));
  mac::PoissonProblem<3> problem;
  problem.f = [](const Vec<3>& x) { return -3.0 * std::cos(x[0]) * std::cos(x[1]) * std::cos(x[2]); };
  problem.pin_value = [](const Vec<3>& x) { return std::cos(x[0]) * std::cos(x[1]) * std::cos(x[2]); };
  mac::PoissonOptions options;
  options.rbf.degree = degree;
  options.cache_weights = cache != 0;
  rbf::WeightCache<3> kept;
  rbf::WeightCache<3>* const shared = cache == 2 ? &kept : nullptr;
  if (shared) mac::assemble_poisson<3>(g, problem, options, shared);  // warm it
  mac::AssemblyStats stats;
  for (auto _ : state) {
    const auto sys = mac::assemble_poisson<3>(g, problem, options, shared);
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
    ->ArgsProduct({{0, 1, 2}, {2, 3}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The FD-row path against a plain CSR fill: BM_PoissonAssemblyUniform assembles the Neumann PPE
// on a uniform 2D grid of 4^level cells (every row FD, f compiled, pinned), BM_CsrFill builds the
// same 5-point matrix from triplets with nothing else to do (Eigen's setFromTriplets, the fill the
// assembly ends with). Their ratio is what the tree walk, the row kernels and the right-hand side
// cost on top of the fill.
void BM_PoissonAssemblyUniform(benchmark::State& state) {
  const int level = static_cast<int>(state.range(0));
  const tree::CellGraph<2> g = tree::uniform<2>({Vec<2>::Zero(), Vec<2>::Constant(M_PI)}, level);
  mac::PoissonProblem<2> problem;
  problem.f = [](const Vec<2>& x) { return -2.0 * std::cos(x[0]) * std::cos(x[1]); };
  problem.pin_value = [](const Vec<2>& x) { return std::cos(x[0]) * std::cos(x[1]) - 1.0; };
  long unknowns = 0;
  for (auto _ : state) {
    const auto sys = mac::assemble_poisson<2>(g, problem, mac::PoissonOptions{});
    unknowns = sys.n_unknowns();
    benchmark::DoNotOptimize(sys.b.data());
  }
  state.counters["unknowns"] = static_cast<double>(unknowns);
  state.counters["rows_per_s"] =
      benchmark::Counter(static_cast<double>(unknowns) * state.iterations(), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_PoissonAssemblyUniform)->Arg(7)->Arg(9)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_CsrFill(benchmark::State& state) {
  const int n = 1 << state.range(0);
  const double inv_h2 = 1.0 / ((M_PI / n) * (M_PI / n));
  for (auto _ : state) {
    std::vector<Eigen::Triplet<double>> t;
    t.reserve(5L * n * n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const int row = i * n + j;
        double diag = 0.0;
        const auto neighbour = [&](int ii, int jj) {
          if (ii < 0 || jj < 0 || ii >= n || jj >= n) return;
          t.emplace_back(row, ii * n + jj, inv_h2);
          diag -= inv_h2;
        };
        neighbour(i - 1, j), neighbour(i + 1, j), neighbour(i, j - 1), neighbour(i, j + 1);
        t.emplace_back(row, row, diag);
      }
    linalg::SparseMatrix A(long(n) * n, long(n) * n);
    A.setFromTriplets(t.begin(), t.end());
    benchmark::DoNotOptimize(A.valuePtr());
  }
  state.counters["rows_per_s"] =
      benchmark::Counter(double(n) * n * state.iterations(), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_CsrFill)->Arg(7)->Arg(9)->Unit(benchmark::kMillisecond)->UseRealTime();

// BM_PpeSolve<Dim>/solver/tree/level: one solve (setup included) of the Neumann PPE of
// poisson-neumann-2d/3d (p = prod cos x_k - 1 on [0, pi]^Dim, pinned), tolerance 1e-8, from zero.
// solver: 0 bicgstab-ilut (the 2D default), 1 bicgstab-amg, 2 gmres-amg, 3 cg-amg (uniform only);
// tree: 0 uniform at `level`, 1 a band around a circle (sphere) of radius 0.9 at `level`, level - 2
// elsewhere (cg-amg on the uniform tree only: it needs a symmetric matrix). MPI starts before the
// timing (make_solver). Counters: unknowns, iterations, spmv_equiv (seconds of a solve over one
// product with the matrix on one thread, as hypre runs).
template <int Dim>
void BM_PpeSolve(benchmark::State& state) {
  const linalg::SolverKind kinds[] = {linalg::SolverKind::bicgstab_ilut, linalg::SolverKind::bicgstab_amg,
                                      linalg::SolverKind::gmres_amg, linalg::SolverKind::cg_amg};
  const auto kind = kinds[state.range(0)];
  const bool adaptive = state.range(1) != 0;
  const int level = static_cast<int>(state.range(2));
  const Box<Dim> domain{Vec<Dim>::Zero(), Vec<Dim>::Constant(M_PI)};
  const tree::CellGraph<Dim> g =
      adaptive ? tree::narrow_band<Dim>(domain, levelset::sphere<Dim>(Vec<Dim>::Constant(0.5 * M_PI), 0.9),
                                        level - 2, level, 2.0)
               : tree::uniform<Dim>(domain, level);
  const auto cosines = [](const Vec<Dim>& x) {
    double p = 1.0;
    for (int k = 0; k < Dim; ++k) p *= std::cos(x[k]);
    return p;
  };
  mac::PoissonProblem<Dim> problem;
  problem.f = [cosines](const Vec<Dim>& x) { return -Dim * cosines(x); };
  problem.pin_value = [cosines](const Vec<Dim>& x) { return cosines(x) - 1.0; };
  const auto sys = mac::assemble_poisson<Dim>(g, problem, mac::PoissonOptions{});
  [[maybe_unused]] const auto warm = linalg::make_solver({kind, 1e-8, 20000});  // starts MPI (AMG) untimed
  linalg::SolveStats stats;
  double seconds = 0.0;
  for (auto _ : state) {
    linalg::Vector x;
    // A fresh solver each time: the timing includes the setup (a kept AMG hierarchy would skip it).
    stats = linalg::make_solver({kind, 1e-8, 20000})->solve(sys.A, sys.b, x);
    seconds = stats.setup_seconds + stats.solve_seconds;
    benchmark::DoNotOptimize(x.data());
  }
  if (!stats.converged()) state.SkipWithError(stats.describe().c_str());
  const int threads = Eigen::nbThreads();
  Eigen::setNbThreads(1);
  const linalg::Vector ones = linalg::Vector::Ones(sys.A.cols());
  linalg::Vector y(sys.A.rows());
  Stopwatch product;
  for (int k = 0; k < 20; ++k) y.noalias() = sys.A * ones;
  const double t_spmv = product.seconds() / 20.0;
  Eigen::setNbThreads(threads);
  state.counters["unknowns"] = static_cast<double>(sys.n_unknowns());
  state.counters["iterations"] = stats.iterations;
  state.counters["spmv_equiv"] = seconds / std::max(t_spmv, 1e-9);
}
void ppe_solve_args(benchmark::internal::Benchmark* b, std::initializer_list<int> levels) {
  b->ArgNames({"solver", "tree", "level"});
  for (int solver = 0; solver < 4; ++solver)
    for (int tree = 0; tree < 2; ++tree)
      for (int level : levels)
        if (solver != 3 || tree == 0) b->Args({solver, tree, level});
}
BENCHMARK(BM_PpeSolve<2>)
    ->Apply([](benchmark::internal::Benchmark* b) {
      ppe_solve_args(b, {6, 7, 8});
    })
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_PpeSolve<3>)
    ->Apply([](benchmark::internal::Benchmark* b) {
      ppe_solve_args(b, {4, 5});
    })
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace liquid
