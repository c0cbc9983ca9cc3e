#include "liquid/sph/forces.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "liquid/core/error.hpp"
#include "liquid/sph/kernels.hpp"

namespace liquid::sph {

const char* to_string(KernelSet kernels) {
  switch (kernels) {
    case KernelSet::wendland:
      return "wendland";
    case KernelSet::spiky:
      return "spiky";
    case KernelSet::mueller:
      return "mueller";
  }
  return "?";
}
const char* to_string(DensityUpdate update) {
  return update == DensityUpdate::continuity ? "continuity" : "summation";
}
const char* to_string(PressureForm form) {
  return form == PressureForm::paper ? "paper" : "variational";
}

namespace {
/// True when the walls act as the liquid mirrored in them (FluidConstants::mirror_walls): only with the
/// continuity density, whose wall term doubles with the push. A summed density has no such term, and
/// the doubled push alone would break the energy balance with the walls' share of the density.
bool mirrored(const FluidConstants& fluid) {
  return fluid.mirror_walls && fluid.density_update == DensityUpdate::continuity;
}
/// The walls' push and continuity term, mirrored: twice those of a wall at zero pressure and at rest.
double wall_factor(const FluidConstants& fluid) {
  return mirrored(fluid) ? 2.0 : 1.0;
}

/// |x_i - x_j|^2 (given) < max(r_i, r_j)^2: beyond it every kernel of the pair is zero, and the lists may
/// hold such pairs (a Verlet skin); skipping them leaves every sum as it was, to the bit.
template <int Dim>
bool within_support(const SphParticles<Dim>& p, int i, int j, double distance_squared) {
  const double r = std::max(p.radius[i], p.radius[j]);
  return distance_squared < r * r;
}

/// What every pair of particle i reads of it besides its state: its volume m_i / rho_i and the
/// constants of its kernels at r_i, computed once per particle rather than once per pair (the same
/// expressions, so the same bits).
struct PairTerms {
  double volume = 0.0, gradient_c = 0.0, laplacian_c = 0.0;
};

/// The constant of the pressure kernel's gradient at support r.
template <int Dim>
double gradient_constant(const FluidConstants& fluid, double r) {
  return fluid.kernels == KernelSet::wendland ? Kernels<Dim>::wendland_constant(r)
                                              : Kernels<Dim>::spiky_gradient_constant(r);
}

template <int Dim>
PairTerms pair_terms(const SphParticles<Dim>& p, int i, const FluidConstants& fluid) {
  const double r = p.radius[i];
  return {p.mass[i] / p.density[i], gradient_constant<Dim>(fluid, r),
          Kernels<Dim>::viscosity_laplacian_constant(r)};
}

template <int Dim>
std::vector<PairTerms> all_pair_terms(const SphParticles<Dim>& p, const FluidConstants& fluid) {
  std::vector<PairTerms> terms(p.size());
#pragma omp parallel for schedule(static)
  for (int i = 0; i < p.size(); ++i) terms[i] = pair_terms(p, i, fluid);
  return terms;
}

/// The pressure kernel's gradient at offset x, with q = |x| (the loops below take the square root
/// once per pair: x.norm() is the square root of the same squared norm, so the bits agree) and the
/// kernel's constant c at r given.
template <int Dim>
inline Vec<Dim> pressure_gradient(const FluidConstants& fluid, const Vec<Dim>& x, double q, double r,
                                  double c) {
  return fluid.kernels == KernelSet::wendland ? Kernels<Dim>::wendland_gradient(x, q, r, c)
                                              : Kernels<Dim>::spiky_gradient(x, q, r, c);
}

/// The pair's pressure-kernel gradient: the paper's average of the two particles' gradients, or with
/// FluidConstants::mean_radius_gradient the gradient at their mean radius.
template <int Dim>
inline Vec<Dim> pair_gradient(const SphParticles<Dim>& p, int i, int j, const FluidConstants& fluid,
                              const Vec<Dim>& xij, double q, const PairTerms& ti, const PairTerms& tj) {
  if (fluid.mean_radius_gradient && p.radius[i] != p.radius[j]) {
    const double r = 0.5 * (p.radius[i] + p.radius[j]);
    return pressure_gradient<Dim>(fluid, xij, q, r, gradient_constant<Dim>(fluid, r));
  }
  return 0.5 * (pressure_gradient<Dim>(fluid, xij, q, p.radius[i], ti.gradient_c) +
                pressure_gradient<Dim>(fluid, xij, q, p.radius[j], tj.gradient_c));
}

/// pair_force with x_ij, |x_ij| and both particles' terms given.
template <int Dim>
inline Vec<Dim> pair_force_at(const SphParticles<Dim>& p, int i, int j, const FluidConstants& fluid,
                              const Vec<Dim>& xij, double q, const PairTerms& ti, const PairTerms& tj) {
  using K = Kernels<Dim>;
  const double vv = ti.volume * tj.volume;
  const Vec<Dim> grad = pair_gradient<Dim>(p, i, j, fluid, xij, q, ti, tj);
  const double lap = 0.5 * (K::viscosity_laplacian(q, p.radius[i], ti.laplacian_c) +
                            K::viscosity_laplacian(q, p.radius[j], tj.laplacian_c));
  const double pressure = fluid.pressure_form == PressureForm::paper
                              ? vv * (p.pressure[i] + p.pressure[j])
                              : (p.mass[i] * p.mass[j]) * (p.pressure[i] / (p.density[i] * p.density[i]) +
                                                           p.pressure[j] / (p.density[j] * p.density[j]));
  return -pressure * grad + (fluid.viscosity * vv * lap) * (p.v[j] - p.v[i]);
}
}  // namespace

template <int Dim>
double density_kernel(const FluidConstants& fluid, double q, double r) {
  switch (fluid.kernels) {
    case KernelSet::wendland:
      return Kernels<Dim>::wendland(q, r);
    case KernelSet::spiky:
      return Kernels<Dim>::spiky(q, r);
    case KernelSet::mueller:
      return Kernels<Dim>::poly6(q, r);
  }
  return 0.0;
}

template <int Dim>
Vec<Dim> pressure_kernel_gradient(const FluidConstants& fluid, const Vec<Dim>& x, double r) {
  return pressure_gradient<Dim>(fluid, x, x.norm(), r, gradient_constant<Dim>(fluid, r));
}

template <int Dim>
void compute_density(SphParticles<Dim>& p, const NeighbourLists& nbrs, const FluidConstants& fluid,
                     const Boundary<Dim>* walls) {
  const int n = p.size();
  LIQUID_VERIFY(nbrs.n_particles() == n, "compute_density: neighbour lists for {} particles, {} particles",
                nbrs.n_particles(), n);
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i) {
    double rho = p.mass[i] * density_kernel<Dim>(fluid, 0.0, p.radius[i]);
    for (int j : nbrs.of(i)) {
      const double q2 = (p.x[i] - p.x[j]).squaredNorm();
      if (within_support(p, i, j, q2))
        rho += p.mass[j] * density_kernel<Dim>(fluid, std::sqrt(q2), p.radius[i]);
    }
    if (walls) rho += fluid.rest_density * walls->share(p.x[i], p.radius[i], fluid.kernels);
    p.density[i] = rho;
  }
  compute_pressure<Dim>(p, fluid);
}

