// User expressions: parsing errors name the position; numerical derivatives and Laplacian are
// accurate far below the discretisation errors the studies measure (1e-6 and up).
#include <gtest/gtest.h>

#include <cmath>

#include "common/expression.hpp"
#include "liquid/core/error.hpp"

namespace liquid::verification {
namespace {

TEST(Expression, EvaluatesAndDifferentiates2D) {
  const Expression<2> p("cos(x)*cos(y) - 1", "--exact");
  double worst_lap = 0.0, worst_grad = 0.0, worst_estimate = 0.0;
  for (double x : {0.1, 0.9, 1.7, 2.9})
    for (double y : {0.2, 1.3, 3.0}) {
      const Vec<2> at(x, y);
      EXPECT_NEAR(p(at), std::cos(x) * std::cos(y) - 1, 1e-15);
      worst_grad = std::max(worst_grad, std::abs(p.derivative(at, 0) + std::sin(x) * std::cos(y)));
      worst_grad = std::max(worst_grad, std::abs(p.derivative(at, 1) + std::cos(x) * std::sin(y)));
      double estimate = 0.0;
      worst_lap = std::max(worst_lap, std::abs(p.laplacian(at, &estimate) + 2 * std::cos(x) * std::cos(y)));
      worst_estimate = std::max(worst_estimate, estimate);
    }
  EXPECT_LT(worst_grad, 1e-9);
  EXPECT_LT(worst_lap, 1e-8);
  EXPECT_GE(worst_estimate, worst_lap);  // the reported estimate is an upper bound here
}

TEST(Expression, LaplacianOfThePapersDirichletSolution3D) {
  const Expression<3> p("(z - x^2 - y^2 + 1)^4 + x^2 + y^2 + z^2 - 1", "--exact");
  for (const Vec<3>& at : {Vec<3>(0.3, -0.2, 0.1), Vec<3>(-1.1, 0.4, -0.9)}) {
    const double u = at[2] - at[0] * at[0] - at[1] * at[1] + 1;
    const double lap = 48 * (at[0] * at[0] + at[1] * at[1]) * u * u - 16 * u * u * u + 12 * u * u + 6;
    EXPECT_NEAR(p.laplacian(at), lap, 1e-8 * (1 + std::abs(lap)));
  }
}

TEST(Expression, ErrorsNameThePosition) {
  try {
    Expression<2> bad("sin(x*", "--exact");
    FAIL() << "no error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("--exact"), std::string::npos);
    EXPECT_NE(what.find("position"), std::string::npos);
  }
  EXPECT_THROW(Expression<2>("x + z", "--levelset"), Error);  // z is not a 2D variable
}

}  // namespace
}  // namespace liquid::verification
