// RBF-FD weights: polynomial reproduction, agreement with standard FD, and hard stencils.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include <Eigen/SVD>

#include "liquid/core/error.hpp"
#include "liquid/rbf/polynomial.hpp"
#include "liquid/rbf/saddle.hpp"
#include "liquid/rbf/weights.hpp"
#include "support/stencils.hpp"

namespace liquid::rbf {
namespace {

// Largest error of weights applied to every monomial of the used degree, relative to the scale
// of the operator on that stencil (1, 1/h, 1/h^2).
template <int Dim>
double reproduction_error(const std::vector<Vec<Dim>>& nodes, const Vec<Dim>& at, int degree, double h) {
  const PolynomialBasis<Dim> basis(degree);
  const BasisWeights<Dim> bw = basis_weights<Dim>(nodes, at, Config{3, degree});
  EXPECT_TRUE(bw.status.usable()) << bw.status.describe();
  EXPECT_EQ(bw.status.degree_used, degree);
  double worst = 0.0;
  for (int t = 0; t < basis.size(); ++t) {
    // Monomials centred at `at`, scaled by h, so every term is O(1) on the stencil.
    Eigen::VectorXd f(nodes.size());
    for (std::size_t j = 0; j < nodes.size(); ++j) f[j] = basis.value(t, ((nodes[j] - at) / h).eval());
    const Vec<Dim> zero = Vec<Dim>::Zero();
    worst = std::max(worst, std::abs(bw.w.col(0).dot(f) - basis.value(t, zero)));
    for (int k = 0; k < Dim; ++k)
      worst = std::max(worst, h * std::abs(bw.w.col(1 + k).dot(f) - basis.derivative(t, k, zero) / h));
    worst = std::max(worst, h * h * std::abs(bw.w.col(Dim + 1).dot(f) - basis.laplacian(t, zero) / (h * h)));
  }
  return worst;
}

TEST(RbfFdWeights, ReproducePolynomialsOnScatteredStencils2D) {
  for (int m = 0; m <= 4; ++m) {
    const auto nodes = support::jittered_stencil<2>(3, 0.01, 0.35, 7u + m);
    EXPECT_LT(reproduction_error<2>(nodes, Vec<2>(0.002, -0.001), m, 0.01), 1e-9) << "degree " << m;
  }
}

TEST(RbfFdWeights, ReproducePolynomialsOnTJunctionStencils3D) {
  for (int m = 0; m <= 4; ++m) {
    const auto nodes = support::quadtree_stencil<3>(1, 0.05, 11u + m);
    ASSERT_GE(static_cast<int>(nodes.size()), 2 * n_polynomial_terms(3, m));
    EXPECT_LT(reproduction_error<3>(nodes, Vec<3>::Zero(), m, 0.05), 1e-9) << "degree " << m;
  }
}

TEST(RbfFdWeights, FivePointStencilGivesStandardFiniteDifferences) {
  // With degree 1 on a symmetric cross the RBF-FD gradient is the central difference.
  const double h = 0.25;
  const std::vector<Vec<2>> nodes{{0, 0}, {h, 0}, {-h, 0}, {0, h}, {0, -h}};
  std::vector<double> w;
  const Status st = weights<2>(nodes, Vec<2>::Zero(), Operator<2>::partial(0), Config{3, 1}, w);
  ASSERT_TRUE(st.usable());
  EXPECT_NEAR(w[0], 0.0, 1e-12);
  EXPECT_NEAR(w[1], 1.0 / (2 * h), 1e-10);
  EXPECT_NEAR(w[2], -1.0 / (2 * h), 1e-10);
  EXPECT_NEAR(w[3], 0.0, 1e-12);
  EXPECT_NEAR(w[4], 0.0, 1e-12);
}

TEST(RbfFdWeights, LinearCombinationEqualsSumOfParts) {
  const auto nodes = support::quadtree_stencil<2>(2, 0.1, 3u);
  const Vec<2> n(0.6, 0.8);
  const auto op = Operator<2>::lap() * 2.0 + Operator<2>::directional(n) + Operator<2>::identity() * 0.5;
  std::vector<double> w, w_lap, w_dir, w_val;
  const Config c;
  ASSERT_TRUE(weights<2>(nodes, Vec<2>::Zero(), op, c, w).usable());
  ASSERT_TRUE(weights<2>(nodes, Vec<2>::Zero(), Operator<2>::lap(), c, w_lap).usable());
  ASSERT_TRUE(weights<2>(nodes, Vec<2>::Zero(), Operator<2>::directional(n), c, w_dir).usable());
  ASSERT_TRUE(weights<2>(nodes, Vec<2>::Zero(), Operator<2>::identity(), c, w_val).usable());
  for (std::size_t j = 0; j < w.size(); ++j)
    EXPECT_NEAR(w[j], 2 * w_lap[j] + w_dir[j] + 0.5 * w_val[j], 1e-8 * (1 + std::abs(w[j])));
}

TEST(RbfFdWeights, TooFewNodesLowersTheDegree) {
  const std::vector<Vec<2>> nodes{{0, 0}, {1, 0}, {0, 1}, {-1, 0}};  // 4 nodes < 6 quadratic terms
  std::vector<double> w;
  const Status st = weights<2>(nodes, Vec<2>::Zero(), Operator<2>::partial(0), Config{3, 2}, w);
  EXPECT_EQ(st.info, Info::degree_reduced);
  EXPECT_EQ(st.degree_used, 1);
  ASSERT_EQ(w.size(), 4u);
  for (double x : w) EXPECT_TRUE(std::isfinite(x));
}

TEST(RbfFdWeights, CollinearNodesLowerTheDegree) {
  std::vector<Vec<2>> nodes;
  for (int i = -4; i <= 4; ++i) nodes.push_back(Vec<2>(0.1 * i, 0.05 * i));
  std::vector<double> w;
  const Status st = weights<2>(nodes, Vec<2>(0.01, 0.005), Operator<2>::identity(), Config{3, 2}, w);
  EXPECT_EQ(st.info, Info::degree_reduced);
  EXPECT_EQ(st.degree_used, 0);  // a line carries no full linear basis in 2D
  EXPECT_EQ(w.size(), nodes.size());
}

TEST(RbfFdWeights, NearlyCollinearNodesStayFiniteAndReported) {
  std::vector<Vec<2>> nodes;
  for (int i = -5; i <= 5; ++i) nodes.push_back(Vec<2>(0.1 * i, 1e-12 * i * i));
  std::vector<double> w;
  const Status st = weights<2>(nodes, Vec<2>::Zero(), Operator<2>::lap(), Config{3, 2}, w);
  if (st.usable()) {
    EXPECT_LT(st.degree_used, 2);
    for (double x : w) EXPECT_TRUE(std::isfinite(x));
  } else {
    EXPECT_TRUE(w.empty());
  }
}

TEST(RbfFdWeights, CoincidentNodesAreReportedNotSolved) {
  const std::vector<Vec<3>> nodes{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 0}};
  std::vector<double> w;
  const Status st = weights<3>(nodes, Vec<3>::Zero(), Operator<3>::lap(), Config{3, 1}, w);
  EXPECT_EQ(st.info, Info::coincident_nodes);
  EXPECT_EQ(st.node_a, 1);
  EXPECT_EQ(st.node_b, 4);
  EXPECT_TRUE(w.empty());
  EXPECT_NE(st.describe().find("nodes 1 and 4"), std::string::npos);
}

TEST(RbfFdWeights, EmptyAndNonFiniteInputAreReported) {
  std::vector<double> w;
  EXPECT_EQ(weights<2>({}, Vec<2>::Zero(), Operator<2>::lap(), Config{}, w).info, Info::empty_stencil);
  const std::vector<Vec<2>> bad{{0, 0}, {std::numeric_limits<double>::quiet_NaN(), 0}, {0, 1}};
  EXPECT_EQ(weights<2>(bad, Vec<2>::Zero(), Operator<2>::lap(), Config{}, w).info, Info::non_finite);
  EXPECT_TRUE(w.empty());
}

TEST(RbfFdWeights, UnusableWeightsThrowWhenCombined) {
  BasisWeights<2> bw;
  bw.status.info = Info::singular_system;
  std::vector<double> out;
  EXPECT_THROW(bw.combine(Operator<2>::lap(), out), Error);
}

TEST(RbfFdWeights, PhsOneRefusesLaplacianAtANode) {
  const auto nodes = support::jittered_stencil<2>(2, 0.1, 0.3, 5u);
  std::vector<double> w;
  EXPECT_FALSE(weights<2>(nodes, Vec<2>::Zero(), Operator<2>::lap(), Config{1, 1}, w).usable());
  EXPECT_TRUE(weights<2>(nodes, Vec<2>::Zero(), Operator<2>::partial(1), Config{1, 1}, w).usable());
}

}  // namespace
}  // namespace liquid::rbf

