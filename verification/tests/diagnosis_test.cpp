// The order diagnosis of a Poisson study: each kind is reached from rows built to show it, and a
// study that converges is not flagged. The rows are synthetic (errors chosen per h), so each rule is
// tested alone.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "studies/poisson_study.hpp"

namespace liquid::verification {
namespace {

/// Rows at h = 2^-4 ... with errors c h^q_k between consecutive rows (q given per step).
std::vector<PoissonRun> rows_with_steps(const std::vector<double>& steps, double e0 = 1e-2) {
  std::vector<PoissonRun> runs;
  double h = 1.0 / 16, e = e0;
  for (std::size_t k = 0; k <= steps.size(); ++k) {
    PoissonRun r;
    r.h = h, r.err_p = e, r.err_grad = 10 * e, r.algebraic_share = 1e-4;
    r.p_scale = 1.0, r.grad_scale = 1.0;
    r.err_by_level = {{4 + int(k), 100, e}};
    r.worst_p = "cell 7", r.worst_grad = "face 9";
    runs.push_back(r);
    if (k < steps.size()) h /= 2, e /= std::pow(2.0, steps[k]);
  }
  return runs;
}

std::vector<int> levels_of(const std::vector<PoissonRun>& runs) {
  std::vector<int> levels;
  for (std::size_t k = 0; k < runs.size(); ++k) levels.push_back(4 + int(k));
  return levels;
}

OrderDiagnosis diagnose(const std::vector<PoissonRun>& runs) {
  return diagnose_orders(levels_of(runs), runs, kSchemeOrderFloor, kSchemeGradOrderFloor, 0.01);
}

TEST(OrderDiagnosis, SecondOrderRowsConverge) {
  const OrderDiagnosis d = diagnose(rows_with_steps({2.0, 2.02, 1.98}));
  EXPECT_EQ(d.p_kind, "converges");
  EXPECT_EQ(d.grad_kind, "converges");
}

TEST(OrderDiagnosis, SettledLowStepOrdersAreALossOfOrderNamingWhere) {
  const OrderDiagnosis d = diagnose(rows_with_steps({1.9, 1.18, 1.07}));
  EXPECT_EQ(d.p_kind, "loss-of-order");
  EXPECT_NE(d.p.find("cell level 7"), std::string::npos) << d.p;
  EXPECT_NE(d.grad.find("face 9"), std::string::npos) << d.grad;
}

TEST(OrderDiagnosis, StillChangingStepOrdersArePreAsymptotic) {
  const OrderDiagnosis d = diagnose(rows_with_steps({0.8, 1.2, 1.7}));
  EXPECT_EQ(d.p_kind, "pre-asymptotic");
  EXPECT_NE(d.p.find("--levels 4:8"), std::string::npos) << d.p;
}

TEST(OrderDiagnosis, AFinalDropIsNotCalledConverged) {
  // The fit over all rows clears 1.8, the last step does not: not "converges".
  const OrderDiagnosis d = diagnose(rows_with_steps({2.2, 2.2, 2.2, 1.1}));
  EXPECT_NE(d.p_kind, "converges");
}

TEST(OrderDiagnosis, StepOrdersCrossingTheFloorAreNotYetALoss) {
  EXPECT_EQ(diagnose(rows_with_steps({1.87, 1.69})).p_kind, "pre-asymptotic");
  EXPECT_EQ(diagnose(rows_with_steps({1.69, 1.87})).p_kind, "pre-asymptotic");
  EXPECT_EQ(diagnose(rows_with_steps({1.75, 1.7, 1.65})).p_kind, "loss-of-order");
}

TEST(OrderDiagnosis, ACoarseRowFarFromTheAsymptoticRangeDoesNotHideConvergence) {
  // The fit over all rows is 1.71; over the three finest it is 2.05.
  EXPECT_EQ(diagnose(rows_with_steps({-0.36, 2.0, 2.11, 2.07, 2.04})).p_kind, "converges");
}

TEST(OrderDiagnosis, OrdersFarAboveTheSchemeAreFlagged) {
  const OrderDiagnosis d = diagnose(rows_with_steps({2.2, 3.0, 4.0}));
  EXPECT_EQ(d.p_kind, "above-order");
}

TEST(OrderDiagnosis, ALargeAlgebraicShareComesFirst) {
  auto runs = rows_with_steps({2.0, 2.0, 2.0});
  runs.back().algebraic_share = 0.2;
  const OrderDiagnosis d = diagnose(runs);
  EXPECT_EQ(d.p_kind, "algebraic");
  EXPECT_NE(d.p.find("level 7"), std::string::npos) << d.p;
}

TEST(OrderDiagnosis, ASolveThatNoLongerImprovesIsRoundoffNotAlgebraic) {
  auto runs = rows_with_steps({2.0, 2.0, 2.0});
  runs.back().algebraic_share = 0.2;
  runs.back().solve_at_roundoff = true;
  EXPECT_EQ(diagnose(runs).p_kind, "round-off");
}

TEST(OrderDiagnosis, ErrorsAtTheRoundoffFloor) {
  // 2e-9 and flat: above the exact level 1e-9 absolute, below 1e-8 of |p| = 1.
  auto runs = rows_with_steps({2.0, 0.1}, 8e-9);
  const OrderDiagnosis d = diagnose(runs);
  EXPECT_EQ(d.p_kind, "round-off");
  for (auto& r : runs) r.err_p = r.err_grad = 1e-12;
  EXPECT_EQ(diagnose(runs).p_kind, "exact");
}

TEST(OrderDiagnosis, TwoRowsCannotTellALossFromAPreAsymptoticStudy) {
  EXPECT_EQ(diagnose(rows_with_steps({1.2})).p_kind, "too-few-rows");
  EXPECT_EQ(diagnose(rows_with_steps({1.79, 1.76})).p_kind, "too-few-rows");  // a loss needs three steps
  EXPECT_EQ(diagnose(rows_with_steps({2.0})).p_kind, "converges");
}

}  // namespace
}  // namespace liquid::verification