template <int Dim>
void compute_pressure(SphParticles<Dim>& p, const FluidConstants& fluid) {
  const int n = p.size();
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i) {
    const double pressure = fluid.stiffness * (p.density[i] / fluid.rest_density - 1.0);
    p.pressure[i] = fluid.negative_pressure ? pressure : std::max(0.0, pressure);
  }
}

template <int Dim>
void compute_density_rate(SphParticles<Dim>& p, const NeighbourLists& nbrs, const FluidConstants& fluid,
                          const Vec<Dim>& gravity, const Boundary<Dim>* walls, double kick,
                          std::vector<Vec<Dim>>* concentration) {
  const int n = p.size();
  std::vector<Vec<Dim>> kicked;  // the velocities the rate is taken at, when they are not p.v
  if (kick != 0.0) {
    kicked.resize(n);
#pragma omp parallel for schedule(static)
    for (int i = 0; i < n; ++i) kicked[i] = p.v[i] + kick * p.a[i];
  }
  const std::vector<Vec<Dim>>& velocity = kick != 0.0 ? kicked : p.v;
  const double c = std::sqrt(fluid.stiffness / fluid.rest_density);
  const double hydrostatic = fluid.rest_density * fluid.rest_density / fluid.stiffness;
  const std::vector<PairTerms> terms = all_pair_terms(p, fluid);
  if (concentration) concentration->assign(n, Vec<Dim>::Zero());
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i) {
    double rate = 0.0;
    Vec<Dim> gc = Vec<Dim>::Zero();
    for (int j : nbrs.of(i)) {
      const Vec<Dim> xij = p.x[i] - p.x[j];
      const double q2 = xij.squaredNorm();
      if (!within_support(p, i, j, q2)) continue;
      const double q = std::sqrt(q2);
      const Vec<Dim> grad = pair_gradient<Dim>(p, i, j, fluid, xij, q, terms[i], terms[j]);
      rate += p.mass[j] * (velocity[i] - velocity[j]).dot(grad);
      gc += terms[j].volume * grad;
      if (fluid.density_diffusion > 0.0) {
        // delta h c sum_j V_j 2 (rho_j - rho_i - hydrostatic part) (x_ji . grad_i W) / |x_ij|^2, with h
        // half the mean support; the hydrostatic part rho_0^2 g . (x_j - x_i) / k is the density
        // difference of a liquid at rest, which the diffusion must not flatten (Fourtakas et al. 2019).
        const double h = 0.25 * (p.radius[i] + p.radius[j]);
        const double jump = p.density[j] - p.density[i] + hydrostatic * gravity.dot(xij);
        // (+ (0.1 h)^2 below: two particles clamped into the same corner by the walls sit on one point.)
        rate += fluid.density_diffusion * h * c * terms[j].volume * 2.0 * jump * (-xij.dot(grad)) /
                (xij.squaredNorm() + 0.01 * h * h);
      }
    }
    if (walls) {
      const Vec<Dim> share = walls->share_gradient(p.x[i], p.radius[i], fluid.kernels);
      rate += wall_factor(fluid) * fluid.rest_density * share.dot(velocity[i]);
      gc += share;
    }
    p.drho[i] = rate;
    if (concentration) (*concentration)[i] = gc;
  }
}

