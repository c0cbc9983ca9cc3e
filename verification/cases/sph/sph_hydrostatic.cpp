// Case sph-hydrostatic: a still SPH tank must stay still (Adams et al. 2007, the solver at rest).
//
// Problem. A closed tank [0, 1]^Dim holds water (rho_0 = 1000, g = 9.81, mu = 5) of depth H = 0.5,
// seeded as a lattice of spacing s, settled for 0.3 s with damped velocities (AdaptiveSph::relax),
// then run with a fixed dt = 0.25 s / c (c = sqrt(k / rho_0), k chosen so that c = 10 sqrt(2 g H), a
// weakly compressible fluid: density varies by g H / c^2 = 0.5% over the depth) to time T, by
//   single: every particle at level 0 (the paper's single-resolution simulation);
//   adaptive: the same lattice resampled at rest by the feature size (levels 0..3), then every 5th
//             step as in the paper.
// 2D: s = 1/50, T = 0.5 s (full tier: s = 1/100, T = 2 s). 3D (full tier only, sph-hydrostatic-3d):
// s = 1/32, T = 0.2 s; at s = 1/16 the 8 rows are too few for any merge (beta r_0 > elfs everywhere).
// Measured, with hydrostatic references rho_h(y) = rho_0 (1 + rho_0 g (H - y) / k), P_h = rho_0 g (H - y):
//   - the density error max |rho_i / rho_h(y_i) - 1| over particles deeper than one support radius,
//     and the pressure error max |P_i - P_h(y_i)| / (rho_0 g H) over the same particles, at the end;
//   - the spurious speed: the largest particle speed over the last half of the run / sqrt(g H);
//   - the volume drift: the volume inside the distance surface (phi > 0 counted on a raster of s/4
//     cells), largest change over the run relative to the start;
//   - particles per level at the end, particle count relative to single, seconds per step.
// Expected (asserted; bounds about twice the values measured when the case was written):
//   single: spurious speed below 0.15 sqrt(g H) (0.078), density error below 1% (0.30%), volume drift
//   below 3% (1.3%);
//   adaptive: no blow-up: spurious speed below 0.7 sqrt(g H) (0.36), volume drift below 15% (5.9%),
//   and fewer particles than single (65% of them at s = 1/50: the tank is only 25 rows deep).
// The pressure error is reported, not asserted: with c = 10 sqrt(2 g H) a density error of 0.3%
// is a pressure error of 0.6 rho g H, so its L-inf over particles is the density's noise magnified.
// Gated: every measured figure.

#include <cmath>

#include <fmt/format.h>

#include "common/case.hpp"
#include "liquid/core/timer.hpp"
#include "liquid/levelset/levelset.hpp"
#include "liquid/sph/adaptive_sph.hpp"

