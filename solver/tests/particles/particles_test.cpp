// Particles: Halton seeding (the sequence itself, reproducible, inside the region, thread-count
// independent), binning against brute-force point location on random non-graded trees (from
// scratch, after moves, after adapts), compaction, reseeding ranges, and advection (RK2/RK3 orders,
// walls and solids).
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <random>

#include "liquid/core/error.hpp"
#include "liquid/particles/advect.hpp"
#include "liquid/particles/bins.hpp"
#include "liquid/particles/seeding.hpp"
#include "liquid/tree/builders.hpp"

namespace liquid {
namespace {

template <typename T>
class ParticlesTest : public ::testing::Test {};
using Dims = ::testing::Types<std::integral_constant<int, 2>, std::integral_constant<int, 3>>;
TYPED_TEST_SUITE(ParticlesTest, Dims);

/// The radical inverse of i in base b: the Halton coordinate by its definition.
double radical_inverse(int i, int b) {
  double f = 1.0, r = 0.0;
  for (; i > 0; i /= b) {
    f /= b;
    r += f * (i % b);
  }
  return r;
}

/// Appends lo..hi particles (uniformly at random) at uniform random points of every cell, with
/// velocity v(x); returns the count per cell id.
template <int Dim, class V>
std::vector<int> random_fill(const tree::CellGraph<Dim>& g, std::uint64_t seed, int lo, int hi, const V& v,
                             particles::Particles<Dim>& p) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> count(lo, hi);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<int> n_of(g.cell_capacity(), 0);
  g.for_each_cell([&](tree::CellId c) {
    const Box<Dim> b = g.box(c);
    n_of[c] = count(rng);
    for (int i = 0; i < n_of[c]; ++i) {
      Vec<Dim> r;
      for (int k = 0; k < Dim; ++k) r[k] = u(rng);
      const Vec<Dim> x = b.lo + r.cwiseProduct(b.size());
      p.push_back(x, v(x));
    }
  });
  return n_of;
}

template <int Dim>
tree::CellGraph<Dim> random_tree(std::uint64_t seed, int jump = 2) {
  tree::CellGraphOptions<Dim> options;
  options.max_jump = jump;
  return tree::random<Dim>(Box<Dim>{Vec<Dim>::Constant(-1.0), Vec<Dim>::Constant(1.0)}, seed,
                           Dim == 2 ? 3 : 2, Dim == 2 ? 7 : 5, 0.35, options);
}

template <int Dim>
std::vector<Vec<Dim>> random_points(int n, std::uint64_t seed, double lo = -1.0, double hi = 1.0) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(lo, hi);
  std::vector<Vec<Dim>> x(n);
  for (auto& p : x)
    for (int k = 0; k < Dim; ++k) p[k] = u(rng);
  return x;
}

template <int Dim>
void expect_bins_match_location(const tree::CellGraph<Dim>& g, std::span<const Vec<Dim>> x,
                                const particles::CellBins& bins) {
  ASSERT_EQ(bins.n_particles(), static_cast<int>(x.size()));
  long listed = 0;
  for (std::size_t i = 0; i < x.size(); ++i) ASSERT_EQ(bins.cell[i], g.locate(x[i])) << "particle " << i;
  g.for_each_cell([&](tree::CellId c) {
    const auto ps = bins.of(c);
    listed += static_cast<long>(ps.size());
    for (std::size_t k = 0; k < ps.size(); ++k) {
      EXPECT_EQ(bins.cell[ps[k]], c);
      if (k > 0) {
        EXPECT_LT(ps[k - 1], ps[k]);
      }
    }
  });
  EXPECT_EQ(listed, static_cast<long>(x.size()));
}

TEST(Halton, IsTheHaltonSequence) {
  const auto p2 = particles::halton_points<2>(50);
  const auto p3 = particles::halton_points<3>(50);
  for (int i = 0; i < 50; ++i) {
    EXPECT_NEAR(p2[i][0], radical_inverse(i + 1, 2), 1e-15);
    EXPECT_NEAR(p2[i][1], radical_inverse(i + 1, 3), 1e-15);
    EXPECT_NEAR(p3[i][2], radical_inverse(i + 1, 5), 1e-15);
  }
}

