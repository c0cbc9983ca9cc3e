#include "liquid/sph/boundary.hpp"

#include <array>
#include <cmath>
#include <limits>
#include <numbers>

#include "liquid/sph/forces.hpp"
#include "liquid/sph/kernels.hpp"

namespace liquid::sph {

namespace {

constexpr int kTable = 1024;

/// A kernel integrated over the plane at height z (unit support): the line |x| < sqrt(1 - z^2) in
/// 2D, the disk of that radius in 3D, by the midpoint rule.
template <int Dim, class W>
double plane_integral(W w, double z) {
  const double half = std::sqrt(std::max(0.0, 1.0 - z * z));
  const int n = 2000;
  double sum = 0.0;
  for (int k = 0; k < n; ++k) {
    const double t = (k + 0.5) * half / n;
    sum += Dim == 2 ? 2.0 * w(std::hypot(t, z)) : 2.0 * std::numbers::pi * t * w(std::hypot(t, z));
  }
  return sum * half / n;
}

/// Tables of (mass beyond delta, mass on the plane at delta) for delta = k / (kTable - 1), one pair per
/// density kernel (indexed by KernelSet).
template <int Dim>
struct Tables {
  std::array<std::array<double, kTable>, 3> beyond{}, plane{};
  Tables() {
    for (KernelSet set : {KernelSet::wendland, KernelSet::spiky, KernelSet::mueller}) {
      FluidConstants fluid;
      fluid.kernels = set;
      auto w = [&](double q) { return density_kernel<Dim>(fluid, q, 1.0); };
      auto& on = plane[static_cast<int>(set)];
      auto& out = beyond[static_cast<int>(set)];
      for (int k = 0; k < kTable; ++k) on[k] = plane_integral<Dim>(w, static_cast<double>(k) / (kTable - 1));
      // Cumulative trapezoid from delta = 1 (nothing beyond) down to 0.
      const double dz = 1.0 / (kTable - 1);
      for (int k = kTable - 2; k >= 0; --k) out[k] = out[k + 1] + 0.5 * dz * (on[k] + on[k + 1]);
    }
  }
  static const Tables& get() {
    static const Tables tables;
    return tables;
  }
};

double lookup(const std::array<double, kTable>& table, double delta) {
  if (delta >= 1.0) return 0.0;
  if (delta <= 0.0) return table[0];
  const double u = delta * (kTable - 1);
  const int k = std::min(static_cast<int>(u), kTable - 2);
  const double f = u - k;
  return (1.0 - f) * table[k] + f * table[k + 1];
}

}  // namespace

template <int Dim>
Boundary<Dim>::Boundary(const Box<Dim>& container, std::vector<levelset::Function<Dim>> obstacles)
    : container_(container), has_container_(true), obstacles_(std::move(obstacles)) {
  Tables<Dim>::get();
}

template <int Dim>
double Boundary<Dim>::beyond(KernelSet kernels, double delta) {
  return lookup(Tables<Dim>::get().beyond[static_cast<int>(kernels)], delta);
}
template <int Dim>
double Boundary<Dim>::on_plane(KernelSet kernels, double delta) {
  return lookup(Tables<Dim>::get().plane[static_cast<int>(kernels)], delta);
}

template <int Dim>
template <class F>
void Boundary<Dim>::for_each_wall(const Vec<Dim>& x, double r, F f) const {
  if (has_container_)
    for (int d = 0; d < Dim; ++d) {
      const double lo = x[d] - container_.lo[d], hi = container_.hi[d] - x[d];
      if (lo < r) f(std::max(0.0, lo), Vec<Dim>(Vec<Dim>::Unit(d)));
      if (hi < r) f(std::max(0.0, hi), Vec<Dim>(-Vec<Dim>::Unit(d)));
    }
  for (const auto& obstacle : obstacles_) {
    const double phi = obstacle(x);
    if (phi >= r) continue;
    const Vec<Dim> g = levelset::gradient(obstacle, x, 1e-6 * r);
    const double gn = g.norm();
    if (gn > 0.0) f(std::max(0.0, phi), Vec<Dim>(g / gn));
  }
}

template <int Dim>
double Boundary<Dim>::nearest(const Vec<Dim>& x, double reach, Vec<Dim>* closest) const {
  double best = std::numeric_limits<double>::infinity();
  for_each_wall(x, reach, [&](double distance, const Vec<Dim>& normal) {
    if (!(distance < best)) return;
    best = distance;
    if (closest) *closest = x - distance * normal;  // the normal points into the liquid
  });
  return best;
}

template <int Dim>
double Boundary<Dim>::share(const Vec<Dim>& x, double r, KernelSet kernels) const {
  double outside = 1.0;  // the kernel mass on the liquid's side of every wall
  for_each_wall(x, r, [&](double d, const Vec<Dim>&) { outside *= 1.0 - beyond(kernels, d / r); });
  return 1.0 - outside;
}

template <int Dim>
const std::vector<typename Boundary<Dim>::NearWall>& Boundary<Dim>::near_walls(const Vec<Dim>& x, double r,
                                                                               KernelSet kernels) const {
  thread_local std::vector<NearWall> walls;  // every wall within reach, as share() counts them
  walls.clear();
  for_each_wall(x, r, [&](double d, const Vec<Dim>& n) {
    walls.push_back(NearWall{d, beyond(kernels, d / r), on_plane(kernels, d / r), n});
  });
  return walls;
}

template <int Dim>
Vec<Dim> Boundary<Dim>::share_gradient_of(const std::vector<NearWall>& walls, double r) {
  // The gradient of 1 - prod_k (1 - Phi_k): each wall's plane integral times the others' factors;
  // Phi_k falls as the distance grows, so the gradient points into the walls.
  const int count = static_cast<int>(walls.size());
  Vec<Dim> g = Vec<Dim>::Zero();
  for (int k = 0; k < count; ++k) {
    double others = 1.0;
    for (int m = 0; m < count; ++m)
      if (m != k) others *= 1.0 - walls[m].beyond;
    g -= others * (walls[k].on_plane / r) * walls[k].n;
  }
  return g;
}

template <int Dim>
Vec<Dim> Boundary<Dim>::hydrostatic_of(const std::vector<NearWall>& walls, double r, const Vec<Dim>& g) {
  // Summed over the walls near a corner (see the header for why not the product rule of share()).
  Vec<Dim> h = Vec<Dim>::Zero();
  for (const NearWall& w : walls) h += (g.dot(w.n) * w.distance * w.on_plane / r) * w.n + w.beyond * g;
  return h;
}

template <int Dim>
Vec<Dim> Boundary<Dim>::share_gradient(const Vec<Dim>& x, double r, KernelSet kernels) const {
  return share_gradient_of(near_walls(x, r, kernels), r);
}

template <int Dim>
Vec<Dim> Boundary<Dim>::hydrostatic_gradient(const Vec<Dim>& x, double r, KernelSet kernels,
                                             const Vec<Dim>& g) const {
  return hydrostatic_of(near_walls(x, r, kernels), r, g);
}

template <int Dim>
typename Boundary<Dim>::Push Boundary<Dim>::push(const Vec<Dim>& x, double r, KernelSet kernels,
                                                 const Vec<Dim>& g) const {
  const std::vector<NearWall>& walls = near_walls(x, r, kernels);
  return {share_gradient_of(walls, r), hydrostatic_of(walls, r, g)};
}

template class Boundary<2>;
template class Boundary<3>;

}  // namespace liquid::sph
