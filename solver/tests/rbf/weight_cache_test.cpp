// The weight cache: equal to uncached weights, hits on repeated layouts at any level and place,
// consistent under OpenMP.
#include <gtest/gtest.h>

#include <omp.h>

#include "liquid/core/error.hpp"
#include "liquid/rbf/weight_cache.hpp"
#include "support/stencils.hpp"

namespace liquid::rbf {
namespace {

TEST(WeightCache, MatchesUncachedWeightsAndHitsOnRepeatedLayouts) {
  WeightCache<2> cache;
  const auto base = support::quadtree_stencil<2>(1, 1.0, 4u);
  const Config config;
  std::vector<double> cached, direct;
  // The same T-junction layout at three levels and two places: one miss, then hits.
  int calls = 0;
  for (double h : {0.125, 0.0625, 0.03125}) {
    for (const Vec<2>& shift : {Vec<2>(0.5, 0.25), Vec<2>(-0.375, 0.75)}) {
      std::vector<Vec<2>> nodes;
      for (const auto& x : base) nodes.push_back(shift + h * x);
      const Status st = cache.weights(nodes, shift, h, Operator<2>::lap(), config, cached);
      ASSERT_TRUE(st.usable());
      ASSERT_TRUE(weights<2>(nodes, shift, Operator<2>::lap(), config, direct).usable());
      ASSERT_EQ(cached.size(), direct.size());
      for (std::size_t j = 0; j < cached.size(); ++j)
        EXPECT_NEAR(cached[j], direct[j], 1e-9 * (1.0 + std::abs(direct[j])));
      ++calls;
    }
  }
  EXPECT_EQ(cache.misses(), 1);
  EXPECT_EQ(cache.hits(), calls - 1);
  EXPECT_EQ(cache.size(), 1u);
  // A different operator on the same geometry reuses the entry.
  ASSERT_TRUE(cache.weights(base, Vec<2>::Zero(), 1.0, Operator<2>::partial(1), config, cached).usable());
  EXPECT_EQ(cache.misses(), 1);
  // Other kernel settings are a different entry.
  ASSERT_TRUE(cache.weights(base, Vec<2>::Zero(), 1.0, Operator<2>::lap(), Config{5, 2}, cached).usable());
  EXPECT_EQ(cache.misses(), 2);
  // So is another condition estimate alone: an entry's refusal must be the estimate asked for.
  Config probes{5, 2};
  probes.condition_estimate = ConditionEstimate::probes;
  ASSERT_TRUE(cache.weights(base, Vec<2>::Zero(), 1.0, Operator<2>::lap(), probes, cached).usable());
  EXPECT_EQ(cache.misses(), 3);
}

TEST(WeightCache, ConsistentUnderOpenMP) {
  WeightCache<3> cache;
  const int n_layouts = 8;
  std::vector<std::vector<Vec<3>>> layouts;
  for (int i = 0; i < n_layouts; ++i) layouts.push_back(support::quadtree_stencil<3>(1, 1.0, 100u + i));
  const int n_queries = 400;
  std::vector<double> checks(n_queries, 0.0);
#pragma omp parallel for num_threads(4)
  for (int q = 0; q < n_queries; ++q) {
    std::vector<double> w;
    const auto& nodes = layouts[q % n_layouts];
    const Status st = cache.weights(nodes, Vec<3>::Zero(), 1.0, Operator<3>::lap(), Config{}, w);
    checks[q] = st.usable() ? w[0] : std::nan("");
  }
  EXPECT_EQ(cache.hits() + cache.misses(), n_queries);
  EXPECT_EQ(static_cast<int>(cache.size()), n_layouts);
  EXPECT_LE(cache.misses(), 4 * n_layouts);  // a racing miss may compute twice, never more
  for (int q = n_layouts; q < n_queries; ++q) EXPECT_EQ(checks[q], checks[q % n_layouts]);
}

TEST(WeightCache, UnusableStencilsAreCachedAsUnusable) {
  WeightCache<2> cache;
  const std::vector<Vec<2>> nodes{{0, 0}, {1, 0}, {1, 0}};
  std::vector<double> w;
  EXPECT_EQ(cache.weights(nodes, Vec<2>::Zero(), 1.0, Operator<2>::lap(), Config{}, w).info,
            Info::coincident_nodes);
  EXPECT_TRUE(w.empty());
  EXPECT_THROW(cache.weights(nodes, Vec<2>::Zero(), 0.0, Operator<2>::lap(), Config{}, w), Error);
}

// An entry depends on its key alone: the same layout met at places whose coordinates round
// differently gives bit-identical weights whichever place is met first. A layout whose offsets are
// not on the quantum (a cell side a third of another) is computed directly and not stored.
TEST(WeightCache, EntriesDependOnTheKeyAloneAndOffQuantumStencilsBypass) {
  const auto base = support::quadtree_stencil<2>(1, 1.0, 9u);
  const double h = 0.0625 * 3.141592653589793;          // cells of a box of side pi, as on a tree
  const Vec<2> here(0.1, 0.7), there(1234.567, 89.01);  // nodes - at rounds differently
  const auto place = [&](const Vec<2>& at) {
    std::vector<Vec<2>> nodes;
    for (const auto& x : base) nodes.push_back(at + h * x);
    return nodes;
  };
  std::vector<double> a_first, b_second, b_first, a_second;
  WeightCache<2> one, other;
  ASSERT_TRUE(one.weights(place(here), here, h, Operator<2>::lap(), Config{}, a_first).usable());
  ASSERT_TRUE(one.weights(place(there), there, h, Operator<2>::lap(), Config{}, b_second).usable());
  ASSERT_TRUE(other.weights(place(there), there, h, Operator<2>::lap(), Config{}, b_first).usable());
  ASSERT_TRUE(other.weights(place(here), here, h, Operator<2>::lap(), Config{}, a_second).usable());
  EXPECT_EQ(one.hits(), 1);
  EXPECT_EQ(a_first, a_second);
  EXPECT_EQ(b_second, b_first);

  std::vector<Vec<2>> thirds = base;
  for (auto& x : thirds) x[1] /= 3.0;
  std::vector<double> cached, direct;
  WeightCache<2> cache;
  ASSERT_TRUE(cache.weights(thirds, Vec<2>::Zero(), 1.0, Operator<2>::lap(), Config{}, cached).usable());
  ASSERT_TRUE(weights<2>(thirds, Vec<2>::Zero(), Operator<2>::lap(), Config{}, direct).usable());
  EXPECT_EQ(cached, direct);
  EXPECT_EQ(cache.bypassed(), 1);
  EXPECT_EQ(cache.size(), 0u);
}

}  // namespace
}  // namespace liquid::rbf
