// Case kinetic-energy: the dam break's energy over time, per method (RBF Liquids, Fig. 10).
//
// Problem. The dam-break-2d scene: a column [0, 0.4] x [0, 0.6] of liquid at rest collapses in a
// closed tank [0, 1]^2 under g = 9.81 (density 1), run with dt = min(0.01, CFL 1) to t = 1.5 s at
// finest level 5 (h = 1/32; full tier: to t = 2 s at levels 6 and 7). Methods: adaptive-rbf (the paper's;
// band at the finest level, level 3 inside), regular-rbf, regular-pic, regular-flip (blend 0.95),
// regular-apic (regular ones on the uniform tree at the finest level). kinetic-energy-3d (full tier
// only): the dam-break-3d scene's column [0, 0.4] x [0, 0.6] x [0, 1] at finest level 4 to t = 1 s.
// Measured from the particles, each standing for its share of the liquid's volume V (the column's,
// which the flow keeps) by the volume of its cell (particle_volumes: a particle in a coarse cell
// stands for more liquid than one in the band): kinetic energy K = sum w |v|^2 / 2 (APIC's plus its
// affine part, particle_affine_energy), potential energy P = sum w g y, their sum E; over time:
// K / E(0), E / E(0), and the liquid's volume by the same count (particle_volumes' `filled`); the peak
// of K, the time at which K falls to 50% of its peak after it; the growth of E: above its earlier
// peak, and the largest rise over any earlier value (max over s < t of E(t) - E(s)), with when it
// happened and the liquid's volume then.
// "Energy never grows" needs a system whose energy is defined. With reseeding it is not: the reseeding
// creates particles (1000-5500 in these runs, from 1001 at the start) and a particle's share moves as others
// enter and leave its cell, so every method's E rises somewhere, by 1.5% (PIC) to 7% (APIC, adaptive RBF);
// APIC's liquid, counted the same way, grows by 28% over the run, and its largest rise comes while it grows
// from 1.16 to 1.26 of the column's volume. So the same regular runs are made again with no reseeding and
// every particle a fixed mass V / N: a closed mechanical system. Measured there (level 5; level 6 in the full
// tier): PIC 0 (no step raised E) and 1.4e-3, APIC 0.6% and 0.2%, FLIP 0.06% and 0.2%, regular RBF 1.1% and
// 0.4%, with the usual projection, orthogonal in the cells' volumes while the transfers weigh the faces by
// the particles' masses. Run again with the projection orthogonal in those masses (PicProjection::mass,
// which also keeps the transferred value of faces that hold mass but are not projected), PIC, FLIP and
// APIC never raise E (asserted for PIC and APIC: the "PIC and APIC never gain energy" holds
// there, and only there; for APIC at this CFL, 1, only: at CFL 0.5 its E rose by 6.4e-4 at level 5,
// while PIC's, whose transfers are averages, did not; that projection does not keep a still pool still,
// see hydrostatic-pool, so it finds the cause without being a method). A third projection,
// PicProjection::split, projects gravity's kick in volumes first and the rest in masses: it keeps a
// still pool still, and measured here (fixed masses) its largest rises are PIC 0, FLIP 8.7e-5, APIC
// 3.6e-4 at level 5 (volume: 0, 6.3e-4, 6.2e-3), PIC 0, FLIP 0, APIC 1.5e-4 at level 6 (1.4e-3,
// 2.1e-3, 2.1e-3), but FLIP 4.3e-3 and APIC 1.1e-2 in 3D at level 4 (volume: 6.2e-4 and 4.9e-3;
// at level 5, outside this case, 5.4e-4 and 1.2e-3 against 6.6e-4 and 3.2e-3): not a cure, since the
// volume-projected kick does work against the particles that has no sign. Each step reports the
// work W the pressure applied in volumes did in the particles' masses (PicStepReport::pressure_work);
// no PIC step raised E by more than W (asserted; see the budget where it is checked), and W is what
// the split's rises come from: 3D level 4, APIC, split: the steps that raised E gained 1.1e-2 E(0)
// while W over them was 2.4e-2.
// Every rise other than the mass projection's PIC and APIC is warned about and gated. With reseeding, PIC and
// APIC do not rise above their earlier peak by more than 5e-3 (asserted); every rise over 5e-3 is warned
// about, and gated. RBF keeps more energy than PIC (the paper's Fig. 10), compared by the total energy E at
// the end: K at one instant is the phase of the slosh as much as what is kept (full tier, level 7: K at 2 s
// 0.092 for adaptive RBF against PIC's 0.110, E 0.749 against 0.577). How often the projection itself raised
// the kinetic energy of the face velocities (PicStepReport::grid_energy_before/after) is reported: an
// orthogonal projection (the uniform grid's D G) never does (asserted for the uniform runs, to 1e-6). Gated:
// the energy left at the end, the peak of K and the largest rise of E per method.

