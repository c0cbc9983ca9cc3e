// RBF-FD weight throughput: Laplacian weights (PHS r^3, degree 2) for T-junction stencils of
// 9-25 nodes in 2D and 19-48 nodes in 3D, computed directly and through the weight cache.
// The cached runs cycle through 64 distinct layouts at several levels and positions, as a tree's
// repeated T-junctions would.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <random>

#include "liquid/rbf/weight_cache.hpp"
#include "liquid/rbf/weights.hpp"
#include "support/stencils.hpp"

namespace {

using namespace liquid;

template <int Dim>
std::vector<std::vector<Vec<Dim>>> layouts(int n_nodes, int n_layouts) {
  std::vector<std::vector<Vec<Dim>>> out;
  for (int i = 0; i < n_layouts; ++i) {
    auto nodes = support::quadtree_stencil<Dim>(2, 1.0, 17u + i);
    std::stable_sort(nodes.begin(), nodes.end(),
                     [](const Vec<Dim>& a, const Vec<Dim>& b) { return a.squaredNorm() < b.squaredNorm(); });
    nodes.resize(std::min<std::size_t>(nodes.size(), n_nodes));
    out.push_back(std::move(nodes));
  }
  return out;
}

template <int Dim>
void BM_WeightsUncached(benchmark::State& state) {
  const auto stencils = layouts<Dim>(static_cast<int>(state.range(0)), 64);
  std::vector<double> w;
  std::size_t i = 0;
  for (auto _ : state) {
    const auto st = rbf::weights<Dim>(stencils[i++ % stencils.size()], Vec<Dim>::Zero(),
                                      rbf::Operator<Dim>::lap(), rbf::Config{}, w);
    benchmark::DoNotOptimize(st);
    benchmark::DoNotOptimize(w.data());
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["nodes"] = static_cast<double>(stencils.front().size());
}

template <int Dim>
void BM_WeightsCached(benchmark::State& state) {
  const auto base = layouts<Dim>(static_cast<int>(state.range(0)), 64);
  // The same layouts at four levels and places: geometry differs, normalised geometry repeats.
  std::vector<std::vector<Vec<Dim>>> stencils;
  std::vector<Vec<Dim>> centres;
  std::vector<double> sizes;
  for (int level = 0; level < 4; ++level)
    for (std::size_t l = 0; l < base.size(); ++l) {
      const double h = std::ldexp(1.0, -3 - level);
      const Vec<Dim> centre = Vec<Dim>::Constant(0.5 + 0.25 * static_cast<double>(l % 3));
      std::vector<Vec<Dim>> nodes;
      for (const auto& x : base[l]) nodes.push_back(centre + h * x);
      stencils.push_back(std::move(nodes));
      centres.push_back(centre);
      sizes.push_back(h);
    }
  rbf::WeightCache<Dim> cache;
  std::vector<double> w;
  std::size_t i = 0;
  for (auto _ : state) {
    const std::size_t k = i++ % stencils.size();
    const auto st =
        cache.weights(stencils[k], centres[k], sizes[k], rbf::Operator<Dim>::lap(), rbf::Config{}, w);
    benchmark::DoNotOptimize(st);
    benchmark::DoNotOptimize(w.data());
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["nodes"] = static_cast<double>(base.front().size());
  state.counters["hit_rate"] =
      static_cast<double>(cache.hits()) / std::max(1L, cache.hits() + cache.misses());
}

/// The particle -> face transfer's solve: value weights of PHS r^3 + degree 1 (the default transfer)
/// on `n` scattered nodes around a face centre (at most 16 in 3D: the node cap).
template <int Dim>
void BM_ValueWeights(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<std::vector<Vec<Dim>>> stencils(64);
  for (auto& nodes : stencils)
    for (int i = 0; i < n; ++i) {
      Vec<Dim> x;
      for (int k = 0; k < Dim; ++k) x[k] = u(rng);
      nodes.push_back(x);
    }
  rbf::Config config{3, 1};
  config.condition_estimate = rbf::ConditionEstimate::probes;
  std::vector<double> w;
  std::size_t i = 0;
  for (auto _ : state) {
    const auto st = rbf::value_weights<Dim>(stencils[i++ % stencils.size()], Vec<Dim>::Zero(), config, w);
    benchmark::DoNotOptimize(st);
    benchmark::DoNotOptimize(w.data());
  }
  state.SetItemsProcessed(state.iterations());
}

BENCHMARK(BM_ValueWeights<2>)->Arg(8)->Arg(12);
BENCHMARK(BM_ValueWeights<3>)->Arg(8)->Arg(16);
BENCHMARK(BM_WeightsUncached<2>)->Arg(9)->Arg(13)->Arg(17)->Arg(21)->Arg(25);
BENCHMARK(BM_WeightsCached<2>)->Arg(9)->Arg(13)->Arg(17)->Arg(21)->Arg(25);
BENCHMARK(BM_WeightsUncached<3>)->Arg(19)->Arg(27)->Arg(33)->Arg(40)->Arg(48);
BENCHMARK(BM_WeightsCached<3>)->Arg(19)->Arg(27)->Arg(33)->Arg(40)->Arg(48);

}  // namespace
