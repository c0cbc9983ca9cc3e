#pragma once
// The dam break of sph-adaptivity-gain and sph-gain-scaling: a water column a wide and 2a high
// (a = 0.2 m; Martin and Moyce's n^2 = 2) in the corner of a tank [0, 5a] x [0, 3a] (3D: 2a deep,
// the column filling the depth), with a speed of sound of 10 sqrt(2 g 2a), and the phases they time.

#include <cmath>

#include "liquid/core/types.hpp"
#include "liquid/sph/adaptive_sph.hpp"

namespace liquid::verification::sph_dam {

inline constexpr double kA = 0.2, kGravity = 9.81;
/// The AdaptiveSph phases the dam-break cases tabulate, in the paper's Table 1 order.
inline const char* const kPhases[] = {"neighbours", "forces",    "redistance", "elfs",
                                      "resample",   "integrate", "collisions", "total"};

/// The speed of sound: ten times the speed of a fall from the column's top.
inline double sound_speed() {
  return 10.0 * std::sqrt(2.0 * kGravity * 2 * kA);
}

/// The tank, spacing s, single resolution or adaptive.
template <int Dim>
sph::SphOptions<Dim> options(bool adaptive, double s) {
  sph::SphOptions<Dim> o;
  Vec<Dim> hi = Vec<Dim>::Constant(2 * kA);
  hi[0] = 5 * kA, hi[1] = 3 * kA;
  o.container = Box<Dim>{Vec<Dim>::Zero(), hi};
  o.spacing = s;
  o.adaptive = adaptive;
  const double c = sound_speed();
  o.fluid.stiffness = o.fluid.rest_density * c * c;
  return o;
}

/// The column (the gate it settles behind).
template <int Dim>
Box<Dim> column() {
  Vec<Dim> hi = Vec<Dim>::Constant(2 * kA);
  hi[0] = kA, hi[1] = 2 * kA;
  return Box<Dim>{Vec<Dim>::Zero(), hi};
}

}  // namespace liquid::verification::sph_dam
