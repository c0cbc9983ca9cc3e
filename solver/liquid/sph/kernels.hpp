#pragma once
// The smoothing kernels of Müller, Charypar and Gross (2003) with support radius r, in 2D and 3D,
// and the surface weight of Adams et al. (2007, Eq. 8). Pointwise functions of the offset x (or its
// length q = |x|); each kernel integrates to 1 over its support.
//
//   poly6      W(q, r) = c (r^2 - q^2)^3                 density
//   spiky      W(q, r) = c (r - q)^3                     pressure (its gradient does not vanish at 0)
//   viscosity  lap W(q, r) = c (r - q)                   viscosity (only the Laplacian is used)
//
// Constants: poly6 315/(64 pi r^9) in 3D, 4/(pi r^8) in 2D; spiky 15/(pi r^6) in 3D, 10/(pi r^5) in 2D;
// the viscosity Laplacian 45/(pi r^6) in 3D, 40/(pi r^5) in 2D. The 2D viscosity kernel is the one
// whose 2D Laplacian is 40/(pi r^5)(r - q), zero with zero slope at q = r and normalised:
//   W = c ((r/4)(q^2 - r^2) - (q^3 - r^3)/9 + (r^3/6) ln(r/q)).

#include <cmath>
#include <numbers>

#include "liquid/core/types.hpp"

namespace liquid::sph {

/// x^n by multiplications (the kernels' constants are on the hot path).
template <int N>
constexpr double ipow(double x) {
  double y = 1.0;
  for (int k = 0; k < N; ++k) y *= x;
  return y;
}

template <int Dim>
struct Kernels {
  static_assert(Dim == 2 || Dim == 3);
  static constexpr double pi = std::numbers::pi;

  static double poly6(double q, double r) {
    if (q >= r) return 0.0;
    const double c = Dim == 3 ? 315.0 / (64.0 * pi * ipow<9>(r)) : 4.0 / (pi * ipow<8>(r));
    const double s = r * r - q * q;
    return c * s * s * s;
  }

  static double spiky(double q, double r) {
    if (q >= r) return 0.0;
    const double c = Dim == 3 ? 15.0 / (pi * ipow<6>(r)) : 10.0 / (pi * ipow<5>(r));
    const double s = r - q;
    return c * s * s * s;
  }

  /// The gradient of the spiky kernel with respect to x, at offset x (zero at x = 0 and beyond r).
  static Vec<Dim> spiky_gradient(const Vec<Dim>& x, double r) {
    return spiky_gradient(x, x.norm(), r, spiky_gradient_constant(r));
  }
  /// The same with q = |x| and the constant c = spiky_gradient_constant(r) given (the force loops
  /// take the square root once per pair and keep c per particle).
  static Vec<Dim> spiky_gradient(const Vec<Dim>& x, double q, double r, double c) {
    if (q >= r || q == 0.0) return Vec<Dim>::Zero();
    const double s = r - q;
    return (-c * s * s / q) * x;
  }

  /// The viscosity kernel itself (for tests; the forces use its Laplacian only). Infinite at q = 0.
  static double viscosity(double q, double r) {
    if (q >= r) return 0.0;
    if constexpr (Dim == 3) {
      const double c = 15.0 / (2.0 * pi * r * r * r);
      return c * (-q * q * q / (2.0 * r * r * r) + q * q / (r * r) + r / (2.0 * q) - 1.0);
    } else {
      const double c = 40.0 / (pi * ipow<5>(r));
      return c * ((r / 4.0) * (q * q - r * r) - (q * q * q - r * r * r) / 9.0 +
                  (r * r * r / 6.0) * std::log(r / q));
    }
  }

  /// Wendland's C2 kernel (Wendland 1995; Dehnen and Aly 2012): sigma (1 - q/r)^4 (1 + 4 q/r), with
  /// sigma = 7 / (pi r^2) in 2D and 21 / (2 pi r^3) in 3D; smooth at 0 and free of the pairing
  /// instability.
  static double wendland(double q, double r) {
    if (q >= r) return 0.0;
    const double c = wendland_constant(r);
    const double t = 1.0 - q / r;
    return c * ipow<4>(t) * (1.0 + 4.0 * q / r);
  }
  static Vec<Dim> wendland_gradient(const Vec<Dim>& x, double r) {
    return wendland_gradient(x, x.norm(), r, wendland_constant(r));
  }
  /// The same with q = |x| and c = wendland_constant(r) given.
  static Vec<Dim> wendland_gradient(const Vec<Dim>& x, double q, double r, double c) {
    if (q >= r) return Vec<Dim>::Zero();
    const double t = 1.0 - q / r;
    return (-20.0 * c * ipow<3>(t) / (r * r)) * x;  // dW/dq = -20 c (q / r^2) (1 - q/r)^3
  }

  static double viscosity_laplacian(double q, double r) {
    return viscosity_laplacian(q, r, viscosity_laplacian_constant(r));
  }
  /// The same with c = viscosity_laplacian_constant(r) given.
  static double viscosity_laplacian(double q, double r, double c) {
    if (q >= r) return 0.0;
    return c * (r - q);
  }

  /// The normalising constants of the Wendland kernel, the spiky gradient and the viscosity
  /// Laplacian at support r.
  static double wendland_constant(double r) {
    return Dim == 3 ? 21.0 / (2.0 * pi * r * r * r) : 7.0 / (pi * r * r);
  }
  static double spiky_gradient_constant(double r) {
    return Dim == 3 ? 45.0 / (pi * ipow<6>(r)) : 30.0 / (pi * ipow<5>(r));
  }
  static double viscosity_laplacian_constant(double r) {
    return Dim == 3 ? 45.0 / (pi * ipow<6>(r)) : 40.0 / (pi * ipow<5>(r));
  }
};

/// The surface weight of Eq. 8: (1 - (q/r)^2)^3 inside the support, 0 outside (not normalised).
inline double surface_weight(double q, double r) {
  if (q >= r) return 0.0;
  const double s = 1.0 - (q * q) / (r * r);
  return s * s * s;
}

/// d/dq of surface_weight.
inline double surface_weight_slope(double q, double r) {
  if (q >= r) return 0.0;
  const double s = 1.0 - (q * q) / (r * r);
  return -6.0 * q * s * s / (r * r);
}

}  // namespace liquid::sph
