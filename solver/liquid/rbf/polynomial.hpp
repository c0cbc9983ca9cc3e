#pragma once
// Monomial bases of total degree <= m in Dim dimensions, with their first derivatives and
// Laplacian. Terms are ordered by total degree, then lexicographically (1, x, y, x^2, xy, y^2, ...).

#include <array>
#include <vector>

#include "liquid/core/types.hpp"

namespace liquid::rbf {

/// Number of monomials of total degree <= degree in dim dimensions: C(degree + dim, dim).
int n_polynomial_terms(int dim, int degree);

template <int Dim>
class PolynomialBasis {
 public:
  /// degree in [0, 4]; a negative degree gives the empty basis (pure RBF).
  explicit PolynomialBasis(int degree);

  int degree() const { return degree_; }
  int size() const { return static_cast<int>(exponents_.size()); }
  const std::array<int, Dim>& exponents(int term) const { return exponents_[term]; }

  /// Value of term `term` at x (inline: the transfers evaluate it in their inner loops).
  double value(int term, const Vec<Dim>& x) const {
    double out = 1.0;
    for (int k = 0; k < Dim; ++k) {
      double power = 1.0;
      for (int i = 0; i < exponents_[term][k]; ++i) power *= x[k];
      out *= power;
    }
    return out;
  }
  /// d/dx_k of term `term` at x.
  double derivative(int term, int k, const Vec<Dim>& x) const;
  /// Laplacian of term `term` at x.
  double laplacian(int term, const Vec<Dim>& x) const;

 private:
  int degree_;
  std::vector<std::array<int, Dim>> exponents_;
};

}  // namespace liquid::rbf