TYPED_TEST(ParticlesTest, SeedingIsReproducibleInsideTheRegionAndThreadIndependent) {
  constexpr int Dim = TypeParam::value;
  const auto g = random_tree<Dim>(3);
  const auto region =
      levelset::subtract<Dim>(levelset::sphere<Dim>(Vec<Dim>::Constant(0.1), 0.8),
                              levelset::box<Dim>({Vec<Dim>::Constant(0.2), Vec<Dim>::Constant(0.6)}));
  for (double jitter : {0.0, 0.5}) {
    particles::SeedOptions options;
    options.jitter = jitter;
    particles::Particles<Dim> a, b;
    const int threads = omp_get_max_threads();
    omp_set_num_threads(1);
    const long na = particles::seed_region<Dim>(g, region, options, a);
    omp_set_num_threads(std::max(2, threads));
    const long nb = particles::seed_region<Dim>(g, region, options, b);
    omp_set_num_threads(threads);
    ASSERT_GT(na, 100);
    ASSERT_EQ(na, nb);
    for (int i = 0; i < a.size(); ++i) {
      ASSERT_EQ(a.x[i], b.x[i]);
      EXPECT_LT(region(a.x[i]), 0.0);
    }
    particles::CellBins bins;
    particles::bin_particles<Dim>(g, a.x, bins);
    g.for_each_cell([&](tree::CellId c) { EXPECT_LE(bins.count(c), 1 << Dim); });
    // The same relative pattern in every cell: a cell wholly inside gets all 2^Dim points.
    const tree::CellId c = g.locate(Vec<Dim>::Constant(-0.1));  // a cell wholly inside the region
    if (jitter == 0.0 && g.level(c) >= 3) {
      ASSERT_EQ(bins.count(c), 1 << Dim);
      const auto pattern = particles::halton_points<Dim>(1 << Dim);
      const Box<Dim> box = g.box(c);
      const Vec<Dim> rel = (a.x[bins.of(c)[0]] - box.lo).cwiseQuotient(box.size());
      EXPECT_NEAR((rel - pattern[0]).norm(), 0.0, 1e-12);
    }
  }
  particles::SeedOptions bad;
  bad.jitter = 1.5;
  particles::Particles<Dim> p;
  EXPECT_THROW(particles::seed_region<Dim>(g, region, bad, p), Error);
}

TYPED_TEST(ParticlesTest, BinningEqualsPointLocationThroughMovesAndAdapts) {
  constexpr int Dim = TypeParam::value;
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    auto g = random_tree<Dim>(seed, seed == 3 ? tree::unlimited_jump : 2);
    auto x = random_points<Dim>(5000, seed);
    particles::CellBins bins;
    particles::bin_particles<Dim>(g, x, bins);
    expect_bins_match_location<Dim>(g, x, bins);

    // Small moves: most stay; only those that left their cell are located.
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> step(0.0, 0.004);
    for (auto& p : x)
      for (int k = 0; k < Dim; ++k) p[k] = std::clamp(p[k] + step(rng), -1.0, 1.0);
    particles::BinStats moved = particles::rebin<Dim>(g, x, bins);
    expect_bins_match_location<Dim>(g, x, bins);
    EXPECT_GT(moved.stayed, 4000);
    EXPECT_EQ(moved.stayed + moved.located, 5000);
    EXPECT_EQ(moved.remapped, 0);

    // An adapt: splits and merges at random; particles that did not move are remapped, not located.
    tree::MarkList marks;
    ASSERT_GT(g.n_cells(), 100);
    std::bernoulli_distribution coin(0.15);
    g.for_each_cell([&](tree::CellId c) {
      if (coin(rng)) (g.level(c) % 2 ? marks.split : marks.merge).push_back(c);
    });
    const tree::AdaptReport report = g.adapt(marks);
    ASSERT_FALSE(report.empty());
    const particles::BinStats adapted = particles::rebin<Dim>(g, x, bins, &report);
    expect_bins_match_location<Dim>(g, x, bins);
    EXPECT_EQ(adapted.located, 0);
    EXPECT_GT(adapted.remapped, 0);
  }
}

