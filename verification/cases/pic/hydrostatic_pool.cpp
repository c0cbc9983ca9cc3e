// Case hydrostatic-pool: a pool at rest must stay at rest (RBF Liquids, Fig. 16).
//
// Problem. A closed tank [0, 1]^d holds liquid of depth H = 0.5 at rest under gravity g = 9.81
// (density 1). The exact solution is u = 0, p = g (H - y). Run for T simulated seconds (2D: 2 s,
// 3D: 0.5 s; full tier: 4 s and 1 s) with dt = min(0.02, CFL-limited) by each method:
//   adaptive-rbf: AdaptivePic on a tree with the band at the finest level and level `coarse` inside
//   (the default transfer and reseeding); adaptive-rbf-paper: the same with the paper's preset;
//   regular-pic / regular-apic / regular-flip: the regular baselines, a uniform tree at the finest
//   level, their symmetric PPE solved by Jacobi-preconditioned CG (the adaptive one: BiCGSTAB+ILUT).
// Finest level 6 in 2D (h = 1/64), 4 in 3D (h = 1/16); the adaptive interior is 3 (2D) / 2 (3D).
// Measured: the fluid volume from the cells (sum of fluid cell volumes) and the surface height from
// the particles (the highest particle), their largest drift over the run relative to the start; the
// largest particle speed and fluid-face speed over the run relative to sqrt(g H); the pressure at
// the end against g (H - y) in L-inf over fluid cells relative to g H; average fluid cells and
// particles, and their share of the regular run's.
// Expected (gated): volume drift <= 1%, speeds <= 1e-2 sqrt(g H), pressure error <= 2 h / H; not for
// regular-pic-mass (the mass projection), which stirs the pool: measured, gated, warned about. The
// split projection (regular-pic-split, regular-apic-split) is held to the bounds: gravity's kick is
// projected in volumes, so the pool's pressure is the volume projection's hydrostatic one. Long runs,
// where the paper's preset lets a 3D pool's speed grow: pool-stability.

#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "common/case.hpp"
#include "liquid/core/timer.hpp"
#include "liquid/pic/adaptive_pic.hpp"
#include "liquid/scene/scene.hpp"

