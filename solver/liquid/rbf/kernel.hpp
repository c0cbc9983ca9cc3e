#pragma once
// Polyharmonic spline (PHS) kernels phi(r) = r^s for odd s.
//
// With x the evaluation point, x_j a node and r = |x - x_j|:
//   d phi / d x_k = s * (x - x_j)_k * r^(s-2)
//   Laplacian phi = s * (s + d - 2) * r^(s-2)          (d = space dimension)
// Both follow from d/dr r^s = s r^(s-1), dr/dx_k = (x - x_j)_k / r and, for a radial function,
// Laplacian = phi'' + (d-1)/r phi'. For s = 1 the derivatives are singular at r = 0; the gradient is
// set to 0 there (the symmetric limit) and the Laplacian is reported as infinite so callers can refuse.

#include <cmath>
#include <limits>

#include "liquid/core/error.hpp"

namespace liquid::rbf {

struct Phs {
  int s = 3;  ///< odd exponent: 1, 3, 5, 7 or 9

  explicit Phs(int exponent = 3) : s(exponent) {
    LIQUID_VERIFY(s >= 1 && s <= 9 && s % 2 == 1, "PHS exponent must be odd and in [1, 9], got {}", s);
  }

  /// phi(r) = r^s.
  double value(double r) const { return ipow(r, s); }

  /// s * r^(s-2), the factor that multiplies (x - x_j)_k in the gradient.
  double gradient_factor(double r) const {
    if (s == 1) return r > 0.0 ? 1.0 / r : 0.0;
    return s * ipow(r, s - 2);
  }

  /// Laplacian of phi in `dim` dimensions at distance r.
  double laplacian(double r, int dim) const {
    if (s == 1) return r > 0.0 ? (dim - 1) / r : std::numeric_limits<double>::infinity();
    return s * (s + dim - 2) * ipow(r, s - 2);
  }

 private:
  static double ipow(double r, int n) {
    double out = 1.0;
    for (int i = 0; i < n; ++i) out *= r;
    return out;
  }
};

}  // namespace liquid::rbf
