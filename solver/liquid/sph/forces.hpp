#pragma once
// Symmetric SPH forces between particles of different sizes (Adams et al. 2007, Eqs. 1-2, after the
// shooting/gathering average of Desbrun and Cani 1999) with the kernels of Müller et al. 2003:
//
//   rho_i = sum_j m_j W(|x_i - x_j|, r_i)        (j = i included; W the density kernel, see below)
//   P_i   = k (rho_i / rho_0 - 1)                (clamped at 0 unless negative pressure is on)
//   f_ij  = -V_i V_j (P_i + P_j) gbar_ij + mu V_i V_j (v_j - v_i) lbar_ij,     V_i = m_i / rho_i
//   gbar_ij = (grad W(x_i - x_j, r_i) + grad W(x_i - x_j, r_j)) / 2 with W the pressure kernel
//             (Wendland by default, spiky for the spiky and mueller sets), lbar_ij likewise for
//             the viscosity kernel's Laplacian. By default (FluidConstants::mean_radius_gradient)
//             gbar_ij = grad W(x_i - x_j, (r_i + r_j) / 2) instead, stiller at mixed sizes.
//
// The gradient is taken with respect to x_i: the paper writes x_ij = x_j - x_i, with which Eq. 1 as
// printed would attract. Eq. 1 carries no 1/2 on (P_i + P_j), unlike Müller et al.'s force density;
// with it the force is half of -grad P (the sum over j of (P_i + P_j)/2 grad W approximates grad P / 2),
// and a tank settles at twice the compression; Eq. 1 is right.
//
// Three choices (why these defaults: docs/findings/sph.md):
//   - kernels: Müller's poly6 density with the spiky pressure gradient (the paper's) is not the
//     gradient of any energy, so a still tank gains energy without bound. Default Wendland C2 for
//     both (smooth at 0, no pairing).
//   - density: the paper's summation starts a resampled tank with large density errors (a merged
//     pair's mass sits closer to its neighbours than the lattice's). Default: carried by the
//     continuity equation with Molteni and Colagrossi's density diffusion, so a split or merge keeps
//     its parents' density; summation is one flag away.
//   - pressure form: `paper` is Eq. 1; `variational` replaces V_i V_j (P_i + P_j) with
//     m_i m_j (P_i / rho_i^2 + P_j / rho_j^2) (equal to Eq. 1 where rho_i = rho_j). Default Eq. 1.
// Every pair's force comes from the same symmetric expression on both sides, so f_ij = -f_ji to the
// last bit and the forces sum to zero to round-off, for mixed sizes too.

#include <span>

#include "liquid/core/types.hpp"
#include "liquid/sph/boundary.hpp"
#include "liquid/sph/fluid.hpp"
#include "liquid/sph/neighbours.hpp"
#include "liquid/sph/sph_particles.hpp"

namespace liquid::sph {

/// The density kernel of `fluid` at distance q with support r.
template <int Dim>
double density_kernel(const FluidConstants& fluid, double q, double r);
/// The gradient of the pressure kernel of `fluid` at offset x with support r.
template <int Dim>
Vec<Dim> pressure_kernel_gradient(const FluidConstants& fluid, const Vec<Dim>& x, double r);

/// Density and pressure of every particle (writes p.density, p.pressure), with the walls' share when
/// `walls` is given. OpenMP.
template <int Dim>
void compute_density(SphParticles<Dim>& p, const NeighbourLists& nbrs, const FluidConstants& fluid,
                     const Boundary<Dim>* walls = nullptr);

/// The pair force on i from j (pressure + viscosity); f(j, i) = -f(i, j) exactly.
template <int Dim>
Vec<Dim> pair_force(const SphParticles<Dim>& p, int i, int j, const FluidConstants& fluid);

/// P from the carried density (continuity update): writes p.pressure. OpenMP.
template <int Dim>
void compute_pressure(SphParticles<Dim>& p, const FluidConstants& fluid);

/// The continuity equation's rate of density change, D rho_i / Dt = sum_j m_j (v_i - v_j) . gbar_ij
/// plus the walls' rho_0 grad share . v_i (twice that with mirrored walls), plus the density diffusion
/// (delta-SPH) of the difference from the hydrostatic state under `gravity` (writes p.drho). With
/// `kick` != 0 the velocities are v + kick a (p.a current): the step's kicked velocities
/// (FluidConstants::kicked_density_rate). With `concentration`, also writes there, per particle, the
/// gradient of C_i = sum_j V_j W(x_ij) + the walls' share with the same pair gradients: the kernel's
/// partition of unity, near 1 wherever the particles' volumes tile the space (FluidConstants::shifting).
/// OpenMP.
template <int Dim>
void compute_density_rate(SphParticles<Dim>& p, const NeighbourLists& nbrs, const FluidConstants& fluid,
                          const Vec<Dim>& gravity, const Boundary<Dim>* walls = nullptr, double kick = 0.0,
                          std::vector<Vec<Dim>>* concentration = nullptr);

/// FluidConstants::free_particles_at_rest: sets rho_0 as the density of every particle with no other
/// particle and no wall within its support; returns how many. OpenMP.
template <int Dim>
int rest_free_particles(SphParticles<Dim>& p, const NeighbourLists& nbrs, const FluidConstants& fluid,
                        const Boundary<Dim>* walls = nullptr);

/// Acceleration of every particle from the pair forces, the walls' pressure (when `walls` is given;
/// twice -P_i rho_0 / rho_i^2 grad share with mirrored walls, plus the mirrored pressure's growth
/// with depth under `gravity`, Boundary::hydrostatic_gradient) and gravity (writes p.a); the density
/// and pressure must be current. Each particle sums its own row (no write conflicts). OpenMP.
template <int Dim>
void compute_accelerations(SphParticles<Dim>& p, const NeighbourLists& nbrs, const FluidConstants& fluid,
                           const Vec<Dim>& gravity, const Boundary<Dim>* walls = nullptr);

}  // namespace liquid::sph