namespace liquid::verification {
namespace {

constexpr double kDepth = 0.5, kGravity = 9.81;

struct Method {
  const char* name;
  bool adaptive;
  pic::PicTransfer transfer;
  pic::PicProjection projection = pic::PicProjection::volume;
  /// The paper's preset (PHS r^5 + degree 2 transfers, the paper's reseeding) instead of the
  /// defaults (PHS r^3 + degree 1, top-up reseeding).
  bool paper = false;
};
// regular-pic-mass: PIC with the projection orthogonal in the faces' transferred masses
// (PicProjection::mass), under which a closed dam break's energy never rises (kinetic-energy). It
// does not keep the pool still: beta follows the particles' sampling, which varies along the
// floor, so g / beta has a curl that no pressure balances and the pool starts to stir (measured,
// gated and warned about; not held to the bounds below).
const Method kMethods[] = {
    {"regular-pic", false, pic::PicTransfer::pic},
    {"adaptive-rbf-paper", true, pic::PicTransfer::rbf, pic::PicProjection::volume, true},
    {"regular-flip", false, pic::PicTransfer::flip},
    {"regular-apic", false, pic::PicTransfer::apic},
    {"regular-pic-mass", false, pic::PicTransfer::pic, pic::PicProjection::mass},
    {"regular-pic-split", false, pic::PicTransfer::pic, pic::PicProjection::split},
    {"regular-apic-split", false, pic::PicTransfer::apic, pic::PicProjection::split},
    {"adaptive-rbf", true, pic::PicTransfer::rbf}};

struct Outcome {
  double volume_drift = 0.0, height_drift = 0.0, particle_speed = 0.0, face_speed = 0.0, pressure = 0.0;
  double fluid_cells = 0.0, particles = 0.0, seconds_per_step = 0.0;
  long steps = 0;
  PhaseTimer timer;
};

const char* const kPhases[] = {"classify", "grid",        "p2g", "forces", "gravity", "laplacian", "ppe",
                               "project",  "extrapolate", "g2p", "advect", "reseed",  "total"};

template <int Dim>
double fluid_volume(const pic::AdaptivePic<Dim>& sim) {
  return pic::volume_of<Dim>(sim.graph(), sim.classification().fluid);
}

template <int Dim>
double top(const pic::AdaptivePic<Dim>& sim) {
  double y = 0.0;
  for (const auto& x : sim.particles().x) y = std::max(y, x[1]);
  return y;
}

template <int Dim>
Outcome run_pool(const Method& m, bool full, Table& series) {
  pic::PicOptions<Dim> o;
  o.domain = Box<Dim>{Vec<Dim>::Zero(), Vec<Dim>::Ones()};
  o.adaptive = m.adaptive;
  o.finest_level = Dim == 2 ? 6 : 4;
  o.coarse_level = Dim == 2 ? 3 : 2;
  o.transfer = m.transfer;
  o.projection = m.projection;
  o.solver.kind =
      scene::default_ppe_solver(m.adaptive, Dim);  // as a scene file would: PCG on the regular grid
  if (m.paper) o.apply_paper_preset();
  pic::AdaptivePic<Dim> sim(o);
  Vec<Dim> hi = Vec<Dim>::Ones();
  hi[1] = kDepth;
  sim.seed(levelset::box<Dim>({Vec<Dim>::Zero(), hi}));
  const double end = Dim == 2 ? (full ? 4.0 : 2.0) : (full ? 1.0 : 0.5);
  const double v_ref = std::sqrt(kGravity * kDepth);
  Outcome out;
  const double v0 = fluid_volume(sim), y0 = top(sim);
  Stopwatch clock;
  double next_row = 0.0;
  while (sim.time() < end - 1e-12) {
    const double dt = std::min(sim.stable_dt(1.0, 0.02), end - sim.time());
    const pic::PicStepReport r = sim.advance(dt);
    ++out.steps;
    out.fluid_cells += static_cast<double>(r.n_fluid_cells);
    out.particles += static_cast<double>(r.n_particles);
    out.volume_drift = std::max(out.volume_drift, std::abs(fluid_volume(sim) / v0 - 1.0));
    out.height_drift = std::max(out.height_drift, std::abs(top(sim) / y0 - 1.0));
    double vp = 0.0, vf = 0.0;
    for (const auto& v : sim.particles().v) vp = std::max(vp, v.norm());
    const auto& g = sim.graph();
    const auto u = sim.face_velocity();
    g.for_each_face([&](tree::FaceId f) {
      if (sim.classification().wet(g.face(f))) vf = std::max(vf, std::abs(u[f]));
    });
    out.particle_speed = std::max(out.particle_speed, vp / v_ref);
    out.face_speed = std::max(out.face_speed, vf / v_ref);
    if (sim.time() >= next_row - 1e-12) {
      series.add_row({long(Dim), std::string(m.name), sim.time(), long(r.n_particles), long(r.n_fluid_cells),
                      std::abs(fluid_volume(sim) / v0 - 1.0), vp / v_ref, long(r.ppe.iterations)});
      next_row += end / 4;
    }
  }
  out.seconds_per_step = clock.seconds() / static_cast<double>(out.steps);
  out.timer = sim.timer();
  out.fluid_cells /= static_cast<double>(out.steps);
  out.particles /= static_cast<double>(out.steps);
  const auto p = sim.pressure();
  for (tree::CellId c : sim.classification().fluid) {
    const double exact = kGravity * (kDepth - sim.graph().centre(c)[1]);
    out.pressure = std::max(out.pressure, std::abs(p[c] - exact) / (kGravity * kDepth));
  }
  return out;
}

template <int Dim>
void study(const CaseOptions& options, Table& table, Table& series, Table& phases, CaseResult& result) {
  const double h = std::ldexp(1.0, -(Dim == 2 ? 6 : 4));
  const double bound = 2.0 * h / kDepth;
  Outcome regular;
  for (const Method& m : kMethods) {
    const Outcome o = run_pool<Dim>(m, options.full, series);
    if (std::string(m.name) == "regular-pic") regular = o;
    const double cells_share = regular.fluid_cells > 0 ? o.fluid_cells / regular.fluid_cells : 1.0;
    const double particle_share = regular.particles > 0 ? o.particles / regular.particles : 1.0;
    table.add_row({long(Dim), std::string(m.name), o.steps, o.particles, particle_share, o.fluid_cells,
                   cells_share, o.volume_drift, o.height_drift, o.particle_speed, o.face_speed, o.pressure,
                   bound, o.seconds_per_step});
    std::vector<Table::Cell> row;
    row.emplace_back(long(Dim));
    row.emplace_back(std::string(m.name));
    for (const char* phase : kPhases) row.push_back(o.timer.seconds(phase) / static_cast<double>(o.steps));
    phases.add_row(std::move(row));
    const std::string key = fmt::format("{}D {}", Dim, m.name);
    result.gate.push_back({key + " volume drift", GateFigure::Kind::error, std::max(o.volume_drift, 1e-6)});
    result.gate.push_back(
        {key + " max particle speed", GateFigure::Kind::error, std::max(o.particle_speed, 1e-6)});
    result.gate.push_back({key + " pressure error", GateFigure::Kind::error, std::max(o.pressure, 1e-6)});
    if (m.projection == pic::PicProjection::mass) {
      result.warnings.push_back(fmt::format(
          "{}: the mass projection stirs the still pool: particle speed up to {:.2e} sqrt(gH), volume drift "
          "{:.2e}, pressure error {:.2e} gH",
          key, o.particle_speed, o.volume_drift, o.pressure));
      continue;
    }
    result.expect(o.volume_drift <= 0.01, fmt::format("{}: volume drift {:.2e} > 1%", key, o.volume_drift));
    result.expect(o.particle_speed <= 1e-2,
                  fmt::format("{}: particle speed {:.2e} sqrt(gH) > 1e-2", key, o.particle_speed));
    result.expect(o.face_speed <= 1e-2,
                  fmt::format("{}: face speed {:.2e} sqrt(gH) > 1e-2", key, o.face_speed));
    result.expect(o.pressure <= bound,
                  fmt::format("{}: pressure error {:.2e} gH > 2h/H = {:.2e}", key, o.pressure, bound));
  }
}

CaseResult run(const CaseOptions& options) {
  CaseResult result;
  Table table(
      "still pool: drift, spurious speeds and pressure, per method",
      {"dim", "method", "steps", "particles", "of regular", "fluid cells", "of regular", "volume drift",
       "height drift", "max |v_p| / sqrt(gH)", "max |u_f| / sqrt(gH)", "p error / gH", "2h/H", "s/step"});
  Table series("over time", {"dim", "method", "t", "particles", "fluid cells", "volume drift",
                             "max |v_p| / sqrt(gH)", "PPE iterations"});
  std::vector<std::string> columns{"dim", "method"};
  for (const char* phase : kPhases) columns.emplace_back(phase);
  Table phases("seconds per step, by phase", columns);
  study<2>(options, table, series, phases, result);
  study<3>(options, table, series, phases, result);
  result.tables.push_back(std::move(table));
  result.tables.push_back(std::move(phases));
  result.tables.push_back(std::move(series));
  return result;
}

}  // namespace

LIQUID_VERIFICATION_CASE(
    {"hydrostatic-pool",
     "a still pool in a closed tank stays still: drift, spurious speed, pressure (Fig. 16)", true, run,
     no_options});

}  // namespace liquid::verification
