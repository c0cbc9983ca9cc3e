#pragma once
// The fluid's constants and the choices of the force model (forces.hpp describes the forces).
// Why these defaults: docs/findings/sph.md.

namespace liquid::sph {

/// The kernels of the density sum and of the pressure gradient.
enum class KernelSet {
  wendland,  ///< Wendland C2 for both
  spiky,     ///< Müller's spiky kernel for both
  mueller,   ///< Müller's (and the paper's): poly6 for the density, spiky for the pressure gradient
};
enum class PressureForm { paper, variational };
/// How the density is found: the paper's sum over neighbours, or carried by the particles and
/// advanced with the continuity equation (resampled particles then take their parents' density).
enum class DensityUpdate { continuity, summation };
const char* to_string(KernelSet kernels);
const char* to_string(PressureForm form);
const char* to_string(DensityUpdate update);

struct FluidConstants {
  double rest_density = 1000.0;    ///< rho_0 (kg/m^Dim)
  double stiffness = 2.0e5;        ///< k of the equation of state (Pa)
  double viscosity = 5.0;          ///< mu (Pa s)
  bool negative_pressure = false;  ///< keep P < 0 (tension) instead of clamping it at 0
  KernelSet kernels = KernelSet::wendland;
  PressureForm pressure_form = PressureForm::paper;
  DensityUpdate density_update = DensityUpdate::continuity;
  /// delta of the continuity equation's density diffusion (Molteni and Colagrossi 2009), 0 for none.
  double density_diffusion = 0.1;
  /// The continuity rate is taken at the step's kicked velocities v + dt a, the velocities that move
  /// the particles: density and velocity then advance by symplectic Euler, as positions and velocities
  /// do. false: at the velocities the step starts from, which makes the pair (density, velocity) an
  /// explicit Euler step of the acoustic oscillation, amplifying every sound wave by sqrt(1 + (w dt)^2)
  /// per step (unbounded without density diffusion).
  bool kicked_density_rate = true;
  /// The walls (container and obstacles) act as the liquid mirrored in them: a particle's own pressure
  /// across the wall, growing with depth as at rest (Boundary::hydrostatic_gradient; counted in full
  /// from a support radius below the surface, in proportion to P_i above it, since the liquid above
  /// the surface is at zero pressure, not in tension), its normal velocity reversed. Both wall terms
  /// (the push -P rho_0 / rho^2 grad share and the continuity's rho_0 grad share . v) are then twice
  /// those of a wall at zero pressure and at rest (false), which pushes a particle of uniform pressure
  /// back with half the force the liquid on its other side pushes it with: with false the floor row
  /// rests on the collisions' margin, with true it floats on the walls' pressure; the growth with
  /// depth keeps the liquid by the side walls from sliding along them. With the continuity density
  /// only: a summed density has no wall term to double with the push. The walls' terms use the density
  /// kernel's tables, so with `mueller` kernels (spiky pressure gradient) the mirror is approximate.
  bool mirror_walls = true;
  /// Between particles of different radii, the pressure kernel's gradient at their mean radius,
  /// grad W(x_ij, (r_i + r_j) / 2), in the pair force and the continuity rate, instead of the paper's
  /// average of the two gradients (Eqs. 1-2; false): a stiller tank at mixed sizes. Identical on one
  /// level.
  bool mean_radius_gradient = true;
  /// Continuity density only: a particle with no other particle and no wall within its support (spray
  /// in flight) is liquid at the ambient pressure, so its density is set to rho_0 (false: it keeps the
  /// density it left with, which nothing changes until it lands: such spray then sets the run's
  /// largest density error, and lands as a void or with its old pressure).
  bool free_particles_at_rest = true;
  /// Particle shifting (continuity density only): each step, a particle whose kernel lies inside the
  /// liquid (carried distance to the surface at least its radius) moves by -shifting r_i^2 grad C_i,
  /// with C_i = sum_j V_j W(x_ij) plus the walls' share: the kernel's partition of unity, near 1 wherever
  /// the particles' volumes tile the space. Its gradient comes from the continuity rate's own pairs.
  /// Mixed sizes pack denser than their volumes Sum m_i / rho_i say, which the continuity density does
  /// not see (the adaptive tank sinks); C sees it, and the shift spreads the crowding. 0: off (the
  /// paper has no shifting).
  double shifting = 0.02;
};

}  // namespace liquid::sph
