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
// Exact solution: the hydrostatic state above, at rest.
// Expected (asserted; bounds about twice the values measured when the case was written):
//   single: spurious speed below 0.15 sqrt(g H), density error below 1%, volume drift below 3%;
//   adaptive: no blow-up: spurious speed below 0.7 sqrt(g H), volume drift below 15%, and fewer
//   particles than single (the quick tank is only 25 rows deep, so the saving is small).
// The pressure error is reported, not asserted: with c = 10 sqrt(2 g H) a density error of 0.3%
// is a pressure error of 0.6 rho g H, so its L-inf over particles is the density's noise magnified.
// Also, steadier: the rms density and pressure errors (deep particles) and the rms speed, each averaged
// over 16 samples in the second half of the run.
// The adaptive run is made with 5 split-direction seeds (full tier: 3), its figures the medians: a split
// or merge decided differently changes the rest of an adaptive run, and a sum merely reordered
// (round-off) does that as a new seed does.
// Gated: every figure of the single run; of the adaptive one the particles and the rms speed (the
// medians that stay put between sets of seeds), the others reported only.
// What the force-model and footpoint choices do to these figures: docs/findings/sph.md.

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <fmt/format.h>

#include "common/case.hpp"
#include "liquid/core/timer.hpp"
#include "liquid/levelset/levelset.hpp"
#include "liquid/sph/adaptive_sph.hpp"