#include <cmath>

#include <fmt/format.h>

#include "common/case.hpp"
#include "liquid/core/timer.hpp"
#include "liquid/pic/adaptive_pic.hpp"
#include "studies/flow_measures.hpp"

namespace liquid::verification {
namespace {

constexpr double kGravity = 9.81;
/// The column: [0, 0.4] x [0, 0.6] (x [0, 1] in 3D: the dam-break-3d scene's).
template <int Dim>
Box<Dim> column() {
  Vec<Dim> hi = Vec<Dim>::Ones();
  hi[0] = 0.4, hi[1] = 0.6;
  return {Vec<Dim>::Zero(), hi};
}

using Method = FlowMethod;

struct Energies {
  double kinetic = 0.0, potential = 0.0;
  double filled = 0.0;  ///< the liquid's volume by the particles' count (particle_volumes), over V
  double total() const { return kinetic + potential; }
};

/// What each particle weighs. cell_shares: particle_volumes (its cell's volume over its cell's
/// particles), the only choice where the reseeding creates and removes particles. fixed_masses:
/// every particle V / N for good, for runs without reseeding on a uniform tree: the particles are
/// then a mechanical system of their own, whose energy the transfers, the projection and the
/// advection alone change.
enum class Shares { cell_shares, fixed_masses };

template <int Dim>
Energies energies(const AdaptivePic<Dim>& sim, double volume, Shares shares) {
  const Particles<Dim>& p = sim.particles();
  Energies e;
  std::vector<double> w = particle_volumes<Dim>(sim.graph(), p.x, volume, &e.filled);
  e.filled /= volume;
  if (shares == Shares::fixed_masses) w.assign(w.size(), volume / p.size());
  for (int i = 0; i < p.size(); ++i) {
    e.kinetic += 0.5 * w[i] * p.v[i].squaredNorm();
    e.potential += kGravity * w[i] * p.x[i][1];
  }
  e.kinetic += affine_energy<Dim>(sim, w);
  return e;
}

struct Run {
  std::vector<double> t, kinetic, total;  ///< relative to E(0)
  std::vector<double> volume;             ///< the liquid's volume by the particles' count, over V
  double peak = 0.0, peak_time = 0.0, half_time = NAN, seconds_per_step = 0.0;
  /// Growth of E: above its earlier peak (E(t) / max E(s<t) - 1), and the largest rise over any
  /// earlier value, max (E(t) - E(s)) / E(0) over s < t, from rise_from to rise_to.
  double above_peak = 0.0, rise = 0.0, rise_from = 0.0, rise_to = 0.0;
  double volume_from = 1.0, volume_to = 1.0;  ///< the liquid's volume at rise_from and rise_to
  long steps = 0, reseeded = 0;               ///< reseeded: particles the reseeding created
  /// Fixed masses, regular transfers: the largest rise of E over one step beyond the work the
  /// pressure applied in volumes did in the particles' masses (PicStepReport::pressure_work), over
  /// E(0); negative when every step lost more than that work. NaN otherwise.
  double beyond_work = NAN;
  double work_up = 0.0;         ///< that work summed over the steps where it was positive, over E(0)
  ProjectionEnergy projection;  ///< how often the projection raised the grid's kinetic energy
};

template <int Dim>
Run run_method(const Method& m, int level, double end, Shares shares = Shares::cell_shares,
               PicProjection projection = PicProjection::volume) {
  PicOptions<Dim> o;
  o.projection = projection;
  o.reseed = shares == Shares::cell_shares;
  o.adaptive = m.adaptive;
  o.transfer = m.transfer;
  o.fine_level = level;
  o.coarse_level = m.adaptive ? 3 : level;
  AdaptivePic<Dim> sim(o);
  sim.seed(levelset::box<Dim>(column<Dim>()));
  const double volume = column<Dim>().size().prod();
  const Energies start = energies(sim, volume, shares);
  const double e0 = start.total();
  Run run;
  run.t.push_back(0.0), run.kinetic.push_back(0.0), run.total.push_back(1.0),
      run.volume.push_back(start.filled);
  double highest = 1.0, lowest = 1.0, lowest_at = 0.0, lowest_volume = run.volume.back();
  // pressure_work is in unit particle masses; a fixed mass is V / N.
  const double mass = volume / sim.particles().size();
  Stopwatch clock;
  while (sim.time() < end - 1e-12) {
    const double dt = std::min(sim.stable_dt(1.0, 0.01), end - sim.time());
    const PicStepReport step = sim.advance(dt);
    ++run.steps;
    run.projection.add(step);
    const Energies e = energies(sim, volume, shares);
    const double k = e.kinetic / e0, total = e.total() / e0;
    if (shares == Shares::fixed_masses && std::isfinite(step.pressure_work)) {
      const double work = step.pressure_work * mass / e0, beyond = total - run.total.back() - work;
      run.beyond_work = std::isnan(run.beyond_work) ? beyond : std::max(run.beyond_work, beyond);
      run.work_up += std::max(work, 0.0);
    }
    run.reseeded += step.reseed.created;
    run.t.push_back(sim.time()), run.kinetic.push_back(k), run.total.push_back(total);
    run.volume.push_back(e.filled);
    run.above_peak = std::max(run.above_peak, total / highest - 1.0);
    if (total - lowest > run.rise) {
      run.rise = total - lowest, run.rise_from = lowest_at, run.rise_to = sim.time();
      run.volume_from = lowest_volume, run.volume_to = run.volume.back();
    }
    highest = std::max(highest, total);
    if (total < lowest) lowest = total, lowest_at = sim.time(), lowest_volume = run.volume.back();
    if (k > run.peak) run.peak = k, run.peak_time = sim.time(), run.half_time = NAN;
    if (std::isnan(run.half_time) && k <= 0.5 * run.peak && sim.time() > run.peak_time)
      run.half_time = sim.time();
  }
  run.seconds_per_step = clock.seconds() / static_cast<double>(run.steps);
  return run;
}

template <int Dim>
CaseResult run(const CaseOptions& options) {
  CaseResult result;
  Table table(
      fmt::format("dam break ({}D): energy per method, relative to the initial total E(0) (potential)", Dim),
      {"method", "level", "steps", "s/step", "peak K", "at t", "K falls to half at t", "K end", "E end",
       "E above its earlier peak", "largest rise of E", "from t", "to t", "liquid volume then", "and then",
       "volume at the end", "particles reseeded", "projections raising KE", "their largest rise"});
  Table over_time("kinetic energy K / E(0) over time", {"method", "level", "t", "K", "E", "liquid volume"});
  Json series = Json::array();
  std::map<std::string, Run> finest;
  // 3D runs in the full tier only (kinetic-energy-3d), at level 4 to 1 s.
  const int first = Dim == 3 ? 4 : options.full ? 6 : 5, last = Dim == 3 ? 4 : options.full ? 7 : 5;
  const double end = Dim == 3 ? 1.0 : options.full ? 2.0 : 1.5;
  for (int level = first; level <= last; ++level)
    for (const Method& m : kFlowMethods) {
      const Run r = run_method<Dim>(m, level, end);
      table.add_row({std::string(m.name), long(level), r.steps, r.seconds_per_step, r.peak, r.peak_time,
                     std::isnan(r.half_time) ? Table::Cell(std::string("not within the run"))
                                             : Table::Cell(r.half_time),
                     r.kinetic.back(), r.total.back(), r.above_peak, r.rise, r.rise_from, r.rise_to,
                     r.volume_from, r.volume_to, r.volume.back(), r.reseeded,
                     fmt::format("{} of {}", r.projection.raised, r.steps), r.projection.largest});
      for (std::size_t i = 0; i < r.t.size(); i += std::max<std::size_t>(1, r.t.size() / 10))
        over_time.add_row({std::string(m.name), long(level), r.t[i], r.kinetic[i], r.total[i], r.volume[i]});
      const std::string key = fmt::format("{} L{}", m.name, level);
      Json curve = series_entry(
          fmt::format("kinetic-energy{}: K / E(0) against t, level {}", Dim == 3 ? "-3d" : "", level), m.name,
          r.t, r.kinetic, "t (s)", "kinetic energy / E(0)");
      curve.set("scale", "linear");
      series.push(std::move(curve));
      if (level == first) {
        result.gate.push_back(
            {key + " energy lost by the end", GateFigure::Kind::error, 1.0 - r.total.back()});
        result.gate.push_back({key + " peak kinetic energy lost", GateFigure::Kind::error, 1.0 - r.peak});
        result.gate.push_back({key + " largest rise of the total energy", GateFigure::Kind::error, r.rise});
      }
      if (!m.adaptive)
        result.expect(
            r.projection.largest <= 1e-6,
            fmt::format("{}: the projection on the uniform tree raised the kinetic energy by {:.2e}", key,
                        r.projection.largest));
      if (m.transfer == PicTransfer::pic || m.transfer == PicTransfer::apic)
        result.expect(
            r.above_peak <= 5e-3,
            fmt::format("{}: the total energy rose {:.2e} above its earlier peak", key, r.above_peak));
      if (r.rise > 5e-3)
        result.warnings.push_back(
            fmt::format("{}: the total energy rose by {:.2e} E(0) from t = {:.2f} to {:.2f} s, while the "
                        "liquid's volume went "
                        "from {:.3f} to {:.3f} of the column's",
                        key, r.rise, r.rise_from, r.rise_to, r.volume_from, r.volume_to));
      finest[m.name] = r;
    }
  // The same regular runs with fixed masses and no reseeding (see Shares).
  Table fixed(fmt::format("dam break ({}D), level {}: the regular methods with every particle a fixed mass, "
                          "no reseeding",
                          Dim, first),
              {"method", "projection", "steps", "K end", "E end", "E above its earlier peak",
               "largest rise of E", "from t", "to t", "liquid volume at the end",
               "largest rise of E over a step beyond the pressure's work in masses",
               "that work summed over the steps it was positive"});
  for (const Method& m : kFlowMethods) {
    if (m.adaptive) continue;
    for (const PicProjection projection :
         {PicProjection::volume, PicProjection::mass, PicProjection::split}) {
      if (projection != PicProjection::volume && m.transfer == PicTransfer::rbf) continue;
      const Run r = run_method<Dim>(m, first, end, Shares::fixed_masses, projection);
      fixed.add_row({std::string(m.name), std::string(to_string(projection)), r.steps, r.kinetic.back(),
                     r.total.back(), r.above_peak, r.rise, r.rise_from, r.rise_to, r.volume.back(),
                     r.beyond_work, r.work_up});
      const std::string key = fmt::format(
          "{} L{} fixed masses{}", m.name, first,
          projection == PicProjection::volume ? "" : fmt::format(", {} projection", to_string(projection)));
      result.gate.push_back({key + " largest rise of the total energy", GateFigure::Kind::error, r.rise});
      result.gate.push_back({key + " energy lost by the end", GateFigure::Kind::error, 1.0 - r.total.back()});
      // PIC's transfers average (p -> face) and interpolate (face -> p) with weights that sum to 1, so
      // neither raises the particles' energy in the faces' transferred masses; APIC's fit neither
      // (where its stencil's first moment vanishes). The volume projection is orthogonal in the
      // cells' volumes, not in those masses, and lets E rise (measured, gated). The mass projection
      // is orthogonal in them and keeps the transferred value of every face that holds mass but is
      // not projected; what is left is gravity's work over a step against the fall it causes, which
      // differ at dt^2. Measured: with it no step of PIC or APIC raised E at levels 5 and 6
      // (asserted, to 1e-9 E(0)); FLIP's update is not an average, so its rises are only gated.
      // For APIC that holds at this CFL (1), not at every one: at CFL 0.5 its E rose by 6.4e-4
      // (level 5) and 2.1e-4 (level 6) with the mass projection; PIC's did not (see the budget).
      result.expect(r.projection.largest <= 1e-6,
                    fmt::format("{}: a projection raised the faces' kinetic energy in its own norm by {:.2e}",
                                key, r.projection.largest));
      const std::string rose =
          fmt::format("{}: the total energy rose by {:.2e} E(0) from t = {:.2f} to {:.2f} s", key, r.rise,
                      r.rise_from, r.rise_to);
      if (projection == PicProjection::mass && m.transfer != PicTransfer::flip)
        result.expect(r.rise <= 1e-9, rose);
      else if (r.rise > 1e-6)
        result.warnings.push_back(rose);
      // The budget of a step. With u = a - dt pi, a = w + dt g (w transferred) and pi the whole
      // pressure's acceleration, of which the part grad p applied in volumes does the work
      // W = -dt <u, grad p>_m in the masses m_f, the faces' energy is
      // K_m(u) = K_m(a) + W - dt^2 |pi|_m^2 / 2: the mass pass does no work in m on a divergence-free
      // u (the floor of min_face_mass aside). With a forward-Euler fall, dt sum m_f u_f . g, the
      // step changes E by W - dt^2 |g - pi|_m^2 / 2 minus the transfers' losses (>= 0 for PIC), so
      // by at most W, provided every face that holds mass carries a - dt pi (the volume projection
      // extrapolates massed faces between two air cells). No PIC step exceeded W in any run
      // measured (the particles fall by RK2, not forward Euler; see the README): asserted. APIC's
      // steps did, as its energy is counted (the affine part at the particle's new position) and
      // with the floor; they are reported, and warned about over 1e-9, as FLIP's are.
      const std::string beyond = fmt::format(
          "{}: a step raised E by {:.2e} E(0) more than the pressure's work in the particles' masses", key,
          r.beyond_work);
      if (m.transfer == PicTransfer::pic)
        result.expect(r.beyond_work <= 1e-9, beyond);
      else if (r.beyond_work > 1e-9)
        result.warnings.push_back(beyond);
    }
  }
  const Run &rbf = finest["adaptive-rbf"], &pic = finest["regular-pic"];
  result.expect(rbf.total.back() > pic.total.back(),
                fmt::format("adaptive RBF ends with E = {:.4f} E(0), PIC with {:.4f}: it kept no more energy",
                            rbf.total.back(), pic.total.back()));
  result.notes.push_back(
      "the flow is inviscid: every loss of E is the method's own (transfers, projection, reseeding); K also "
      "trades with the potential energy as the wave runs up the far wall and falls back");
  result.fields.set("series", std::move(series));
  result.tables.push_back(std::move(table));
  result.tables.push_back(std::move(over_time));
  result.tables.push_back(std::move(fixed));
  return result;
}

}  // namespace

LIQUID_VERIFICATION_CASE({"kinetic-energy",
                          "dam break (2D): kinetic and total energy over time for adaptive RBF, regular RBF, "
                          "PIC, FLIP and APIC (Fig. 10)",
                          true, run<2>, no_options});
LIQUID_VERIFICATION_CASE(
    {"kinetic-energy-3d",
     "dam break (3D, level 4, to 1 s): kinetic and total energy over time for adaptive RBF, "
     "regular RBF, PIC, FLIP and APIC",
     false, run<3>, no_options});

}  // namespace liquid::verification