template <int Dim>
int rest_free_particles(SphParticles<Dim>& p, const NeighbourLists& nbrs, const FluidConstants& fluid,
                        const Boundary<Dim>* walls) {
  const int n = p.size();
  int freed = 0;
#pragma omp parallel for schedule(static) reduction(+ : freed)
  for (int i = 0; i < n; ++i) {
    bool alone = true;
    for (int j : nbrs.of(i))
      if (within_support(p, i, j, (p.x[i] - p.x[j]).squaredNorm())) {
        alone = false;
        break;
      }
    if (!alone || (walls && walls->share(p.x[i], p.radius[i], fluid.kernels) > 0.0)) continue;
    // Every particle that could read this density in a sum is within its support: none does.
    p.density[i] = fluid.rest_density;
    ++freed;
  }
  return freed;
}

template <int Dim>
Vec<Dim> pair_force(const SphParticles<Dim>& p, int i, int j, const FluidConstants& fluid) {
  const Vec<Dim> xij = p.x[i] - p.x[j];
  return pair_force_at<Dim>(p, i, j, fluid, xij, xij.norm(), pair_terms(p, i, fluid),
                            pair_terms(p, j, fluid));
}

template <int Dim>
void compute_accelerations(SphParticles<Dim>& p, const NeighbourLists& nbrs, const FluidConstants& fluid,
                           const Vec<Dim>& gravity, const Boundary<Dim>* walls) {
  const int n = p.size();
  const std::vector<PairTerms> terms = all_pair_terms(p, fluid);
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i) {
    Vec<Dim> f = Vec<Dim>::Zero();
    for (int j : nbrs.of(i)) {
      const Vec<Dim> xij = p.x[i] - p.x[j];
      const double q2 = xij.squaredNorm();
      if (within_support(p, i, j, q2))
        f += pair_force_at<Dim>(p, i, j, fluid, xij, std::sqrt(q2), terms[i], terms[j]);
    }
    p.a[i] = f / p.mass[i] + gravity;
    if (walls && p.pressure[i] != 0.0) {
      // One walk over the walls for both terms (same expressions and order as two separate calls).
      const typename Boundary<Dim>::Push push = walls->push(p.x[i], p.radius[i], fluid.kernels, gravity);
      if (mirrored(fluid)) {
        // The mirrored liquid's pressure grows with depth as at rest; it is not pulled below zero
        // above a particle near the free surface, so the growth is counted in full only for a
        // particle at least a support radius deep (P_i >= rho_0 |g| r_i), in proportion above that
        // (a pressure raised by an impact reads as depth here).
        const double g = gravity.norm();
        const double deep =
            g > 0.0 ? std::clamp(p.pressure[i] / (fluid.rest_density * g * p.radius[i]), 0.0, 1.0) : 0.0;
        if (deep > 0.0)
          p.a[i] -= deep * (fluid.rest_density * fluid.rest_density / (p.density[i] * p.density[i])) *
                    push.hydrostatic;
      }
      p.a[i] -= wall_factor(fluid) * (p.pressure[i] * fluid.rest_density / (p.density[i] * p.density[i])) *
                push.share_gradient;
    }
  }
}

