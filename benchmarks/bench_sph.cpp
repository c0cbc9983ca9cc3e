// Adaptive SPH: neighbour search (cell list against k-d tree), force evaluation, and the redistancing
// and feature-size marches (queue against rounds) per particle, on single-level and three-level
// particle sets of 100k and 1M particles (2D and 3D). The three-level
// set stands in for an adaptive one: the box is cut into three slabs along x, of levels 0, 1 and 2,
// each a jittered lattice at its level's spacing. Items are particles.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "liquid/sph/distance_surface.hpp"
#include "liquid/sph/feature_size.hpp"
#include "liquid/sph/forces.hpp"
#include "liquid/sph/neighbours.hpp"

namespace {

using namespace liquid;
using namespace liquid::sph;

/// About n particles in the unit box: one level, or three slabs of levels 0, 1, 2.
template <int Dim>
SphParticles<Dim> particle_set(long n, bool levels) {
  Sizes sizes;
  // Level-0 spacing for n particles if all were level 0.
  const double s0 = std::pow(1.0 / static_cast<double>(n), 1.0 / Dim);
  sizes.radius = 2.5 * s0;
  sizes.mass = 1000.0 * std::pow(s0, Dim);
  SphParticles<Dim> p;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> jitter(-0.1, 0.1);
  for (int slab = 0; slab < (levels ? 3 : 1); ++slab) {
    const int level = levels ? slab : 0;
    const double s = sizes.spacing_of<Dim>(level);
    const double x0 = levels ? slab / 3.0 : 0.0, x1 = levels ? (slab + 1) / 3.0 : 1.0;
    Eigen::Matrix<long, Dim, 1> count, k = Eigen::Matrix<long, Dim, 1>::Zero();
    count[0] = std::max(1L, std::lround((x1 - x0) / s));
    for (int d = 1; d < Dim; ++d) count[d] = std::max(1L, std::lround(1.0 / s));
    while (true) {
      Vec<Dim> x = (k.template cast<double>() + Vec<Dim>::Constant(0.5)) * s;
      x[0] += x0;
      for (int d = 0; d < Dim; ++d) x[d] += jitter(rng) * s;
      p.add(sizes, x, Vec<Dim>::Zero(), level, 0.0, 1000.0);
      int d = 0;
      while (d < Dim && ++k[d] >= count[d]) k[d] = 0, ++d;
      if (d == Dim) break;
    }
  }
  return p;
}

template <int Dim>
void BM_SphNeighbours(benchmark::State& state) {
  const bool tree = state.range(0) == 1, levels = state.range(1) == 1;
  const SphParticles<Dim> p = particle_set<Dim>(state.range(2), levels);
  long pairs = 0;
  for (auto _ : state) {
    NeighbourLists lists;
    if (tree) {
      const PointTree<Dim> kd(p.x);
      lists = find_neighbours<Dim>(kd, p.x, p.radius);
    } else {
      lists = find_neighbours_cells<Dim>(p.x, p.radius);
    }
    pairs = lists.n_pairs();
    benchmark::DoNotOptimize(lists.index.data());
  }
  state.SetItemsProcessed(state.iterations() * p.size());
  state.counters["particles"] = p.size();
  state.counters["pairs per particle"] = static_cast<double>(pairs) / p.size();
}

template <int Dim>
void BM_SphForces(benchmark::State& state) {
  const bool levels = state.range(0) == 1;
  SphParticles<Dim> p = particle_set<Dim>(state.range(1), levels);
  const NeighbourLists lists = find_neighbours_cells<Dim>(p.x, p.radius);
  FluidConstants fluid;
  fluid.stiffness = 1e5;
  Vec<Dim> g = Vec<Dim>::Zero();
  g[1] = -9.81;
  for (auto _ : state) {
    compute_density<Dim>(p, lists, fluid);
    compute_accelerations<Dim>(p, lists, fluid, g);
    benchmark::DoNotOptimize(p.a.data());
  }
  state.SetItemsProcessed(state.iterations() * p.size());
  state.counters["particles"] = p.size();
}

/// One redistancing and one feature-size estimate (the every-k-th-step phases of AdaptiveSph) of the
/// three-level set, whose carried distances are the exact ones to the unit box's faces.
template <int Dim>
void BM_SphMarches(benchmark::State& state) {
  const MarchOrder order = state.range(0) == 1 ? MarchOrder::parallel : MarchOrder::serial;
  SphParticles<Dim> start = particle_set<Dim>(state.range(1), true);
  for (int i = 0; i < start.size(); ++i) {
    double d = 1.0;
    for (int k = 0; k < Dim; ++k) d = std::min({d, start.x[i][k], 1.0 - start.x[i][k]});
    start.distance[i] = std::max(d, 0.0);
  }
  const PointTree<Dim> tree(start.x);
  const NeighbourLists lists = find_neighbours<Dim>(tree, start.x, start.radius);
  for (auto _ : state) {
    state.PauseTiming();
    SphParticles<Dim> p = start;
    state.ResumeTiming();
    redistance<Dim>(p, lists, tree, 1, 0.5, order);
    feature_size<Dim>(p, lists, 60.0, nullptr, order);
    benchmark::DoNotOptimize(p.elfs.data());
  }
  state.SetItemsProcessed(state.iterations() * start.size());
  state.counters["particles"] = start.size();
}

// Arguments: search (0 cell list, 1 k-d tree), levels (0 one, 1 three), particles.
BENCHMARK(BM_SphNeighbours<2>)
    ->ArgsProduct({{0, 1}, {0, 1}, {100000, 1000000}})
    ->ArgNames({"kdtree", "levels", "n"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_SphNeighbours<3>)
    ->ArgsProduct({{0, 1}, {0, 1}, {100000, 1000000}})
    ->ArgNames({"kdtree", "levels", "n"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
// Arguments: levels (0 one, 1 three), particles.
BENCHMARK(BM_SphForces<2>)
    ->ArgsProduct({{0, 1}, {100000, 1000000}})
    ->ArgNames({"levels", "n"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_SphForces<3>)
    ->ArgsProduct({{0, 1}, {100000, 1000000}})
    ->ArgNames({"levels", "n"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
// Arguments: order (0 queue, 1 rounds), particles.
BENCHMARK(BM_SphMarches<2>)
    ->ArgsProduct({{0, 1}, {100000}})
    ->ArgNames({"rounds", "n"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_SphMarches<3>)
    ->ArgsProduct({{0, 1}, {100000}})
    ->ArgNames({"rounds", "n"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
