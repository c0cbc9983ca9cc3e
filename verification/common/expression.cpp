#include "expression.hpp"

#include <cmath>

#include <fmt/format.h>
#include <gsl/gsl_deriv.h>

#include "liquid/core/error.hpp"

namespace liquid::verification {

namespace {
template <class F>
double central(F& f, double at, double step, double* abserr) {
  gsl_function g;
  g.function = [](double t, void* p) { return (*static_cast<F*>(p))(t); };
  g.params = &f;
  double result = 0.0, err = 0.0;
  gsl_deriv_central(&g, at, step, &result, &err);
  if (abserr) *abserr = err;
  return result;
}
}  // namespace

template <int Dim>
double Expression<Dim>::derivative(const Vec<Dim>& x, int k, double* abserr) const {
  auto along = [&](double t) {
    Vec<Dim> y = x;
    y[k] = t;
    return (*this)(y);
  };
  return central(along, x[k], 1e-3 * std::max(1.0, std::abs(x[k])), abserr);
}

template <int Dim>
double Expression<Dim>::laplacian(const Vec<Dim>& x, double* abserr) const {
  // GSL has first derivatives only, and nesting them loses 5-6 digits; instead, second central
  // differences at h, h/2, h/4, h/8 with Richardson extrapolation of their h^2, h^4, h^6 terms
  // (exact for polynomials up to degree 9). The error estimate is the last correction.
  double sum = 0.0, err_sum = 0.0;
  for (int k = 0; k < Dim; ++k) {
    const double h0 = 0.05 * std::max(1.0, std::abs(x[k]));
    const double f0 = (*this)(x);
    double table[4][4];
    for (int i = 0; i < 4; ++i) {
      const double h = h0 / (1 << i);
      Vec<Dim> xp = x, xm = x;
      xp[k] += h;
      xm[k] -= h;
      table[i][0] = ((*this)(xp)-2.0 * f0 + (*this)(xm)) / (h * h);
      for (int j = 1; j <= i; ++j) {
        const double factor = std::pow(4.0, j);
        table[i][j] = (factor * table[i][j - 1] - table[i - 1][j - 1]) / (factor - 1.0);
      }
    }
    sum += table[3][3];
    err_sum += std::abs(table[3][3] - table[3][2]) + 1e-14 * std::abs(f0) / (h0 * h0 / 64);
  }
  if (abserr) *abserr = err_sum;
  return sum;
}

template class Expression<2>;
template class Expression<3>;

}  // namespace liquid::verification
