// The RBF interpolant: interpolation at the nodes, polynomial reproduction, gradients.
#include <gtest/gtest.h>

#include <cmath>

#include "liquid/core/error.hpp"
#include "liquid/rbf/interpolant.hpp"
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

}  // namespace
}  // namespace liquid::rbf