namespace liquid::rbf {
namespace {

// The saddle system's condition estimate (LU, 1-norm) tracks the true 2-norm condition number
// within the factor n that separates the two norms, and a system past Config::max_condition is
// refused: a pair of nodes 1e-7 R apart (above the coincidence test) makes K nearly singular.
TEST(RbfFdWeights, ConditionEstimateTracksTheTrueOneAndRefusesNearSingularSystems) {
  for (int m : {1, 2, 3}) {
    auto nodes = support::jittered_stencil<2>(3, 0.1, 0.3, 11u + m);
    std::vector<Vec<2>> unit(nodes.size());
    double radius = 0.0;
    for (const auto& x : nodes) radius = std::max(radius, x.norm());
    for (std::size_t j = 0; j < nodes.size(); ++j) unit[j] = nodes[j] / radius;
    const detail::SaddleSystem<2> system(unit, Config{3, m});
    ASSERT_TRUE(system.status.usable()) << system.status.describe();
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(system.matrix);
    const auto& s = svd.singularValues();
    const double exact = s(0) / s(s.size() - 1);
    const double n = static_cast<double>(system.matrix.rows());
    EXPECT_GT(system.status.condition, exact / n) << "degree " << m;
    EXPECT_LT(system.status.condition, exact * n) << "degree " << m;

    nodes.push_back(nodes[3] + Vec<2>(1e-7 * radius, 0.0));
    std::vector<double> w;
    const Status near = weights<2>(nodes, Vec<2>::Zero(), Operator<2>::lap(), Config{3, m}, w);
    EXPECT_EQ(near.info, Info::singular_system) << near.describe();
    EXPECT_TRUE(w.empty());
    Config strict{3, m};
    strict.max_condition = 0.5 * system.status.condition;
    nodes.pop_back();
    EXPECT_EQ(weights<2>(nodes, Vec<2>::Zero(), Operator<2>::lap(), strict, w).info, Info::singular_system);

    // An exactly repeated node, with the coincidence test switched off, makes K singular (two equal
    // rows): a zero pivot must read as refused, not as NaN weights.
    Config no_coincidence{3, m};
    no_coincidence.coincidence_tolerance = 0.0;
    nodes.push_back(nodes[3]);
    EXPECT_EQ(weights<2>(nodes, Vec<2>::Zero(), Operator<2>::lap(), no_coincidence, w).info,
              Info::singular_system);
    EXPECT_TRUE(w.empty());
  }
}

// The two-probe estimate is the start of the full one: not above it (but for rounding; these
// stencils are well conditioned, so 1e-12 covers it), on these stencils within a
// factor 10 of it (7.6 at worst, measured) and above the true 2-norm condition over n; it refuses the same
// near-singular systems, and accepting a system leaves its weights untouched (the estimate decides nothing
// else).
TEST(RbfFdWeights, ProbeConditionEstimateBoundsTheFullOneAndRefusesTheSameSystems) {
  Config probes{5, 2};
  probes.condition_estimate = ConditionEstimate::probes;
  int lower = 0;  // stencils where the probes alone see less than the ascent
  for (unsigned seed = 1; seed <= 12; ++seed) {
    auto nodes = support::jittered_stencil<3>(1, 0.2 + 0.02 * seed, 0.3, 40u + seed);
    std::vector<Vec<3>> unit(nodes.size());
    double radius = 0.0;
    for (const auto& x : nodes) radius = std::max(radius, x.norm());
    for (std::size_t j = 0; j < nodes.size(); ++j) unit[j] = nodes[j] / radius;
    const detail::SaddleSystem<3> full(unit, Config{5, 2});
    const detail::SaddleSystem<3> cheap(unit, probes);
    ASSERT_TRUE(full.status.usable() && cheap.status.usable()) << cheap.status.describe();
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(full.matrix);
    const auto& s = svd.singularValues();
    const double exact = s(0) / s(s.size() - 1);
    const double n = static_cast<double>(full.matrix.rows());
    EXPECT_LE(cheap.status.condition, full.status.condition * (1.0 + 1e-12)) << "seed " << seed;
    EXPECT_GT(cheap.status.condition, full.status.condition / 10.0) << "seed " << seed;
    EXPECT_GT(cheap.status.condition, exact / n) << "seed " << seed;
    if (cheap.status.condition < full.status.condition * (1.0 - 1e-9)) ++lower;

    std::vector<double> a, b;
    const Vec<3> at(0.05, -0.1, 0.02);
    ASSERT_TRUE(value_weights<3>(nodes, at, Config{5, 2}, a).usable());
    ASSERT_TRUE(value_weights<3>(nodes, at, probes, b).usable());
    EXPECT_EQ(a, b) << "seed " << seed;

    nodes.push_back(nodes[2] + Vec<3>(1e-7 * radius, 0.0, 0.0));
    EXPECT_EQ(value_weights<3>(nodes, at, Config{5, 2}, a).info, Info::singular_system);
    EXPECT_EQ(value_weights<3>(nodes, at, probes, b).info, Info::singular_system) << "seed " << seed;
    Config exact_copy = probes;
    exact_copy.coincidence_tolerance = 0.0;
    nodes.back() = nodes[2];
    EXPECT_EQ(value_weights<3>(nodes, at, exact_copy, b).info, Info::singular_system) << "seed " << seed;
    EXPECT_TRUE(b.empty());
  }
  EXPECT_GT(lower, 0) << "the probe estimate is never cheaper than the full one: is the option read?";
}

TEST(RbfFdWeights, ValueWeightsEqualTheIdentityColumn) {
  for (int degree : {0, 1, 2, 3}) {
    const auto nodes = support::jittered_stencil<3>(1, 0.3, 0.25, 5u + degree);
    const Vec<3> at(0.11, -0.07, 0.2);
    std::vector<double> a, b;
    const Config config{5, degree};
    const Status sa = weights<3>(nodes, at, Operator<3>::identity(), config, a);
    const Status sb = value_weights<3>(nodes, at, config, b);
    ASSERT_TRUE(sa.usable() && sb.usable());
    EXPECT_EQ(sa.degree_used, sb.degree_used);
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t j = 0; j < a.size(); ++j) EXPECT_NEAR(a[j], b[j], 1e-12);
  }
  // Up to 48 unknowns (the rows above: 28 to 47) value_weights factorises on the stack; past them
  // (125 nodes) it takes the saddle system's LU. Both are the identity column.
  {
    const auto nodes = support::jittered_stencil<3>(2, 0.3, 0.25, 17u);
    const Vec<3> at(0.11, -0.07, 0.2);
    std::vector<double> a, b;
    const Config config{3, 1};
    ASSERT_TRUE(weights<3>(nodes, at, Operator<3>::identity(), config, a).usable());
    ASSERT_TRUE(value_weights<3>(nodes, at, config, b).usable());
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t j = 0; j < a.size(); ++j) EXPECT_NEAR(a[j], b[j], 1e-12);
  }
  std::vector<double> w;
  EXPECT_EQ(value_weights<2>({}, Vec<2>::Zero(), Config{5, 2}, w).info, Info::empty_stencil);
  EXPECT_TRUE(w.empty());
}

}  // namespace
}  // namespace liquid::rbf
