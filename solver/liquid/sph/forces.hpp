#pragma once
// Symmetric SPH forces between particles of different sizes (Adams et al. 2007, Eqs. 1-2, after the
// shooting/gathering average of Desbrun and Cani 1999) with the kernels of Müller et al. 2003:
//
//   rho_i = sum_j m_j W_poly6(|x_i - x_j|, r_i)        (j = i included)
//   P_i   = k (rho_i / rho_0 - 1)                       (clamped at 0 unless negative pressure is on)
//   f_ij  = -V_i V_j (P_i + P_j)/2 (grad W_spiky(x_i - x_j, r_i) + grad W_spiky(x_i - x_j, r_j))/2
//           + mu V_i V_j (v_j - v_i) (lap W_visc(., r_i) + lap W_visc(., r_j))/2,     V_i = m_i / rho_i
//
// The pressure term differs from the paper's Eq. 1 in two stated ways: the gradient is taken with
// respect to x_i (the paper's x_ij = x_j - x_i written with the opposite sign would attract), and
// (P_i + P_j) carries Müller's 1/2, so that a single level is exactly Müller's SPH; the paper's form
// is the same with k doubled. Every pair's force is computed from the same symmetric expression on
// both sides, so f_ij = -f_ji to the last bit and the forces sum to zero to round-off.

#include <span>

#include "liquid/core/types.hpp"
#include "liquid/sph/neighbours.hpp"
#include "liquid/sph/sph_particles.hpp"

namespace liquid::sph {

struct FluidConstants {
  double rest_density = 1000.0;    ///< rho_0 (kg/m^Dim)
  double stiffness = 2.0e5;        ///< k of the equation of state (Pa)
  double viscosity = 0.5;          ///< mu
  bool negative_pressure = false;  ///< keep P < 0 (tension) instead of clamping it at 0
};

/// Density and pressure of every particle (writes p.density, p.pressure). OpenMP.
template <int Dim>
void compute_density(SphParticles<Dim>& p, const NeighbourLists& nbrs, const FluidConstants& fluid);

/// The pair force on i from j (pressure + viscosity); f(j, i) = -f(i, j) exactly.
template <int Dim>
Vec<Dim> pair_force(const SphParticles<Dim>& p, int i, int j, const FluidConstants& fluid);

/// Acceleration of every particle from the pair forces plus gravity (writes p.a); the density and
/// pressure must be current. Each particle sums its own row (no write conflicts). OpenMP.
template <int Dim>
void compute_accelerations(SphParticles<Dim>& p, const NeighbourLists& nbrs, const FluidConstants& fluid,
                           const Vec<Dim>& gravity);

}  // namespace liquid::sph
