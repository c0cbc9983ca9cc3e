// CellGraph speed: building octrees of up to a few million leaves, split/merge throughput, point
// location, k-ring queries, and a narrow-band re-adaptation after the level set moves by one fine
// cell, with every cell marked or only the tracked band, shown next to a full rebuild.
//
//   liquid-bench --benchmark_filter=Tree
//
// Counters: leaves, faces, rates per second, and for the re-adaptation the cells visited and
// changed per step, the rebuild time of the same tree (full_build_s) and the time of a step per
// changed cell against the rebuild's time per leaf.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <cstdio>
#include <memory>
#include <random>

#include "liquid/core/timer.hpp"
#include "liquid/tree/band_tracker.hpp"
#include "liquid/tree/builders.hpp"

namespace liquid {
namespace {

levelset::Function<3> sphere(const Vec<3>& centre, double radius = 0.3) {
  return [centre, radius](const Vec<3>& x) { return (x - centre).norm() - radius; };
}

/// Octrees by size: 0 uniform level 6 (262k), 1 banded level 5 (+2 in a band, ~185k),
/// 2 banded level 6 (~870k), 3 narrow band to level 9 (~1.8M), 4 uniform level 7 (2.1M).
tree::CellGraph<3> make_tree(int which) {
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
const tree::CellGraph<3>& million() {
  static const tree::CellGraph<3> g = make_tree(2);
  return g;
}

void BM_TreeBuild(benchmark::State& state) {
  const int which = static_cast<int>(state.range(0));
  int n_cells = 0, n_faces = 0;
  for (auto _ : state) {
    const tree::CellGraph<3> g = make_tree(which);
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

/// Random splits and merges of single cells on a seeded random non-graded octree (levels 2-7)
/// under each level-jump limit: splitting a fine cell next to coarse ones forces balancing splits,
/// counted in balance_per_split. Each iteration draws a leaf and tries a split (up to level 8) or
/// the merge of its sibling group; tries that change nothing are timed too. ops_per_s counts the
/// cells split (balancing included) and the groups merged. The tree drifts (splits succeed more
/// often than merges), so leaves_start and leaves (at the end) bracket its size.
void BM_TreeSplitMerge(benchmark::State& state) {
  tree::CellGraphOptions<3> options;
  options.max_jump = static_cast<int>(state.range(0));
  tree::CellGraph<3> g = tree::random<3>(Box<3>{}, 7, 2, 7, 0.35, options);
  const int leaves_start = g.n_cells();
  std::mt19937_64 rng(1);
  long splits = 0, balance = 0, merges = 0, tries = 0;
  const int max_level = 8;
  const auto pick = [&] {
    tree::CellId c;
    do {
      c = static_cast<tree::CellId>(rng() % g.cell_capacity());
    } while (!g.alive(c));
    return c;
  };
  tree::AdaptReport report;
  for (auto _ : state) {
    ++tries;
    const tree::CellId c = pick();
    if (rng() % 2 == 0) {
      if (g.level(c) >= max_level) continue;
      g.split(c, &report);
      splits += report.n_split;
      balance += report.n_balance_splits;
    } else if (g.can_merge(c)) {
      g.merge(*g.siblings(c));
      ++merges;
    }
  }
  state.counters["ops_per_s"] =
      benchmark::Counter(static_cast<double>(splits + merges), benchmark::Counter::kIsRate);
  state.counters["splits"] = static_cast<double>(splits);
  state.counters["merges"] = static_cast<double>(merges);
  state.counters["balance_per_split"] = static_cast<double>(balance) / std::max(1L, splits - balance);
  state.counters["tries"] = static_cast<double>(tries);
  state.counters["leaves_start"] = leaves_start;
  state.counters["leaves"] = g.n_cells();
}
BENCHMARK(BM_TreeSplitMerge)->Arg(1)->Arg(2)->Arg(tree::unlimited_jump)->UseRealTime();

void BM_TreeLocate(benchmark::State& state) {
  const tree::CellGraph<3>& g = million();
  const bool parallel = state.range(0) != 0;
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec<3>> points(1 << 20);
  for (auto& x : points) x = Vec<3>(u(rng), u(rng), u(rng));
  std::vector<tree::CellId> out(points.size());
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
  const tree::CellGraph<3>& g = million();
  const int k = static_cast<int>(state.range(0));
  const auto ids = g.cell_ids();
  const long n_queries = 1 << 16;
  long found = 0;
  for (auto _ : state) {
    found = 0;
#pragma omp parallel reduction(+ : found)
    {
      std::vector<tree::CellId> ring;
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
/// re-adapted by mark + adapt. First arg, the marking: 0 every cell (dense marks, dense adapt);
/// 1 the NarrowBandTracker (refined cells and the coarse cells next to them, sparse marks).
/// Second arg, the scene: 0 a sphere of radius 0.3 over a level-1 background (the band is most of
/// the tree); 1 a sphere of radius 0.1 in a uniform level-6 background; 2 the same sphere in a
/// level-7 background (4x the leaves, the same band). Scenes 1 and 2 side by side show whether a
/// step costs what changes or what exists.
void BM_TreeReadapt(benchmark::State& state) {
  const bool tracked = state.range(0) != 0;
  const int scene = static_cast<int>(state.range(1));
  const int fine = 9;
  const int coarse = scene == 0 ? 1 : scene == 1 ? 6 : 7;
  const double radius = scene == 0 ? 0.3 : 0.1;
  const double h = std::ldexp(1.0, -fine);
  const double band = 1.0;
  Vec<3> centre = Vec<3>::Constant(0.5);
  tree::CellGraph<3> g = tree::narrow_band<3>(Box<3>{}, sphere(centre, radius), coarse, fine, band);
  Stopwatch watch;
  const tree::CellGraph<3> rebuilt =
      tree::narrow_band<3>(Box<3>{}, sphere(centre, radius), coarse, fine, band);
  const double full_build = watch.seconds();
  tree::NarrowBandTracker<3> tracker(g, coarse, fine, band);
  std::vector<tree::Mark> marks;
  tree::MarkList list;
  long changed = 0, steps = 0, visited = 0;
  double mark_seconds = 0.0, adapt_seconds = 0.0;
  // One re-adaptation to the sphere at `centre`, its parts timed into the totals.
  const auto step = [&] {
    const auto phi = sphere(centre, radius);
    watch.restart();
    if (tracked) {
      tracker.mark(g, phi, list);
      visited += static_cast<long>(tracker.candidates().size());
    } else {
      tree::mark_narrow_band<3>(g, phi, coarse, fine, band, marks);
      visited += g.n_cells();
    }
    mark_seconds += watch.seconds();
    watch.restart();
    const tree::AdaptReport report = tracked ? g.adapt(list) : g.adapt(marks);
    if (tracked) tracker.update(g, report);
    adapt_seconds += watch.seconds();
    changed += static_cast<long>(report.new_cells.size() + report.removed_cells.size());
  };
  // Warm-up, not counted: the tracker's first call (which visits every cell), then one step out
  // and back, after which the id arrays have grown to their working size (their growth is
  // amortised; a step that reallocates them copies the whole tree once).
  for (int k = 0; k < 3; ++k) {
    centre[0] += k == 1 ? h : (k == 2 ? -h : 0.0);
    step();
  }
  changed = visited = 0;
  mark_seconds = adapt_seconds = 0.0;
  int direction = 1;
  for (auto _ : state) {
    centre[0] += direction * h;
    direction = -direction;
    step();
    ++steps;
  }
  state.counters["leaves"] = g.n_cells();
  state.counters["visited_per_step"] = static_cast<double>(visited) / steps;
  state.counters["changed_cells_per_step"] = static_cast<double>(changed) / steps;
  state.counters["full_build_s"] = full_build;
  state.counters["mark_s"] = mark_seconds / steps;
  state.counters["adapt_s"] = adapt_seconds / steps;
  state.counters["step_ns_per_changed_cell"] = 1e9 * (mark_seconds + adapt_seconds) / std::max(1L, changed);
  state.counters["build_ns_per_leaf"] = 1e9 * full_build / rebuilt.n_cells();
  state.counters["threads"] = omp_get_max_threads();
}
BENCHMARK(BM_TreeReadapt)
    ->ArgsProduct({{0, 1}, {0, 1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(6);

}  // namespace
}  // namespace liquid
