#pragma once
// Particle advection through a velocity field (any callable u(x) -> Vec<Dim>, e.g. an interpolant of
// the face velocities), with RK2 (midpoint) or RK3 (Ralston's third-order scheme, as in Bridson's
// "Fluid Simulation for Computer Graphics"). After each move a particle is clamped onto the domain
// (inset by a hair, so that it stays in a leaf) and pushed out of the solid along the gradient of
// the solid's signed distance.

#include <cmath>
#include <cstdint>
#include <span>

#include "liquid/core/error.hpp"
#include "liquid/core/parallel.hpp"
#include "liquid/core/types.hpp"
#include "liquid/levelset/levelset.hpp"

namespace liquid::particles {

enum class Integrator { rk2, rk3 };
const char* to_string(Integrator integrator);

struct AdvectReport {
  long clamped = 0;  ///< particles moved back onto the domain
  long pushed = 0;   ///< particles pushed out of the solid
  long stuck = 0;    ///< particles still inside the solid after the pushes (φ < 0)
};

namespace detail {
/// Moves x out of the solid (phi < 0) along phi's gradient (central differences with step `eps`).
/// Returns 0 when x was outside, 1 when it was pushed out, 2 when it is still inside.
template <int Dim>
int push_out(const levelset::Function<Dim>& solid, double eps, Vec<Dim>& x) {
  double phi = solid(x);
  if (phi >= 0.0) return 0;
  for (int iteration = 0; iteration < 4 && phi < 0.0; ++iteration) {
    Vec<Dim> g;
    for (int k = 0; k < Dim; ++k) {
      Vec<Dim> a = x, b = x;
      a[k] -= eps, b[k] += eps;
      g[k] = (solid(b) - solid(a)) / (2 * eps);
    }
    const double n = g.norm();
    if (!(n > 0.0) || !std::isfinite(n)) break;
    x -= (phi - eps) * g / n;
    phi = solid(x);
  }
  return phi >= 0.0 ? 1 : 2;
}
}  // namespace detail

/// Advances every position by dt through `u` (called from several threads at once) and returns what
/// the boundary treatment did. `solid` may be empty (no solid). Throws naming the particle when a
/// position or a velocity is not finite. `order` (optional, a permutation of the positions, e.g.
/// CellBins::index) is the order the positions are visited in: each moves on its own, so the result
/// is the same in any order, and an order that keeps a cell's particles together reads each cell's
/// velocity data once rather than once per particle.
template <int Dim, class Velocity>
AdvectReport advect(std::span<Vec<Dim>> x, double dt, Integrator integrator, const Velocity& u,
                    const Box<Dim>& domain, const levelset::Function<Dim>& solid = {},
                    std::span<const std::int32_t> order = {}) {
  LIQUID_VERIFY(std::isfinite(dt) && dt >= 0.0, "advect: time step {} is not a finite non-negative number",
                dt);
  LIQUID_VERIFY(order.empty() || order.size() == x.size(), "advect: an order of {} for {} positions",
                order.size(), x.size());
  const double margin = 1e-9 * domain.size().maxCoeff();
  const double eps = 1e-6 * domain.size().maxCoeff();
  AdvectReport total;
  parallel_for(
      static_cast<long>(x.size()), [] { return AdvectReport{}; },
      [&](AdvectReport& r, long visit) {
        const long i = order.empty() ? visit : order[visit];
        Vec<Dim> p = x[i];
        const Vec<Dim> k1 = u(p);
        Vec<Dim> step;
        if (integrator == Integrator::rk2) {
          step = u(Vec<Dim>(p + 0.5 * dt * k1));
        } else {
          const Vec<Dim> k2 = u(Vec<Dim>(p + 0.5 * dt * k1));
          const Vec<Dim> k3 = u(Vec<Dim>(p + 0.75 * dt * k2));
          step = (2.0 / 9.0) * k1 + (3.0 / 9.0) * k2 + (4.0 / 9.0) * k3;
        }
        p += dt * step;
        LIQUID_VERIFY(p.allFinite(), "advect: particle {} reached a non-finite position (velocity ({}))", i,
                      fmt::join(step.data(), step.data() + Dim, ", "));
        const Vec<Dim> lo = domain.lo.array() + margin, hi = domain.hi.array() - margin;
        const Vec<Dim> q = p.cwiseMax(lo).cwiseMin(hi);
        if (q != p) ++r.clamped;
        p = q;
        if (solid) {
          const int pushed = detail::push_out(solid, eps, p);
          if (pushed > 0) {
            ++r.pushed;
            p = p.cwiseMax(lo).cwiseMin(hi);
          }
          if (pushed == 2) ++r.stuck;
        }
        x[i] = p;
      },
      [&](AdvectReport& r) {
        total.clamped += r.clamped;
        total.pushed += r.pushed;
        total.stuck += r.stuck;
      },
      512);
  return total;
}

}  // namespace liquid::particles