namespace liquid::verification {
namespace {

constexpr double kDepth = 0.5, kGravity = 9.81, kRho = 1000.0, kSettle = 0.3;
constexpr int kSeeds = 5;  ///< adaptive runs, one per split-direction seed (full tier: 3, longer runs)

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
  /// Root-mean-square density and pressure errors over the deep particles and rms speed over all,
  /// each averaged over 16 samples in the second half of the run: steadier than the L-inf figures
  /// (see the header), and the ones the adaptive run's gate checks.
  double rms_density = 0.0, rms_pressure = 0.0, rms_speed = 0.0;
  int particles = 0;
  std::vector<int> per_level;
  long steps = 0, split = 0, merged = 0;
  PhaseTimer timer;
};

struct Errors {
  double density = 0.0, pressure = 0.0;  ///< L-inf
  double rms_density = 0.0, rms_pressure = 0.0, rms_speed = 0.0;
};

/// Errors against the hydrostatic state now, over the particles deeper than their support radius.
template <int Dim>
Errors errors(const sph::AdaptiveSph<Dim>& sim, double stiffness) {
  const auto& p = sim.particles();
  Errors e;
  int deep = 0;
  for (int i = 0; i < p.size(); ++i) {
    e.rms_speed += p.v[i].squaredNorm();
    const double y = p.x[i][1];
    if (kDepth - y < p.radius[i]) continue;  // within a support radius of the free surface
    const double rho_h = kRho * (1.0 + kRho * kGravity * (kDepth - y) / stiffness);
    const double de = std::abs(p.density[i] / rho_h - 1.0),
                 pe = std::abs(p.pressure[i] - kRho * kGravity * (kDepth - y)) / (kRho * kGravity * kDepth);
    e.density = std::max(e.density, de), e.pressure = std::max(e.pressure, pe);
    e.rms_density += de * de, e.rms_pressure += pe * pe, ++deep;
  }
  e.rms_density = std::sqrt(e.rms_density / std::max(1, deep));
  e.rms_pressure = std::sqrt(e.rms_pressure / std::max(1, deep));
  e.rms_speed = std::sqrt(e.rms_speed / std::max(1, p.size())) / std::sqrt(kGravity * kDepth);
  return e;
}

template <int Dim>
Outcome run_tank(bool adaptive, double s, double end, std::uint64_t seed) {
  sph::SphOptions<Dim> o;
  o.seed = seed;
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
  int samples = 0;
  Stopwatch clock;
  double clock_seconds = 0.0;
  for (long k = 0; k < steps; ++k) {
    clock.restart();
    const sph::SphStepReport r = sim.advance(dt);
    clock_seconds += clock.seconds();
    out.split += r.resampling.split, out.merged += r.resampling.merged;
    if (2 * k >= steps) out.speed = std::max(out.speed, r.max_speed / std::sqrt(kGravity * kDepth));
    if (2 * k >= steps && (k + 1) % std::max<long>(1, steps / 32) == 0) {
      const Errors e = errors(sim, o.fluid.stiffness);
      out.rms_density += e.rms_density, out.rms_pressure += e.rms_pressure, out.rms_speed += e.rms_speed;
      ++samples;
    }
    if ((k + 1) % std::max<long>(1, steps / 8) == 0 || k + 1 == steps)
      out.volume_drift = std::max(out.volume_drift, std::abs(surface_volume(sim, cell) / v0 - 1.0));
  }
  out.rms_density /= samples, out.rms_pressure /= samples, out.rms_speed /= samples;
  const Errors last = errors(sim, o.fluid.stiffness);
  out.density = last.density, out.pressure = last.pressure;
  out.steps = steps;
  out.seconds_per_step = clock_seconds / static_cast<double>(steps);
  const auto& p = sim.particles();
  out.particles = p.size();
  out.per_level.assign(o.max_level + 1, 0);
  for (int i = 0; i < p.size(); ++i) ++out.per_level[p.level[i]];
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
               "merged", "density err", "pressure err / (rho g H)", "speed / sqrt(gH)", "volume drift",
               "rms density err", "rms pressure err", "rms speed"});
  Table phases("seconds per step by phase", {"method", "neighbours", "forces", "redistance", "elfs",
                                             "resample", "integrate", "collisions", "total"});
  // The adaptive run once per split-direction seed: one split or merge taken differently (a
  // different seed, or the same seed with sums in another order) changes the rest of the run, so
  // its figures are gated as medians over the seeds.
  const int n_seeds = options.full ? 3 : kSeeds;
  std::vector<Outcome> runs{run_tank<Dim>(false, s, end, 1)};
  for (int k = 0; k < n_seeds; ++k) runs.push_back(run_tank<Dim>(true, s, end, 1 + k));
  const Outcome& single = runs.front();
  auto add_rows = [&](const std::string& name, const Outcome& r) {
    std::string levels;
    for (std::size_t l = 0; l < r.per_level.size(); ++l)
      levels += (l ? ", " : "") + std::to_string(r.per_level[l]);
    table.add_row({name, long(r.particles), levels, double(r.particles) / single.particles, r.steps,
                   r.seconds_per_step, r.split, r.merged, r.density, r.pressure, r.speed, r.volume_drift,
                   r.rms_density, r.rms_pressure, r.rms_speed});
    auto per_step = [&](const char* phase) { return r.timer.seconds(phase) / static_cast<double>(r.steps); };
    phases.add_row({name, per_step("neighbours"), per_step("forces"), per_step("redistance"),
                    per_step("elfs"), per_step("resample"), per_step("integrate"), per_step("collisions"),
                    per_step("total")});
  };
  add_rows("single", single);
  for (int k = 0; k < n_seeds; ++k) add_rows(fmt::format("adaptive, seed {}", 1 + k), runs[1 + k]);
  // The adaptive figures: the median over the seeds (each figure's own median).
  Outcome adaptive = runs[1];
  auto median_of = [&](auto member) {
    std::vector<double> v;
    for (int k = 0; k < n_seeds; ++k) v.push_back(static_cast<double>(runs[1 + k].*member));
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  adaptive.density = median_of(&Outcome::density), adaptive.pressure = median_of(&Outcome::pressure);
  adaptive.speed = median_of(&Outcome::speed), adaptive.volume_drift = median_of(&Outcome::volume_drift);
  adaptive.particles = static_cast<int>(median_of(&Outcome::particles));
  adaptive.split = static_cast<long>(median_of(&Outcome::split));
  adaptive.merged = static_cast<long>(median_of(&Outcome::merged));
  adaptive.rms_density = median_of(&Outcome::rms_density),
  adaptive.rms_pressure = median_of(&Outcome::rms_pressure);
  adaptive.rms_speed = median_of(&Outcome::rms_speed);
  table.add_row({fmt::format("adaptive, median of {}", n_seeds), long(adaptive.particles), std::string("-"),
                 double(adaptive.particles) / single.particles, adaptive.steps, std::string("-"),
                 adaptive.split, adaptive.merged, adaptive.density, adaptive.pressure, adaptive.speed,
                 adaptive.volume_drift, adaptive.rms_density, adaptive.rms_pressure, adaptive.rms_speed});
  // Gated: every figure of the single run (deterministic); of the adaptive runs only the medians that
  // stay put between sets of seeds (particles and rms speed; the L-inf and rms density and pressure
  // errors and the volume drift move far more: docs/findings/sph.md).
  result.gate.push_back({"single density error", GateFigure::Kind::error, single.density});
  result.gate.push_back({"single pressure error", GateFigure::Kind::error, single.pressure});
  result.gate.push_back({"single spurious speed", GateFigure::Kind::error, single.speed});
  result.gate.push_back({"single volume drift", GateFigure::Kind::error, single.volume_drift});
  result.gate.push_back({"single particles", GateFigure::Kind::count, double(single.particles)});
  result.gate.push_back({"single rms density error", GateFigure::Kind::error, single.rms_density});
  result.gate.push_back({"single rms pressure error", GateFigure::Kind::error, single.rms_pressure});
  result.gate.push_back({"single rms speed", GateFigure::Kind::error, single.rms_speed});
  // Not a count: a median over seeds moves by a few particles, so it is checked as a cost that may
  // not grow by more than the tolerance.
  result.gate.push_back({"adaptive particles", GateFigure::Kind::error, double(adaptive.particles)});
  result.gate.push_back({"adaptive rms speed", GateFigure::Kind::error, adaptive.rms_speed});
  // Every run within the bounds (not only the medians).
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const Outcome& r = runs[k];
    const bool is_adaptive = k > 0;
    const std::string name = is_adaptive ? fmt::format("adaptive (seed {})", k) : "single";
    const double speed_bound = is_adaptive ? 0.7 : 0.15, drift_bound = is_adaptive ? 0.15 : 0.03;
    result.expect(r.speed < speed_bound,
                  fmt::format("{}: the largest speed in the second half is {:.3g} sqrt(gH), "
                              "above {}",
                              name, r.speed, speed_bound));
    result.expect(r.volume_drift < drift_bound, fmt::format("{}: the volume drifted by {:.3g}, more than {}",
                                                            name, r.volume_drift, drift_bound));
    if (!is_adaptive)
      result.expect(r.density < 0.01,
                    fmt::format("single: density error {:.3g} against the hydrostatic state", r.density));
    else
      result.expect(
          r.particles < single.particles,
          fmt::format("{}: {} particles, not fewer than single's {}", name, r.particles, single.particles));
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