template Vec<2> pressure_kernel_gradient<2>(const FluidConstants&, const Vec<2>&, double);
template Vec<3> pressure_kernel_gradient<3>(const FluidConstants&, const Vec<3>&, double);
template double density_kernel<2>(const FluidConstants&, double, double);
template double density_kernel<3>(const FluidConstants&, double, double);
template void compute_density<2>(SphParticles<2>&, const NeighbourLists&, const FluidConstants&,
                                 const Boundary<2>*);
template void compute_density<3>(SphParticles<3>&, const NeighbourLists&, const FluidConstants&,
                                 const Boundary<3>*);
template Vec<2> pair_force<2>(const SphParticles<2>&, int, int, const FluidConstants&);
template Vec<3> pair_force<3>(const SphParticles<3>&, int, int, const FluidConstants&);
template void compute_pressure<2>(SphParticles<2>&, const FluidConstants&);
template void compute_pressure<3>(SphParticles<3>&, const FluidConstants&);
template void compute_density_rate<2>(SphParticles<2>&, const NeighbourLists&, const FluidConstants&,
                                      const Vec<2>&, const Boundary<2>*, double, std::vector<Vec<2>>*);
template void compute_density_rate<3>(SphParticles<3>&, const NeighbourLists&, const FluidConstants&,
                                      const Vec<3>&, const Boundary<3>*, double, std::vector<Vec<3>>*);
template int rest_free_particles<2>(SphParticles<2>&, const NeighbourLists&, const FluidConstants&,
                                    const Boundary<2>*);
template int rest_free_particles<3>(SphParticles<3>&, const NeighbourLists&, const FluidConstants&,
                                    const Boundary<3>*);
template void compute_accelerations<2>(SphParticles<2>&, const NeighbourLists&, const FluidConstants&,
                                       const Vec<2>&, const Boundary<2>*);
template void compute_accelerations<3>(SphParticles<3>&, const NeighbourLists&, const FluidConstants&,
                                       const Vec<3>&, const Boundary<3>*);

}  // namespace liquid::sph
