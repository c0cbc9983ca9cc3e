// CellGraph speed: building octrees of up to a few million leaves, split/merge throughput, point
// location, k-ring queries, and a narrow-band re-adaptation after the level set moves by one fine
// cell, shown next to a full rebuild of the same tree.
//
//   liquid-bench --benchmark_filter=Tree
//
// Counters: leaves, faces, rates per second, and for the re-adaptation the cells changed per step,
// the rebuild time of the same tree (full_build_s) and the time per changed cell against the
// rebuild's time per leaf.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <cstdio>
#include <memory>
#include <random>

#include "liquid/core/timer.hpp"
#include "liquid/tree/builders.hpp"

namespace liquid {
namespace {

tree::LevelSet<3> sphere(const Vec<3>& centre, double radius = 0.3) {
  return [centre, radius](const Vec<3>& x) { return (x - centre).norm() - radius; };
}

/// Octrees by size: 0 uniform level 6 (262k), 1 banded level 5 (+2 in a band, ~185k),
/// 2 banded level 6 (~870k), 3 narrow band to level 9 (~1.8M), 4 uniform level 7 (2.1M).
CellGraph<3> make_tree(int which) {
  const Box<3> unit;
  const auto phi = sphere(Vec<3>::Constant(0.5));
  switch (which) {
    case 0:
      return tree::uniform<3>(unit, 6);
    case 1:
      return tree::banded<3>(unit, phi, 5, 2.0);
    case 2:
      return tree::banded<3>(unit, phi, 6, 2.0);
    case 3:
      return tree::narrow_band<3>(unit, phi, 1, 9, 1.0);
    default:
      return tree::uniform<3>(unit, 7);
  }
}

/// One shared ~1M-leaf octree for the query benchmarks.
const CellGraph<3>& million() {
  static const CellGraph<3> g = make_tree(2);
  return g;
}

void BM_TreeBuild(benchmark::State& state) {
  const int which = static_cast<int>(state.range(0));
  int n_cells = 0, n_faces = 0;
  for (auto _ : state) {
    const CellGraph<3> g = make_tree(which);
    n_cells = g.n_cells();
    n_faces = g.n_faces();
    benchmark::DoNotOptimize(n_cells);
  }
  state.counters["leaves"] = n_cells;
  state.counters["faces"] = n_faces;
  state.counters["leaves_per_s"] =
      benchmark::Counter(static_cast<double>(n_cells), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["threads"] = omp_get_max_threads();
}
BENCHMARK(BM_TreeBuild)->DenseRange(0, 4)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_TreeSplitMerge(benchmark::State& state) {
  CellGraphOptions<3> options;
  options.max_jump = static_cast<int>(state.range(0));
  CellGraph<3> g = tree::uniform<3>(Box<3>{}, 5, options);
  std::mt19937_64 rng(1);
  long ops = 0;
  for (auto _ : state) {
    // Split a random leaf and merge its children back: two local changes.
    CellId c;
    do {
      c = static_cast<CellId>(rng() % g.cell_capacity());
    } while (!g.alive(c) || g.level(c) != 5);
    const auto children = g.split(c);
    g.merge(children);
    ops += 2;
  }
  state.counters["ops_per_s"] = benchmark::Counter(static_cast<double>(ops), benchmark::Counter::kIsRate);
  state.counters["leaves"] = g.n_cells();
}
BENCHMARK(BM_TreeSplitMerge)->Arg(1)->Arg(2)->Arg(unlimited_jump)->UseRealTime();

void BM_TreeLocate(benchmark::State& state) {
  const CellGraph<3>& g = million();
  const bool parallel = state.range(0) != 0;
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec<3>> points(1 << 20);
  for (auto& x : points) x = Vec<3>(u(rng), u(rng), u(rng));
  std::vector<CellId> out(points.size());
  for (auto _ : state) {
    if (parallel) {
      g.locate(points, out);
    } else {
      for (std::size_t i = 0; i < points.size(); ++i) out[i] = g.locate(points[i]);
    }
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["points_per_s"] =
      benchmark::Counter(static_cast<double>(points.size()), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["leaves"] = g.n_cells();
  state.counters["threads"] = parallel ? omp_get_max_threads() : 1;
}
BENCHMARK(BM_TreeLocate)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_TreeKRing(benchmark::State& state) {
  const CellGraph<3>& g = million();
  const int k = static_cast<int>(state.range(0));
  const auto ids = g.cell_ids();
  const long n_queries = 1 << 16;
  long found = 0;
  for (auto _ : state) {
    found = 0;
#pragma omp parallel reduction(+ : found)
    {
      std::vector<CellId> ring;
#pragma omp for schedule(static)
      for (long q = 0; q < n_queries; ++q) {
        g.k_ring(ids[(q * 2654435761L) % ids.size()], k, ring);
        found += static_cast<long>(ring.size());
      }
    }
    benchmark::DoNotOptimize(found);
  }
  state.counters["queries_per_s"] =
      benchmark::Counter(static_cast<double>(n_queries), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["mean_ring"] = static_cast<double>(found) / n_queries;
  state.counters["threads"] = omp_get_max_threads();
}
BENCHMARK(BM_TreeKRing)->Arg(1)->Arg(2)->Arg(3)->Unit(benchmark::kMillisecond)->UseRealTime();

/// Narrow band to level 9 around a sphere that moves by one fine cell per step (back and forth),
/// re-adapted by mark + adapt. First arg, the marking: 0 every cell; 1 only the previous band's
/// cells and their 1-ring (the paper's surface-cell list, kept up to date from the reports).
/// Second arg, the scene: 0 a sphere of radius 0.3 over a level-1 background (the band is most of
/// the tree); 1 a sphere of radius 0.1 in a uniform level-6 background (most cells far from it).
void BM_TreeReadapt(benchmark::State& state) {
  const bool band_only = state.range(0) != 0;
  const bool small = state.range(1) != 0;
  const int fine = 9;
  const int coarse = small ? 6 : 1;
  const double radius = small ? 0.1 : 0.3;
  const double h = std::ldexp(1.0, -fine);
  const double band = 1.0;
  Vec<3> centre = Vec<3>::Constant(0.5);
  CellGraph<3> g = tree::narrow_band<3>(Box<3>{}, sphere(centre, radius), coarse, fine, band);
  Stopwatch watch;
  const CellGraph<3> rebuilt = tree::narrow_band<3>(Box<3>{}, sphere(centre, radius), coarse, fine, band);
  const double full_build = watch.seconds();
  std::vector<Mark> marks;
  std::vector<CellId> candidates, ring, band_list;
  std::vector<std::uint32_t> stamp;
  std::vector<std::uint8_t> in_band;
  // The band list (cells at the two finest levels), kept up to date from the change reports.
  const auto band_add = [&](CellId c) {
    if (g.level(c) < fine - 1) return;
    if (in_band.size() <= static_cast<std::size_t>(c)) in_band.resize(g.cell_capacity(), 0);
    in_band[c] = 1;
    band_list.push_back(c);
  };
  g.for_each_cell(band_add);
  long changed = 0, steps = 0;
  double mark_seconds = 0.0, adapt_seconds = 0.0;
  int direction = 1;
  std::uint32_t round = 0;
  for (auto _ : state) {
    centre[0] += direction * h;
    direction = -direction;
    const auto phi = sphere(centre, radius);
    watch.restart();
    if (band_only) {
      ++round;
      candidates.clear();
      if (stamp.size() < static_cast<std::size_t>(g.cell_capacity())) stamp.resize(g.cell_capacity(), 0);
      std::size_t kept = 0;
      for (CellId c : band_list) {
        if (!g.alive(c) || !in_band[c]) continue;
        band_list[kept++] = c;
        g.k_ring(c, 1, ring);
        for (CellId x : ring)
          if (stamp[x] != round) {
            stamp[x] = round;
            candidates.push_back(x);
          }
      }
      band_list.resize(kept);
      tree::mark_narrow_band<3>(g, phi, coarse, fine, band, marks, &candidates);
    } else {
      tree::mark_narrow_band<3>(g, phi, coarse, fine, band, marks);
    }
    mark_seconds += watch.seconds();
    watch.restart();
    const AdaptReport report = g.adapt(marks);
    adapt_seconds += watch.seconds();
    for (CellId c : report.removed_cells)
      if (static_cast<std::size_t>(c) < in_band.size()) in_band[c] = 0;
    for (CellId c : report.new_cells) band_add(c);
    changed += static_cast<long>(report.new_cells.size() + report.removed_cells.size());
    ++steps;
  }
  state.counters["leaves"] = g.n_cells();
  state.counters["changed_cells_per_step"] = static_cast<double>(changed) / steps;
  state.counters["full_build_s"] = full_build;
  state.counters["mark_s"] = mark_seconds / steps;
  state.counters["adapt_s"] = adapt_seconds / steps;
  state.counters["adapt_ns_per_changed_cell"] = 1e9 * adapt_seconds / std::max(1L, changed);
  state.counters["build_ns_per_leaf"] = 1e9 * full_build / rebuilt.n_cells();
  state.counters["candidates"] = band_only ? static_cast<double>(candidates.size()) : g.n_cells();
}
BENCHMARK(BM_TreeReadapt)
    ->ArgsProduct({{0, 1}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(6);

}  // namespace
}  // namespace liquid
