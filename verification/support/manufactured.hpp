#pragma once
// Manufactured solutions of Lap p = f, shared by the unit tests, the verification cases and the
// benchmarks: each is p, its gradient and its Laplacian in closed form, stated once here.

#include <cmath>
#include <functional>
#include <numbers>

#include "liquid/core/types.hpp"

namespace liquid::support {

template <int Dim>
struct Manufactured {
  std::function<double(const Vec<Dim>&)> p;
  std::function<Vec<Dim>(const Vec<Dim>&)> gradient;
  std::function<double(const Vec<Dim>&)> laplacian;  ///< f = Lap p
};

/// p = prod_k cos x_k - 1 (paper Figs. 14-15): dp/dn = 0 on the walls of [0, pi]^Dim, f = -Dim (p + 1).
template <int Dim>
Manufactured<Dim> cosine_product() {
  const auto prod = [](const Vec<Dim>& x) {
    double p = 1.0;
    for (int k = 0; k < Dim; ++k) p *= std::cos(x[k]);
    return p;
  };
  return {[prod](const Vec<Dim>& x) { return prod(x) - 1.0; },
          [](const Vec<Dim>& x) {
            Vec<Dim> g;
            for (int k = 0; k < Dim; ++k) {
              g[k] = -std::sin(x[k]);
              for (int j = 0; j < Dim; ++j)
                if (j != k) g[k] *= std::cos(x[j]);
            }
            return g;
          },
          [prod](const Vec<Dim>& x) { return -Dim * prod(x); }};
}

/// p = cos x - 1 (no dependence on the other axes): Neumann on the walls of any box whose x-extent
/// is [0, pi].
template <int Dim>
Manufactured<Dim> cosine_x() {
  return {[](const Vec<Dim>& x) { return std::cos(x[0]) - 1.0; },
          [](const Vec<Dim>& x) {
            Vec<Dim> g = Vec<Dim>::Zero();
            g[0] = -std::sin(x[0]);
            return g;
          },
          [](const Vec<Dim>& x) { return -std::cos(x[0]); }};
}

/// p = (z - r^2 + 1)^4 + |x|^2 - 1 with r^2 the squared distance off the last axis z (paper Fig. 17
/// in 2D): its zero set is the Dirichlet interface of the level-set studies. With u = z - r^2 + 1,
/// f = 48 r^2 u^2 - 8 (Dim - 1) u^3 + 12 u^2 + 2 Dim.
template <int Dim>
Manufactured<Dim> quartic_bowl() {
  constexpr int z = Dim - 1;
  const auto radial = [](const Vec<Dim>& x) {
    double r = 0.0;
    for (int k = 0; k < z; ++k) r += x[k] * x[k];
    return r;
  };
  return {[radial](const Vec<Dim>& x) {
            const double u = x[z] - radial(x) + 1.0;
            return u * u * u * u + x.squaredNorm() - 1.0;
          },
          [radial](const Vec<Dim>& x) {
            const double u = x[z] - radial(x) + 1.0;
            Vec<Dim> g;
            for (int k = 0; k < z; ++k) g[k] = -8.0 * x[k] * u * u * u + 2.0 * x[k];
            g[z] = 4.0 * u * u * u + 2.0 * x[z];
            return g;
          },
          [radial](const Vec<Dim>& x) {
            const double u = x[z] - radial(x) + 1.0;
            return 48.0 * radial(x) * u * u - 8.0 * (Dim - 1) * u * u * u + 12.0 * u * u + 2.0 * Dim;
          }};
}

/// p = exp(x) sin(y) + 1: harmonic (f = 0).
inline Manufactured<2> exp_sin() {
  return {[](const Vec<2>& x) { return std::exp(x[0]) * std::sin(x[1]) + 1.0; },
          [](const Vec<2>& x) {
            return Vec<2>(std::exp(x[0]) * std::sin(x[1]), std::exp(x[0]) * std::cos(x[1]));
          },
          [](const Vec<2>&) { return 0.0; }};
}

/// p = tanh(d / eps) with d = |x - centre| - radius, the signed distance to a circle (sphere): a
/// layer of width about eps along the interface, flat (|p| -> 1) away from it. With t = tanh(d/eps),
/// p' = (1 - t^2) / eps, p'' = -2 t (1 - t^2) / eps^2 along d, and Lap p = p'' + (Dim - 1) p' / r.
template <int Dim>
Manufactured<Dim> tanh_layer(const Vec<Dim>& centre, double radius, double eps) {
  return {[=](const Vec<Dim>& x) { return std::tanh(((x - centre).norm() - radius) / eps); },
          [=](const Vec<Dim>& x) -> Vec<Dim> {
            const double r = (x - centre).norm();
            if (r == 0.0) return Vec<Dim>::Zero();
            const double t = std::tanh((r - radius) / eps);
            return (1.0 - t * t) / eps * (x - centre) / r;
          },
          [=](const Vec<Dim>& x) {
            const double r = std::max((x - centre).norm(), 1e-300);
            const double t = std::tanh((r - radius) / eps);
            const double d1 = (1.0 - t * t) / eps;
            return -2.0 * t * d1 / eps + (Dim - 1) * d1 / r;
          }};
}

}  // namespace liquid::support
