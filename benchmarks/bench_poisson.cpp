// Pressure Poisson assembly on non-graded octrees (jump 2), with and without the RBF-FD weight
// cache (PoissonOptions::cache_weights), polynomial degree 2 and 3.
//
//   liquid-bench --benchmark_filter=PoissonAssembly
//
// Args: cache (0 off, 1 on); degree; scene: 0 a band around a sphere (the poisson-neumann-3d
// tree: T-junction layouts vary along the curved band), 1 a band around a plane (a still pool's
// surface: the layouts repeat along it). Counters (of the last iteration): unknowns, RBF-FD
// rows, weight lookups the cache served.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <cmath>

#include "liquid/levelset/levelset.hpp"
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

}  // namespace
}  // namespace liquid