TEST(Particles, FieldsCompactAndRefuseBadUse) {
  particles::Particles<2> p;
  p.push_back(Vec<2>(0.1, 0.2), Vec<2>(1, 0));
  const int f = p.add_field("apic", 4);
  const int id = p.add_field("id", 1);
  EXPECT_THROW(p.add_field("apic", 2), Error);
  EXPECT_THROW(p.field_index("nope"), Error);
  for (int i = 1; i < 6; ++i) p.push_back(Vec<2>(0.1 * i, 0.0), Vec<2>(i, 0));
  for (int i = 0; i < p.size(); ++i) {
    p.field(id)[i] = i;
    for (int k = 0; k < 4; ++k) p.field(f)[4 * i + k] = 10 * i + k;
  }
  std::vector<std::uint8_t> remove{1, 0, 0, 1, 0, 1};
  std::vector<std::int32_t> to;
  EXPECT_EQ(p.compact(remove, &to), 3);
  ASSERT_EQ(p.size(), 3);
  EXPECT_EQ(to, (std::vector<std::int32_t>{-1, 0, 1, -1, 2, -1}));
  const int kept[3] = {1, 2, 4};
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(p.field(id)[i], kept[i]);
    EXPECT_EQ(p.field(f)[4 * i + 3], 10 * kept[i] + 3);
    EXPECT_EQ(p.v[i][0], kept[i]);
  }
  EXPECT_THROW(p.compact(std::vector<std::uint8_t>(2, 0)), Error);
}

TYPED_TEST(ParticlesTest, ReseedingBringsEveryFluidCellIntoRange) {
  constexpr int Dim = TypeParam::value;
  const auto g = random_tree<Dim>(5);
  // 0 to 24 particles per cell, at random.
  particles::Particles<Dim> p;
  random_fill<Dim>(
      g, 11, 0, 24, [](const Vec<Dim>&) -> Vec<Dim> { return Vec<Dim>::Constant(-7.0); }, p);
  particles::CellBins bins;
  particles::bin_particles<Dim>(g, p.x, bins);
  const int lo = Dim == 2 ? 3 : 5, hi = Dim == 2 ? 12 : 15;
  long outside = 0, occupied = 0;
  g.for_each_cell([&](tree::CellId c) {
    const int n = bins.count(c);
    occupied += n > 0;
    outside += n > 0 && (n < lo || n > hi);
  });
  ASSERT_GT(outside, 10);
  const auto cells = g.cell_ids();
  const auto source = [](std::span<const Vec<Dim>> x, std::span<const tree::CellId>, std::span<Vec<Dim>> v) {
    for (std::size_t i = 0; i < x.size(); ++i) v[i] = 2.0 * x[i];
  };
  const long before = p.size();
  const particles::ReseedReport r =
      particles::reseed<Dim>(g, cells, particles::ReseedOptions{}, source, p, bins);
  EXPECT_EQ(r.cells, outside);
  EXPECT_EQ(r.created, outside * (1 << Dim));
  EXPECT_EQ(p.size(), before - r.deleted + r.created);
  expect_bins_match_location<Dim>(g, p.x, bins);
  long occupied_after = 0;
  g.for_each_cell([&](tree::CellId c) {
    const int n = bins.count(c);
    occupied_after += n > 0;
    if (n > 0) {
      EXPECT_GE(n, lo) << "cell " << c;
      EXPECT_LE(n, hi) << "cell " << c;
    }
  });
  EXPECT_EQ(occupied_after, occupied);  // empty (non-fluid) cells stay empty
  for (int i = static_cast<int>(before - r.deleted); i < p.size(); ++i) EXPECT_EQ(p.v[i], 2.0 * p.x[i]);
  EXPECT_EQ(particles::reseed<Dim>(g, cells, particles::ReseedOptions{}, source, p, bins).cells,
            0);  // idempotent
  // Empty cells are left alone unless the caller says they are fluid (fill_empty).
  std::vector<tree::CellId> empty;
  g.for_each_cell([&](tree::CellId c) {
    if (bins.count(c) == 0) empty.push_back(c);
  });
  ASSERT_FALSE(empty.empty());
  EXPECT_EQ(particles::reseed<Dim>(g, empty, particles::ReseedOptions{}, source, p, bins).created, 0);
  particles::ReseedOptions fill;
  fill.fill_empty = true;
  const particles::ReseedReport filled = particles::reseed<Dim>(g, empty, fill, source, p, bins);
  EXPECT_EQ(filled.cells, static_cast<long>(empty.size()));
  EXPECT_EQ(filled.created, static_cast<long>(empty.size()) * (1 << Dim));
  for (tree::CellId c : empty) EXPECT_EQ(bins.count(c), 1 << Dim);
  expect_bins_match_location<Dim>(g, p.x, bins);
  particles::ReseedOptions bad;
  bad.lo = 10, bad.hi = 5;
  EXPECT_THROW(particles::reseed<Dim>(g, cells, bad, source, p, bins), Error);
}

