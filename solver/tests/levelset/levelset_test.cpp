// Level sets: distances of the primitives, CSG signs, and interface crossings along segments,
// including crossings within 1e-6 h of a node.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "liquid/core/error.hpp"
#include "liquid/levelset/levelset.hpp"

namespace liquid::levelset {
namespace {

TEST(LevelSet, PrimitivesAreSignedDistances) {
  const auto s = sphere<3>(Vec<3>(1, 0, 0), 0.5);
  EXPECT_NEAR(s(Vec<3>(1, 0, 0)), -0.5, 1e-15);
  EXPECT_NEAR(s(Vec<3>(2, 0, 0)), 0.5, 1e-15);
  const auto b = box<2>(Box<2>{Vec<2>(0, 0), Vec<2>(2, 1)});
  EXPECT_NEAR(b(Vec<2>(1, 0.5)), -0.5, 1e-15);
  EXPECT_NEAR(b(Vec<2>(3, 0.5)), 1.0, 1e-15);
  EXPECT_NEAR(b(Vec<2>(3, 2)), std::sqrt(2.0), 1e-15);
  EXPECT_THROW(sphere<2>(Vec<2>::Zero(), 0.0), Error);
}

TEST(LevelSet, CsgCombinesSigns) {
  const auto a = sphere<2>(Vec<2>(0, 0), 1.0);
  const auto b = sphere<2>(Vec<2>(1, 0), 1.0);
  const Vec<2> only_a(-0.8, 0), both(0.5, 0), only_b(1.8, 0);
  EXPECT_LT(unite<2>(a, b)(only_b), 0.0);
  EXPECT_LT(intersect<2>(a, b)(both), 0.0);
  EXPECT_GT(intersect<2>(a, b)(only_a), 0.0);
  EXPECT_LT(subtract<2>(a, b)(only_a), 0.0);
  EXPECT_GT(subtract<2>(a, b)(both), 0.0);
}

TEST(LevelSet, CrossingOnACurvedInterfaceIsAccurate) {
  // The paper's Dirichlet interface p = (y - x^2 + 1)^4 + x^2 + y^2 - 1 = 0.
  const Function<2> p = [](const Vec<2>& x) {
    return std::pow(x[1] - x[0] * x[0] + 1, 4) + x[0] * x[0] + x[1] * x[1] - 1;
  };
  const Vec<2> a(0.1, -0.2), b(0.1, -1.3);
  const auto c = crossing<2>(p, a, b, p(a), p(b));
  ASSERT_TRUE(c.has_value());
  EXPECT_NEAR(p(c->point), 0.0, 1e-11);
  EXPECT_GT(c->theta, 0.0);
  EXPECT_LT(c->theta, 1.0);
}

TEST(LevelSet, CrossingNearANodeAndAtEnds) {
  const double h = 0.01;
  const auto plane = [h](const Vec<3>& x) { return x[0] - 1e-6 * h; };
  const Function<3> phi = plane;
  const Vec<3> a(0, 0, 0), b(h, 0, 0);
  const auto c = crossing<3>(phi, a, b, phi(a), phi(b));
  ASSERT_TRUE(c.has_value());
  EXPECT_NEAR(c->theta, 1e-6, 1e-10);
  EXPECT_FALSE(crossing<3>(phi, b, Vec<3>(2 * h, 0, 0), phi(b), 1.0).has_value());
  const auto at_end = crossing<3>(phi, a, b, 0.0, 1.0);
  ASSERT_TRUE(at_end.has_value());
  EXPECT_EQ(at_end->theta, 0.0);
  EXPECT_THROW(crossing<3>(phi, a, b, std::numeric_limits<double>::quiet_NaN(), 1.0), Error);
}

}  // namespace
}  // namespace liquid::levelset
