#include "liquid/sph/forces.hpp"

#include <cmath>

#include "liquid/core/error.hpp"
#include "liquid/sph/kernels.hpp"

namespace liquid::sph {

template <int Dim>
void compute_density(SphParticles<Dim>& p, const NeighbourLists& nbrs, const FluidConstants& fluid) {
  using K = Kernels<Dim>;
  const int n = p.size();
  LIQUID_VERIFY(nbrs.n_particles() == n, "compute_density: neighbour lists for {} particles, {} particles",
                nbrs.n_particles(), n);
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i) {
    double rho = p.mass[i] * K::poly6(0.0, p.radius[i]);
    for (int j : nbrs.of(i)) rho += p.mass[j] * K::poly6((p.x[i] - p.x[j]).norm(), p.radius[i]);
    p.density[i] = rho;
    const double pressure = fluid.stiffness * (rho / fluid.rest_density - 1.0);
    p.pressure[i] = fluid.negative_pressure ? pressure : std::max(0.0, pressure);
  }
}

template <int Dim>
Vec<Dim> pair_force(const SphParticles<Dim>& p, int i, int j, const FluidConstants& fluid) {
  using K = Kernels<Dim>;
  const Vec<Dim> xij = p.x[i] - p.x[j];
  const double q = xij.norm();
  const double vv = (p.mass[i] / p.density[i]) * (p.mass[j] / p.density[j]);
  const Vec<Dim> grad = 0.5 * (K::spiky_gradient(xij, p.radius[i]) + K::spiky_gradient(xij, p.radius[j]));
  const double lap = 0.5 * (K::viscosity_laplacian(q, p.radius[i]) + K::viscosity_laplacian(q, p.radius[j]));
  return (-vv * 0.5 * (p.pressure[i] + p.pressure[j])) * grad +
         (fluid.viscosity * vv * lap) * (p.v[j] - p.v[i]);
}

template <int Dim>
void compute_accelerations(SphParticles<Dim>& p, const NeighbourLists& nbrs, const FluidConstants& fluid,
                           const Vec<Dim>& gravity) {
  const int n = p.size();
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i) {
    Vec<Dim> f = Vec<Dim>::Zero();
    for (int j : nbrs.of(i)) f += pair_force(p, i, j, fluid);
    p.a[i] = f / p.mass[i] + gravity;
  }
}

template void compute_density<2>(SphParticles<2>&, const NeighbourLists&, const FluidConstants&);
template void compute_density<3>(SphParticles<3>&, const NeighbourLists&, const FluidConstants&);
template Vec<2> pair_force<2>(const SphParticles<2>&, int, int, const FluidConstants&);
template Vec<3> pair_force<3>(const SphParticles<3>&, int, int, const FluidConstants&);
template void compute_accelerations<2>(SphParticles<2>&, const NeighbourLists&, const FluidConstants&,
                                       const Vec<2>&);
template void compute_accelerations<3>(SphParticles<3>&, const NeighbourLists&, const FluidConstants&,
                                       const Vec<3>&);

}  // namespace liquid::sph
