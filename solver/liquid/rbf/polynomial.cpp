#include "liquid/rbf/polynomial.hpp"

#include "liquid/core/error.hpp"

namespace liquid::rbf {

namespace {
double ipow(double x, int n) {
  double out = 1.0;
  for (int i = 0; i < n; ++i) out *= x;
  return out;
}
}  // namespace

int n_polynomial_terms(int dim, int degree) {
  if (degree < 0) return 0;
  long num = 1, den = 1;
  for (int i = 1; i <= dim; ++i) {
    num *= degree + i;
    den *= i;
  }
  return static_cast<int>(num / den);
}

template <int Dim>
PolynomialBasis<Dim>::PolynomialBasis(int degree) : degree_(degree) {
  LIQUID_VERIFY(degree <= 4, "polynomial degree must be at most 4, got {}", degree);
  for (int total = 0; total <= degree; ++total) {
    // Enumerate exponent tuples of this total degree, first axis descending.
    if constexpr (Dim == 2) {
      for (int a = total; a >= 0; --a) exponents_.push_back({a, total - a});
    } else {
      for (int a = total; a >= 0; --a)
        for (int b = total - a; b >= 0; --b) exponents_.push_back({a, b, total - a - b});
    }
  }
}

template <int Dim>
double PolynomialBasis<Dim>::derivative(int term, int k, const Vec<Dim>& x) const {
  const auto& e = exponents_[term];
  if (e[k] == 0) return 0.0;
  double out = e[k] * ipow(x[k], e[k] - 1);
  for (int j = 0; j < Dim; ++j)
    if (j != k) out *= ipow(x[j], e[j]);
  return out;
}

template <int Dim>
double PolynomialBasis<Dim>::laplacian(int term, const Vec<Dim>& x) const {
  const auto& e = exponents_[term];
  double out = 0.0;
  for (int k = 0; k < Dim; ++k) {
    if (e[k] < 2) continue;
    double part = e[k] * (e[k] - 1) * ipow(x[k], e[k] - 2);
    for (int j = 0; j < Dim; ++j)
      if (j != k) part *= ipow(x[j], e[j]);
    out += part;
  }
  return out;
}

template class PolynomialBasis<2>;
template class PolynomialBasis<3>;

}  // namespace liquid::rbf
