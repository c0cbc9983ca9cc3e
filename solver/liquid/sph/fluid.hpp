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
};

}  // namespace liquid::sph
