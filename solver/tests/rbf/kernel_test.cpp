// PHS kernels and polynomial bases against central finite differences of their values.
#include <gtest/gtest.h>

#include "liquid/rbf/kernel.hpp"
#include "liquid/rbf/polynomial.hpp"

namespace liquid::rbf {
namespace {

template <int Dim>
double phs_at(const Phs& k, const Vec<Dim>& x) {
  return k.value(x.norm());
}

template <int Dim>
void check_kernel_derivatives(int s) {
  const Phs kernel(s);
  Vec<Dim> x;
  for (int k = 0; k < Dim; ++k) x[k] = 0.3 + 0.17 * k;
  const double e = 1e-4;
  double lap_fd = 0.0;
  for (int k = 0; k < Dim; ++k) {
    Vec<Dim> xp = x, xm = x, xpp = x, xmm = x;
    xp[k] += e;
    xm[k] -= e;
    xpp[k] += 2 * e;
    xmm[k] -= 2 * e;
    // Fourth-order central difference, so the reference's own error is far below the tolerance.
    const double d_fd = (-phs_at<Dim>(kernel, xpp) + 8 * phs_at<Dim>(kernel, xp) -
                         8 * phs_at<Dim>(kernel, xm) + phs_at<Dim>(kernel, xmm)) /
                        (12 * e);
    EXPECT_NEAR(kernel.gradient_factor(x.norm()) * x[k], d_fd, 1e-9) << "s=" << s << " k=" << k;
    lap_fd += (phs_at<Dim>(kernel, xp) - 2 * phs_at<Dim>(kernel, x) + phs_at<Dim>(kernel, xm)) / (e * e);
  }
  EXPECT_NEAR(kernel.laplacian(x.norm(), Dim), lap_fd, 1e-5) << "s=" << s;
}

TEST(PhsKernel, DerivativesMatchFiniteDifferences2D) {
  for (int s : {1, 3, 5, 7, 9}) check_kernel_derivatives<2>(s);
}

TEST(PhsKernel, DerivativesMatchFiniteDifferences3D) {
  for (int s : {1, 3, 5, 7, 9}) check_kernel_derivatives<3>(s);
}

TEST(PhsKernel, RejectsEvenOrOutOfRangeExponents) {
  EXPECT_THROW(Phs(2), Error);
  EXPECT_THROW(Phs(11), Error);
  EXPECT_THROW(Phs(-1), Error);
}

TEST(PhsKernel, OriginIsRegularForSAtLeastThree) {
  EXPECT_EQ(Phs(3).laplacian(0.0, 2), 0.0);
  EXPECT_EQ(Phs(3).gradient_factor(0.0), 0.0);
  EXPECT_TRUE(std::isinf(Phs(1).laplacian(0.0, 3)));
}

TEST(PolynomialBasis, TermCounts) {
  const int expected2[] = {1, 3, 6, 10, 15};
  const int expected3[] = {1, 4, 10, 20, 35};
  for (int m = 0; m <= 4; ++m) {
    EXPECT_EQ(PolynomialBasis<2>(m).size(), expected2[m]);
    EXPECT_EQ(PolynomialBasis<3>(m).size(), expected3[m]);
    EXPECT_EQ(n_polynomial_terms(2, m), expected2[m]);
    EXPECT_EQ(n_polynomial_terms(3, m), expected3[m]);
  }
  EXPECT_EQ(PolynomialBasis<2>(-1).size(), 0);
  EXPECT_THROW(PolynomialBasis<2>(5), Error);
}

template <int Dim>
void check_basis_derivatives() {
  const PolynomialBasis<Dim> basis(4);
  Vec<Dim> x;
  for (int k = 0; k < Dim; ++k) x[k] = 0.7 - 0.4 * k;
  const double e = 1e-4;
  for (int t = 0; t < basis.size(); ++t) {
    double lap_fd = 0.0;
    for (int k = 0; k < Dim; ++k) {
      Vec<Dim> xp = x, xm = x;
      xp[k] += e;
      xm[k] -= e;
      EXPECT_NEAR(basis.derivative(t, k, x), (basis.value(t, xp) - basis.value(t, xm)) / (2 * e), 1e-7);
      lap_fd += (basis.value(t, xp) - 2 * basis.value(t, x) + basis.value(t, xm)) / (e * e);
    }
    EXPECT_NEAR(basis.laplacian(t, x), lap_fd, 1e-5) << "term " << t;
  }
}

TEST(PolynomialBasis, DerivativesMatchFiniteDifferences) {
  check_basis_derivatives<2>();
  check_basis_derivatives<3>();
}

TEST(PolynomialBasis, TermsAreOrderedByDegree) {
  const PolynomialBasis<3> basis(3);
  int last = 0;
  for (int t = 0; t < basis.size(); ++t) {
    const auto& e = basis.exponents(t);
    const int total = e[0] + e[1] + e[2];
    EXPECT_GE(total, last);
    last = total;
  }
}

}  // namespace
}  // namespace liquid::rbf
