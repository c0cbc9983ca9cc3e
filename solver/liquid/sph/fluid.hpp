#pragma once
// The fluid's constants and the two measured choices of the force model (forces.hpp says why).

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
  /// per step. Measured on the still 2D tank (s = 1/100, delta = 0.1, mirrored walls): largest speed
  /// 0.12-0.19 sqrt(g H) in every window of 0.015 s with false, 0.025-0.09 with true; with delta = 0
  /// false grows without bound (0.26 to 18 sqrt(g H) in 0.25 s) and true stays bounded.
  bool kicked_density_rate = true;
  /// The walls (container and obstacles) act as the liquid mirrored in them: a particle's own pressure
  /// across the wall, growing with depth as at rest (Boundary::hydrostatic_gradient; counted in full
  /// from a support radius below the surface, in proportion to P_i above it, since the liquid above
  /// the surface is at zero pressure, not in tension), its normal velocity reversed. Both wall terms
  /// (the push -P rho_0 / rho^2 grad share and the continuity's rho_0 grad share . v) are then twice
  /// those of a wall at zero pressure and at rest (false), which pushes a particle of uniform pressure
  /// back with half the force the liquid on its other side pushes it with. Measured on the still 2D
  /// tank: false, the whole floor row rests on the collisions' margin (with the margin halved it sinks
  /// onto the new one); true, it floats half a spacing above the floor on the walls' pressure alone.
  /// Without the growth with depth the liquid by the side walls slid along them (0.1 sqrt(g H) at
  /// s = 1/50; 0.03 with it, the tank's largest speed anywhere). With the continuity density only: a
  /// summed density has no wall term to double with the push. The walls' terms use the density
  /// kernel's tables, so with `mueller` kernels (spiky pressure gradient) the mirror is approximate.
  bool mirror_walls = true;
  /// Between particles of different radii, the pressure kernel's gradient at their mean radius,
  /// grad W(x_ij, (r_i + r_j) / 2), in the pair force and the continuity rate, instead of the paper's
  /// average of the two gradients (Eqs. 1-2; false). Measured on the still 2D tank, adaptive, before ->
  /// after: quick tier (s = 1/50, 0.5 s, medians of 5 seeds) largest speed 0.24 -> 0.12 sqrt(g H), rms
  /// speed 0.028 -> 0.015, density error 0.29% -> 0.12%, volume drift 1.2% -> 0.6%; full tier
  /// (s = 1/100, 2 s, 3 seeds) volume drift 12-15% -> 10%, splits 11k-18k -> 7k-11k a seed, largest
  /// speed 0.27-0.41 -> 0.30-0.67 sqrt(g H) (one seed higher); one seed over 0.5 s without resampling,
  /// the centre of mass fell 0.5% instead of 1.0%. The quick dam break's adaptive front stays within
  /// 0.8% of single's (1.0% with false). Identical on one level.
  bool mean_radius_gradient = true;
  /// Continuity density only: a particle with no other particle and no wall within its support (spray
  /// in flight) is liquid at the ambient pressure, so its density is set to rho_0 (false: it keeps the
  /// density it left with, which nothing changes until it lands). Measured on sph-drop-2d (one level,
  /// to 0.8 s): from t = 0.2 s on the largest density error of any step was a drop of spray flying at
  /// 64% of rho_0, and the run's peak error (38-52% at 0.125-1.0 s / c) was set by the spray, not by
  /// the impact. Landing, such a drop is a void until compressed by a third; one that left compressed
  /// lands with its old pressure.
  bool free_particles_at_rest = true;
  /// Particle shifting (continuity density only): each step, a particle whose kernel lies inside the
  /// liquid (carried distance to the surface at least its radius) moves by -shifting r_i^2 grad C_i,
  /// with C_i = sum_j V_j W(x_ij) plus the walls' share: the kernel's partition of unity, near 1 wherever
  /// the particles' volumes tile the space. Its gradient comes from the continuity rate's own pairs, at no
  /// measurable cost. Mixed sizes pack denser than their volumes Sum m_i / rho_i say, and the continuity
  /// density does not see it: the adaptive tank stood 3.5% low and went on sinking. C sees it, and the
  /// shift spreads the crowding. Measured on the still 2D tank (sph-hydrostatic), 0 -> 0.02:
  ///   - s = 1/100, adaptive, one seed: after the 0.3 s of settling the centre of mass stands 1.4% below
  ///     the single run's, against 4.3%; it falls 0.7% in the next 0.5 s, against 1.0%.
  ///   - quick tier (s = 1/50, 0.5 s, medians of 5 seeds): splits and merges 23 / 23 -> 8 / 4, volume drift
  ///     0.61% -> 0.30%, rms pressure error 0.052 -> 0.028 rho g H; single resolution: pressure error
  ///     0.070 -> 0.036, largest speed 0.030 -> 0.023 sqrt(g H).
  ///   - full tier (s = 1/100, 2 s, 3 seeds): splits 7k-11k -> 0.7k-2k a seed, volume drift 10% ->
  ///     3.4-4.0%; single resolution's largest late speed 0.033 -> 0.011 sqrt(g H).
  /// 0.05 settles as well but sent one tank to 0.37 sqrt(g H) and spread the quick dam break's adaptive
  /// fronts (1.1-2.0% from single, against 0.6-1.1%). 0: off (the paper has no shifting).
  double shifting = 0.02;
};

}  // namespace liquid::sph