// keep: a crowded cell keeps 2^Dim of its own particles (velocities untouched), a sparse one keeps
// all of its own and is topped up to 2^Dim; only the new particles take the source's velocities.
TYPED_TEST(ParticlesTest, ReseedingThatKeepsChangesOnlyTheSurplusOrTheShortfall) {
  constexpr int Dim = TypeParam::value;
  const auto g = random_tree<Dim>(9);
  particles::Particles<Dim> p;  // the old particles' velocities: -3 x
  const std::vector<int> before = random_fill<Dim>(
      g, 3, 1, 24, [](const Vec<Dim>& x) -> Vec<Dim> { return -3.0 * x; }, p);
  particles::CellBins bins;
  particles::bin_particles<Dim>(g, p.x, bins);
  const auto source = [](std::span<const Vec<Dim>> x, std::span<const tree::CellId>, std::span<Vec<Dim>> v) {
    for (std::size_t i = 0; i < x.size(); ++i) v[i] = 2.0 * x[i];
  };
  particles::ReseedOptions keep;
  keep.keep = true;
  const int lo = Dim == 2 ? 3 : 5, hi = Dim == 2 ? 12 : 15, full = 1 << Dim;
  long crowded = 0, sparse = 0, surplus = 0, shortfall = 0;
  g.for_each_cell([&](tree::CellId c) {
    crowded += before[c] > hi;
    sparse += before[c] < lo;
    if (before[c] > hi) surplus += before[c] - full;
    if (before[c] < lo) shortfall += full - before[c];
  });
  ASSERT_GT(crowded, 5);
  ASSERT_GT(sparse, 5);
  const particles::ReseedReport r = particles::reseed<Dim>(g, g.cell_ids(), keep, source, p, bins);
  EXPECT_EQ(r.cells, crowded + sparse);
  EXPECT_EQ(r.deleted, surplus);
  EXPECT_EQ(r.created, shortfall);
  expect_bins_match_location<Dim>(g, p.x, bins);
  g.for_each_cell([&](tree::CellId c) {
    const int n = bins.count(c);
    if (before[c] < lo || before[c] > hi)
      EXPECT_EQ(n, full) << "cell " << c;
    else
      EXPECT_EQ(n, before[c]) << "cell " << c;
    int old = 0;
    for (std::int32_t i : bins.of(c)) old += (p.v[i] + 3.0 * p.x[i]).norm() < 1e-12;
    const int own = before[c] > hi ? full : before[c];  // sparse and in-range cells keep all theirs
    EXPECT_EQ(old, own) << "cell " << c << ": its own particles kept";
  });
  for (int i = p.size() - static_cast<int>(r.created); i < p.size(); ++i) EXPECT_EQ(p.v[i], 2.0 * p.x[i]);
}

/// Error of one revolution of a rigid rotation about the origin.
template <int Dim>
double rotation_error(particles::Integrator integrator, int steps) {
  const auto u = [](const Vec<Dim>& x) {
    Vec<Dim> v = Vec<Dim>::Zero();
    v[0] = -x[1], v[1] = x[0];
    return v;
  };
  std::vector<Vec<Dim>> x(3, Vec<Dim>::Zero());
  x[0][0] = 0.5, x[1][1] = -0.3, x[2][0] = 0.2, x[2][1] = 0.4;
  const auto start = x;
  const double dt = 2 * std::numbers::pi / steps;
  const Box<Dim> domain{Vec<Dim>::Constant(-1.0), Vec<Dim>::Constant(1.0)};
  for (int s = 0; s < steps; ++s) particles::advect<Dim>(x, dt, integrator, u, domain);
  double e = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) e = std::max(e, (x[i] - start[i]).norm());
  return e;
}