namespace liquid::verification {
namespace {

constexpr double kDepth = 0.5, kGravity = 9.81, kRho = 1000.0, kSettle = 0.3;

/// The volume inside the distance surface, counted on a raster of cells of side `cell`.
template <int Dim>
double surface_volume(const sph::AdaptiveSph<Dim>& sim, double cell) {
  const auto& p = sim.particles();
  const sph::PointTree<Dim> tree(p.x);
  const sph::SurfaceField<Dim> phi(tree, p.x, p.radius, p.distance, sph::SurfaceModel::distance);
  const Box<Dim>& box = sim.options().container;
  Eigen::Matrix<long, Dim, 1> n, k = Eigen::Matrix<long, Dim, 1>::Zero();
  for (int d = 0; d < Dim; ++d) n[d] = std::lround(box.size()[d] / cell);
  long inside = 0, total = n.prod();
#pragma omp parallel for reduction(+ : inside) schedule(dynamic, 1024)
  for (long flat = 0; flat < total; ++flat) {
    long rest = flat;
    Vec<Dim> x;
    for (int d = 0; d < Dim; ++d)
      x[d] = box.lo[d] + cell * (static_cast<double>(rest % n[d]) + 0.5), rest /= n[d];
    inside += phi.value(x) > 0.0;
  }
  (void)k;
  return static_cast<double>(inside) * std::pow(cell, Dim);
}

struct Outcome {
  double density = 0.0, pressure = 0.0, speed = 0.0, volume_drift = 0.0, seconds_per_step = 0.0;
  int particles = 0;
  std::vector<int> per_level;
  long steps = 0, split = 0, merged = 0;
  PhaseTimer timer;
};

template <int Dim>
Outcome run_tank(bool adaptive, double s, double end) {
  sph::SphOptions<Dim> o;
  o.container = Box<Dim>{Vec<Dim>::Zero(), Vec<Dim>::Ones()};
  o.spacing = s;
  o.adaptive = adaptive;
  const double c = 10.0 * std::sqrt(2.0 * kGravity * kDepth);
  o.fluid.rest_density = kRho;
  o.fluid.stiffness = kRho * c * c;
  sph::AdaptiveSph<Dim> sim(o);
  Vec<Dim> hi = Vec<Dim>::Ones();
  hi[1] = kDepth;
  sim.seed(levelset::box<Dim>(Box<Dim>{Vec<Dim>::Zero(), hi}));
  sim.relax(kSettle);
  const double dt = 0.25 * s / c, cell = s / 4.0;
  const long steps = std::lround(end / dt);
  const double v0 = surface_volume(sim, cell);
  Outcome out;
  Stopwatch clock;
  double clock_seconds = 0.0;
  for (long k = 0; k < steps; ++k) {
    clock.restart();
    const sph::SphStepReport r = sim.advance(dt);
    clock_seconds += clock.seconds();
    out.split += r.resampling.split, out.merged += r.resampling.merged;
    if (2 * k >= steps) out.speed = std::max(out.speed, r.max_speed / std::sqrt(kGravity * kDepth));
    if ((k + 1) % std::max<long>(1, steps / 8) == 0 || k + 1 == steps)
      out.volume_drift = std::max(out.volume_drift, std::abs(surface_volume(sim, cell) / v0 - 1.0));
  }
  out.steps = steps;
  out.seconds_per_step = clock_seconds / static_cast<double>(steps);
  const auto& p = sim.particles();
  out.particles = p.size();
  out.per_level.assign(o.max_level + 1, 0);
  for (int i = 0; i < p.size(); ++i) {
    ++out.per_level[p.level[i]];
    const double y = p.x[i][1];
    if (kDepth - y < p.radius[i]) continue;  // within a support radius of the free surface
    const double rho_h = kRho * (1.0 + kRho * kGravity * (kDepth - y) / o.fluid.stiffness);
    out.density = std::max(out.density, std::abs(p.density[i] / rho_h - 1.0));
    out.pressure = std::max(
        out.pressure, std::abs(p.pressure[i] - kRho * kGravity * (kDepth - y)) / (kRho * kGravity * kDepth));
  }
  out.timer = sim.timer();
  return out;
}

template <int Dim>
CaseResult run(const CaseOptions& options) {
  CaseResult result;
  const double s = Dim == 2 ? (options.full ? 0.01 : 0.02) : 1.0 / 32;
  const double end = Dim == 2 ? (options.full ? 2.0 : 0.5) : 0.2;
  Table table(fmt::format("still tank ({}D, s = {:.4g}, to t = {} s): errors against the hydrostatic state",
                          Dim, s, end),
              {"method", "particles", "per level (0, 1, 2, 3)", "of single", "steps", "s/step", "split",
               "merged", "density err", "pressure err / (rho g H)", "speed / sqrt(gH)", "volume drift"});
  Table phases("seconds per step by phase", {"method", "neighbours", "forces", "redistance", "elfs",
                                             "resample", "integrate", "collisions", "total"});
  Outcome single;
  for (bool adaptive : {false, true}) {
    const Outcome r = run_tank<Dim>(adaptive, s, end);
    if (!adaptive) single = r;
    const std::string name = adaptive ? "adaptive" : "single";
    std::string levels;
    for (std::size_t l = 0; l < r.per_level.size(); ++l)
      levels += (l ? ", " : "") + std::to_string(r.per_level[l]);
    table.add_row({name, long(r.particles), levels, double(r.particles) / single.particles, r.steps,
                   r.seconds_per_step, r.split, r.merged, r.density, r.pressure, r.speed, r.volume_drift});
    auto per_step = [&](const char* phase) { return r.timer.seconds(phase) / static_cast<double>(r.steps); };
    phases.add_row({name, per_step("neighbours"), per_step("forces"), per_step("redistance"),
                    per_step("elfs"), per_step("resample"), per_step("integrate"), per_step("collisions"),
                    per_step("total")});
    result.gate.push_back({name + " density error", GateFigure::Kind::error, r.density});
    result.gate.push_back({name + " pressure error", GateFigure::Kind::error, r.pressure});
    result.gate.push_back({name + " spurious speed", GateFigure::Kind::error, r.speed});
    result.gate.push_back({name + " volume drift", GateFigure::Kind::error, r.volume_drift});
    result.gate.push_back({name + " particles", GateFigure::Kind::count, double(r.particles)});
    const double speed_bound = adaptive ? 0.7 : 0.15, drift_bound = adaptive ? 0.15 : 0.03;
    result.expect(r.speed < speed_bound,
                  fmt::format("{}: the largest speed in the second half is {:.3g} sqrt(gH), "
                              "above {}",
                              name, r.speed, speed_bound));
    result.expect(r.volume_drift < drift_bound, fmt::format("{}: the volume drifted by {:.3g}, more than {}",
                                                            name, r.volume_drift, drift_bound));
    if (!adaptive)
      result.expect(r.density < 0.01,
                    fmt::format("single: density error {:.3g} against the hydrostatic state", r.density));
    else
      result.expect(
          r.particles < single.particles,
          fmt::format("adaptive: {} particles, not fewer than single's {}", r.particles, single.particles));
  }
  result.notes.push_back(
      "weakly compressible: the equation of state lets the density vary by 0.5% over the depth; the "
      "errors "
      "are against that compressed hydrostatic state, not against rho_0");
  result.tables.push_back(std::move(table));
  result.tables.push_back(std::move(phases));
  return result;
}

}  // namespace

LIQUID_VERIFICATION_CASE({"sph-hydrostatic",
                          "still SPH tank (2D): density, pressure, spurious speed and volume drift, adaptive "
                          "against single resolution",
                          true, run<2>, no_options});
LIQUID_VERIFICATION_CASE(
    {"sph-hydrostatic-3d",
     "still SPH tank (3D, s = 1/32): density, pressure, spurious speed and volume drift, "
     "adaptive against single resolution",
     false, run<3>, no_options});

}  // namespace liquid::verification
