// The RBF interpolant: interpolation at the nodes, polynomial reproduction, gradients (also in one
// pass with the value); the cache of shared factors: equal to a direct interpolant to round-off
// whatever the node order, one entry per layout at any level and place, an entry that depends on its
// key alone, bypassed off the quantum.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "liquid/core/error.hpp"
#include "liquid/rbf/interpolant.hpp"
#include "liquid/rbf/interpolant_cache.hpp"
#include "support/stencils.hpp"

namespace liquid::rbf {
namespace {

TEST(RbfInterpolant, InterpolatesAtNodesAndReproducesQuadratics3D) {
  auto nodes = support::jittered_stencil<3>(1, 0.2, 0.3, 9u);
  for (auto& x : nodes) x += Vec<3>(1.0, -2.0, 0.5);  // away from the origin on purpose
  Interpolant<3> interp(nodes, Config{5, 2});
  ASSERT_TRUE(interp.status().usable()) << interp.status().describe();
  auto quad = [](const Vec<3>& x) { return 1.0 + 2 * x[0] - x[1] * x[2] + 0.5 * x[0] * x[0]; };
  auto wavy = [](const Vec<3>& x) { return std::sin(3 * x[0]) * std::cos(x[1] + x[2]); };
  Eigen::MatrixXd values(nodes.size(), 2);
  for (std::size_t j = 0; j < nodes.size(); ++j) values.row(j) << quad(nodes[j]), wavy(nodes[j]);
  interp.fit(values);
  for (std::size_t j = 0; j < nodes.size(); ++j) {
    const auto v = interp.value(nodes[j]);
    EXPECT_NEAR(v[0], values(j, 0), 1e-10);
    EXPECT_NEAR(v[1], values(j, 1), 1e-10);
  }
  const Vec<3> x(1.07, -1.95, 0.41);
  EXPECT_NEAR(interp.value(x)[0], quad(x), 1e-10);
  const Eigen::MatrixXd g = interp.gradient(x);
  EXPECT_NEAR(g(0, 0), 2 + x[0], 1e-9);
  EXPECT_NEAR(g(1, 0), -x[2], 1e-9);
  EXPECT_NEAR(g(2, 0), -x[1], 1e-9);
  // The one-pass value and gradient are the two calls' bits, for either field (r^3 and r^5).
  for (int exponent : {3, 5}) {
    Interpolant<3> other(nodes, Config{exponent, exponent == 3 ? 1 : 2});
    ASSERT_TRUE(other.status().usable());
    other.fit(values);
    for (int column : {0, 1}) {
      double grad[3];
      const double value = other.value_and_gradient(x, column, grad);
      EXPECT_EQ(value, other.value_at(x, column));
      const Eigen::MatrixXd expected = other.gradient(x);
      for (int k = 0; k < 3; ++k) EXPECT_EQ(grad[k], expected(k, column)) << "axis " << k;
    }
    double grad[3];
    EXPECT_THROW(other.value_and_gradient(x, 2, grad), Error);
  }
}

TEST(RbfInterpolant, ErrorsAreExplicit) {
  const auto nodes = support::jittered_stencil<2>(1, 0.1, 0.2, 1u);
  Interpolant<2> interp(nodes, Config{5, 2});
  EXPECT_THROW(interp.value(Vec<2>::Zero()), Error);             // not fitted
  EXPECT_THROW(interp.fit(Eigen::MatrixXd::Zero(3, 1)), Error);  // wrong row count
  Interpolant<2> empty(std::vector<Vec<2>>{}, Config{});
  EXPECT_EQ(empty.status().info, Info::empty_stencil);
  EXPECT_THROW(empty.fit(Eigen::MatrixXd::Zero(0, 1)), Error);
}

// The same layout of nodes at three levels and two places, gathered in a shuffled order each time:
// one factorisation, and every interpolant agrees with the one factorised for its own nodes.
TEST(InterpolantCache, CongruentStencilsShareOneFactorisationAndMatchDirectInterpolants) {
  const auto base = support::quadtree_stencil<2>(1, 1.0, 4u);
  const auto field = [](const Vec<2>& x) { return std::sin(2.0 * x[0]) + x[0] * x[1]; };
  InterpolantCache<2> cache;
  std::mt19937 rng(3);
  std::vector<int> order;
  int calls = 0;
  for (double h : {0.125, 0.0625, 0.03125}) {
    for (const Vec<2>& at : {Vec<2>(0.5, 0.25), Vec<2>(-0.375, 0.75)}) {
      std::vector<Vec<2>> nodes;
      for (const auto& x : base) nodes.push_back(at + h * x);
      std::shuffle(nodes.begin(), nodes.end(), rng);
      Eigen::VectorXd values(nodes.size());
      for (std::size_t j = 0; j < nodes.size(); ++j) values[j] = field(nodes[j]);

      Interpolant<2> direct(nodes, Config{5, 2});
      direct.fit(values);
      Interpolant<2> shared = cache.interpolant(nodes, at, h, Config{5, 2}, order);
      ASSERT_TRUE(shared.status().usable()) << shared.status().describe();
      ASSERT_EQ(order.size(), nodes.size());
      Eigen::VectorXd sorted(nodes.size());
      for (std::size_t j = 0; j < nodes.size(); ++j) sorted[j] = values[order[j]];
      shared.fit(sorted);
      for (const Vec<2>& d : {Vec<2>(0.1, -0.2), Vec<2>(0.45, 0.3), Vec<2>(-0.5, -0.5)}) {
        const Vec<2> x = at + h * d;
        EXPECT_NEAR(shared.value_at(x), direct.value_at(x), 1e-12) << "h " << h;
        EXPECT_NEAR((shared.gradient(x) - direct.gradient(x)).norm(), 0.0, 1e-9 / h) << "h " << h;
      }
      for (std::size_t j = 0; j < nodes.size(); ++j) EXPECT_NEAR(shared.value_at(nodes[j]), values[j], 1e-12);
      ++calls;
    }
  }
  EXPECT_EQ(cache.misses(), 1);
  EXPECT_EQ(cache.hits(), calls - 1);
  EXPECT_EQ(cache.size(), 1u);
  // Other kernel settings are other entries: the degree alone, then the exponent alone.
  cache.interpolant(base, Vec<2>::Zero(), 1.0, Config{5, 1}, order);
  EXPECT_EQ(cache.misses(), 2);
  cache.interpolant(base, Vec<2>::Zero(), 1.0, Config{3, 2}, order);
  EXPECT_EQ(cache.misses(), 3);
}

// An entry is factorised from its key's offsets: the same layout met at places whose coordinates
// round differently gives the same values whichever place is met first. Off the quantum (a cell
// side a third of another) the nodes are factorised directly and nothing is stored; a full cache is
// emptied and goes on.
TEST(InterpolantCache, EntriesDependOnTheKeyAloneAndOffQuantumStencilsBypass) {
  const auto base = support::quadtree_stencil<3>(1, 1.0, 7u);
  const double h = 0.0625 * 3.141592653589793;
  const Vec<3> here(0.1, 0.7, 0.3), there(1234.567, 89.01, -7.25);
  const auto place = [&](const Vec<3>& at) {
    std::vector<Vec<3>> nodes;
    for (const auto& x : base) nodes.push_back(at + h * x);
    return nodes;
  };
  const auto probe = [&](InterpolantCache<3>& cache, const Vec<3>& at) {
    std::vector<int> order;
    Interpolant<3> interp = cache.interpolant(place(at), at, h, Config{5, 2}, order);
    Eigen::VectorXd v(base.size());
    for (std::size_t j = 0; j < base.size(); ++j)
      v[j] = std::cos(base[order[j]][0] + 2.0 * base[order[j]][2]);
    interp.fit(v);
    return interp.value_at(at + h * Vec<3>(0.2, -0.1, 0.3));
  };
  InterpolantCache<3> one, other;
  const double a_first = probe(one, here), b_second = probe(one, there);
  const double b_first = probe(other, there), a_second = probe(other, here);
  EXPECT_EQ(one.hits(), 1);
  EXPECT_EQ(a_first, a_second);
  EXPECT_EQ(b_first, b_second);

  std::vector<Vec<3>> thirds = base;
  for (auto& x : thirds) x[1] /= 3.0;
  InterpolantCache<3> cache(0x1p-24, 4);
  std::vector<int> order;
  EXPECT_TRUE(cache.interpolant(thirds, Vec<3>::Zero(), 1.0, Config{5, 2}, order).status().usable());
  EXPECT_EQ(cache.bypassed(), 1);
  EXPECT_EQ(cache.size(), 0u);
  // An interpolant handed out before the cache empties itself keeps its factors.
  Interpolant<3> early = cache.interpolant(base, Vec<3>::Zero(), 1.0, Config{5, 2}, order);
  Eigen::VectorXd early_values(base.size());
  for (std::size_t j = 0; j < base.size(); ++j) early_values[j] = base[order[j]][0] - 2.0 * base[order[j]][1];
  const Vec<3> probe_at(0.1, 0.2, -0.3);
  for (unsigned seed : {1u, 2u, 3u})
    cache.interpolant(support::quadtree_stencil<3>(1, 1.0, seed), Vec<3>::Zero(), 1.0, Config{5, 2}, order);
  // Two generations of two entries each: the fourth shape turned the third and fourth old, dropping
  // the first two.
  EXPECT_EQ(cache.misses(), 4);
  EXPECT_EQ(cache.flushes(), 2);
  EXPECT_LE(cache.size(), 4u);
  // An old shape that is met again is kept (a hit), a dropped one is made again (a miss).
  cache.interpolant(support::quadtree_stencil<3>(1, 1.0, 3u), Vec<3>::Zero(), 1.0, Config{5, 2}, order);
  EXPECT_EQ(cache.hits(), 1);
  cache.interpolant(support::quadtree_stencil<3>(1, 1.0, 1u), Vec<3>::Zero(), 1.0, Config{5, 2}, order);
  EXPECT_EQ(cache.misses(), 5);
  early.fit(early_values);
  EXPECT_NEAR(early.value_at(probe_at), probe_at[0] - 2.0 * probe_at[1], 1e-12);
  EXPECT_THROW(cache.interpolant(base, Vec<3>::Zero(), 0.0, Config{5, 2}, order), Error);
}

// A node farther than 2^14 h, or not finite, gets no key: the nodes are factorised directly (a NaN
// is reported, never a cache entry), and the order handed back is still a permutation. Under UBSan
// this also checks that the canonical order's squared offsets do not overflow.
// The Lebesgue function: 1 at the nodes (the cardinal functions are 0 or 1 there), at least 1
// anywhere (they sum to 1, constants being reproduced), small on a balanced stencil and large on a
// one-sided, nearly unisolvent one; cell_lebesgue() is lebesgue() over the cell's 3^Dim lattice,
// shared by interpolants on the same factors, and reads the cell the same way when the cache
// bypasses a stencil.
TEST(RbfInterpolant, LebesgueConstantBoundsHowErrorsGrow) {
  // A 5 x 5 lattice of spacing 1 around the origin, and the unit cell at its centre.
  std::vector<Vec<2>> lattice;
  for (int i = -2; i <= 2; ++i)
    for (int j = -2; j <= 2; ++j) lattice.push_back(Vec<2>(i, j));
  const Interpolant<2> balanced(lattice, Config{5, 2});
  ASSERT_TRUE(balanced.status().usable());
  EXPECT_NEAR(balanced.lebesgue(lattice), 1.0, 1e-9);
  std::vector<Vec<2>> cell;
  for (int k = 0; k < 9; ++k) cell.push_back(Vec<2>(0.5 * (k % 3) - 0.5, 0.5 * (k / 3) - 0.5));
  const double inside = balanced.lebesgue(cell);
  EXPECT_GE(inside, 1.0 - 1e-12);
  EXPECT_LT(inside, 3.0);
  // The same lattice evaluated far outside its nodes: extrapolation amplifies.
  EXPECT_GT(balanced.lebesgue(std::vector<Vec<2>>{Vec<2>(6.0, 6.0)}), 10.0);
  // Seven nodes for degree 2's six terms, all on one side of the cell: nearly unisolvent.
  const std::vector<Vec<2>> one_sided{Vec<2>(0, 0), Vec<2>(1, 0), Vec<2>(2, 0),    Vec<2>(0, 1),
                                      Vec<2>(1, 1), Vec<2>(0, 2), Vec<2>(2.0, 1.5)};
  const Interpolant<2> lopsided(one_sided, Config{5, 2});
  ASSERT_TRUE(lopsided.status().usable());
  ASSERT_EQ(lopsided.status().degree_used, 2);
  std::vector<Vec<2>> far_cell;
  for (const auto& x : cell) far_cell.push_back(x + Vec<2>(-1.0, -1.0));
  EXPECT_GT(lopsided.lebesgue(far_cell), 5 * inside);

  // cell_lebesgue(): through the cache (the cell centre and size as frame), shared, and over the
  // same cell when the cache bypasses the stencil (off the quantum: the nodes shifted by 1e-3 h).
  InterpolantCache<2> cache;
  std::vector<int> order;
  const Vec<2> centre(10.0, -4.0);
  const double h = 0.25;
  std::vector<Vec<2>> nodes;
  for (const auto& x : lattice) nodes.push_back(centre + h * x);
  const Interpolant<2> a = cache.interpolant(nodes, centre, h, Config{5, 2}, order);
  const Interpolant<2> b = cache.interpolant(nodes, centre, h, Config{5, 2}, order);
  EXPECT_EQ(cache.misses(), 1);
  EXPECT_NEAR(a.cell_lebesgue(), inside, 1e-9);
  EXPECT_EQ(b.cell_lebesgue(), a.cell_lebesgue());
  std::vector<Vec<2>> shifted_nodes;
  for (const auto& x : nodes) shifted_nodes.push_back(x + Vec<2>(1e-3 * h, 0.0));
  const Interpolant<2> bypassed = cache.interpolant(shifted_nodes, centre, h, Config{5, 2}, order);
  EXPECT_EQ(cache.bypassed(), 1);
  std::vector<Vec<2>> world_cell;
  for (const auto& x : cell) world_cell.push_back(centre + h * x);
  const Interpolant<2> world(shifted_nodes, Config{5, 2});
  EXPECT_NEAR(bypassed.cell_lebesgue(), world.lebesgue(world_cell), 1e-9);
}

TEST(InterpolantCache, FarOrNonFiniteNodesAreFactorisedDirectly) {
  InterpolantCache<2> cache;
  std::vector<Vec<2>> nodes = support::quadtree_stencil<2>(1, 1.0, 4u);
  nodes.push_back(Vec<2>(3e5, 0.0));
  std::vector<int> order;
  const auto is_permutation = [&] {
    std::vector<int> sorted = order;
    std::sort(sorted.begin(), sorted.end());
    std::vector<int> ids(nodes.size());
    std::iota(ids.begin(), ids.end(), 0);
    return sorted == ids;
  };
  cache.interpolant(nodes, Vec<2>::Zero(), 1.0, Config{5, 2}, order);
  EXPECT_TRUE(is_permutation());
  EXPECT_EQ(cache.bypassed(), 1);
  nodes.back() = Vec<2>(std::nan(""), 0.0);
  EXPECT_EQ(cache.interpolant(nodes, Vec<2>::Zero(), 1.0, Config{5, 2}, order).status().info,
            Info::non_finite);
  EXPECT_TRUE(is_permutation());
  EXPECT_EQ(cache.bypassed(), 2);
  EXPECT_EQ(cache.size(), 0u);
}

}  // namespace
}  // namespace liquid::rbf