TYPED_TEST(ParticlesTest, AdvectionConvergesAtTheOrderOfItsIntegrator) {
  constexpr int Dim = TypeParam::value;
  const double o2 = std::log2(rotation_error<Dim>(particles::Integrator::rk2, 64) /
                              rotation_error<Dim>(particles::Integrator::rk2, 128));
  const double o3 = std::log2(rotation_error<Dim>(particles::Integrator::rk3, 64) /
                              rotation_error<Dim>(particles::Integrator::rk3, 128));
  EXPECT_NEAR(o2, 2.0, 0.2);
  EXPECT_NEAR(o3, 3.0, 0.2);
  EXPECT_LT(rotation_error<Dim>(particles::Integrator::rk3, 64),
            rotation_error<Dim>(particles::Integrator::rk2, 64));
}

TYPED_TEST(ParticlesTest, AdvectionClampsToTheDomainAndPushesOutOfSolids) {
  constexpr int Dim = TypeParam::value;
  const Box<Dim> domain{Vec<Dim>::Zero(), Vec<Dim>::Ones()};
  const auto solid = levelset::sphere<Dim>(Vec<Dim>::Constant(0.5), 0.2);
  auto x = random_points<Dim>(400, 7, 0.0, 1.0);
  std::erase_if(x, [&](const Vec<Dim>& p) { return solid(p) < 0.0; });
  const auto towards_centre = [](const Vec<Dim>& p) { return Vec<Dim>(Vec<Dim>::Constant(0.5) - p); };
  const particles::AdvectReport r =
      particles::advect<Dim>(x, 0.9, particles::Integrator::rk2, towards_centre, domain, solid);
  EXPECT_GT(r.pushed, 50);
  EXPECT_EQ(r.stuck, 0);
  for (const auto& p : x) {
    EXPECT_GE(solid(p), 0.0);
    EXPECT_TRUE(domain.contains(p));
  }
  const auto outwards = [](const Vec<Dim>& p) { return Vec<Dim>(10.0 * (p - Vec<Dim>::Constant(0.5))); };
  const particles::AdvectReport w =
      particles::advect<Dim>(x, 1.0, particles::Integrator::rk3, outwards, domain);
  EXPECT_EQ(w.clamped, static_cast<long>(x.size()));
  for (const auto& p : x) EXPECT_TRUE(domain.contains(p));
  const auto nan = [](const Vec<Dim>&) { return Vec<Dim>::Constant(std::nan("")); };
  EXPECT_THROW(particles::advect<Dim>(x, 0.1, particles::Integrator::rk2, nan, domain), Error);
}

TYPED_TEST(ParticlesTest, AdvectionInAnyOrderMovesEachParticleAlike) {
  constexpr int Dim = TypeParam::value;
  const Box<Dim> domain{Vec<Dim>::Zero(), Vec<Dim>::Ones()};
  const auto solid = levelset::sphere<Dim>(Vec<Dim>::Constant(0.5), 0.2);
  auto x = random_points<Dim>(300, 11, 0.0, 1.0);
  std::erase_if(x, [&](const Vec<Dim>& p) { return solid(p) < 0.0; });
  const auto swirl = [](const Vec<Dim>& p) {
    Vec<Dim> v = Vec<Dim>::Zero();
    v[0] = -(p[1] - 0.5) + 0.3 * p[0] * p[0];
    v[1] = (p[0] - 0.5);
    return v;
  };
  std::vector<std::int32_t> order(x.size());
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), std::mt19937(5));
  auto y = x;
  const auto a = particles::advect<Dim>(x, 0.4, particles::Integrator::rk3, swirl, domain, solid);
  const auto b = particles::advect<Dim>(y, 0.4, particles::Integrator::rk3, swirl, domain, solid, order);
  EXPECT_EQ(a.pushed, b.pushed);
  EXPECT_EQ(a.clamped, b.clamped);
  for (std::size_t i = 0; i < x.size(); ++i) EXPECT_EQ(x[i], y[i]) << "particle " << i;
  order.pop_back();
  EXPECT_THROW(particles::advect<Dim>(y, 0.1, particles::Integrator::rk2, swirl, domain, {}, order), Error);
}

}  // namespace
}  // namespace liquid
