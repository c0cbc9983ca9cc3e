// Case kinetic-energy: the dam break's energy over time, per method (RBF Liquids, Fig. 10).
//
// Problem. The dam-break-2d scene: a column [0, 0.4] x [0, 0.6] of liquid at rest collapses in a
// closed tank [0, 1]^2 under g = 9.81 (density 1), run with dt = min(0.01, CFL 1) to t = 1.5 s at
// finest level 5 (h = 1/32; full tier: to t = 2 s at levels 6 and 7). Methods: adaptive-rbf (band at
// the finest level, level 3 inside; the default transfer and reseeding), adaptive-rbf-paper (the
// same with the paper's preset), regular-rbf, regular-pic, regular-flip (blend 0.95),
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
// Why fixed masses: with reseeding the energy is not defined (reseeding creates particles, and a
// particle's share moves as others enter and leave its cell), so every method's E rises somewhere.
// The same regular runs are therefore made again with no reseeding and every particle a fixed mass
// V / N (a closed mechanical system), once per projection (PicProjection volume, mass, split). Each
// step reports the work W the pressure applied in volumes did in the particles' masses
// (PicStepReport::pressure_work), which bounds a PIC step's rise of E.
// Exact solution: none; the flow is inviscid, so every loss of E is the method's own.
// Expected (asserted): with the mass projection, PIC and APIC never raise E (to 1e-9 E(0); APIC at
// this CFL, 1, only); no fixed-mass PIC step raises E by more than W; with reseeding, PIC and APIC
// do not rise above their earlier peak by more than 5e-3; adaptive RBF, default and paper's preset,
// ends with more total energy E than PIC (the paper's Fig. 10; E, not K, since K at one instant is the
// slosh's phase); the uniform tree's projection never raises the faces' kinetic energy (to 1e-6). Every other
// rise of E is warned about (reseeded runs over 5e-3) and gated, as are the energy left at the end and the
// peak of K. Measured values: docs/findings/energy-and-projections.md.

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
Energies energies(const pic::AdaptivePic<Dim>& sim, double volume, Shares shares) {
  const particles::Particles<Dim>& p = sim.particles();
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
               pic::PicProjection projection = pic::PicProjection::volume) {
  pic::PicOptions<Dim> o;
  o.projection = projection;
  o.reseed = shares == Shares::cell_shares;
  o.adaptive = m.adaptive;
  o.transfer = m.transfer;
  o.finest_level = level;
  o.coarse_level = m.adaptive ? 3 : level;
  if (m.paper) o.apply_paper_preset();
  pic::AdaptivePic<Dim> sim(o);
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
    const pic::PicStepReport step = sim.advance(dt);
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
      if (m.transfer == pic::PicTransfer::pic || m.transfer == pic::PicTransfer::apic)
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
    for (const pic::PicProjection projection :
         {pic::PicProjection::volume, pic::PicProjection::mass, pic::PicProjection::split}) {
      if (projection != pic::PicProjection::volume && m.transfer == pic::PicTransfer::rbf) continue;
      const Run r = run_method<Dim>(m, first, end, Shares::fixed_masses, projection);
      fixed.add_row({std::string(m.name), std::string(to_string(projection)), r.steps, r.kinetic.back(),
                     r.total.back(), r.above_peak, r.rise, r.rise_from, r.rise_to, r.volume.back(),
                     r.beyond_work, r.work_up});
      const std::string key = fmt::format("{} L{} fixed masses{}", m.name, first,
                                          projection == pic::PicProjection::volume
                                              ? ""
                                              : fmt::format(", {} projection", to_string(projection)));
      result.gate.push_back({key + " largest rise of the total energy", GateFigure::Kind::error, r.rise});
      result.gate.push_back({key + " energy lost by the end", GateFigure::Kind::error, 1.0 - r.total.back()});
      // PIC's transfers average (p -> face) and interpolate (face -> p) with weights that sum to 1, so
      // neither raises the particles' energy in the faces' transferred masses; APIC's fit neither
      // (where its stencil's first moment vanishes). The volume projection is orthogonal in the
      // cells' volumes, not in those masses, and lets E rise (gated). The mass projection is
      // orthogonal in them and keeps the transferred value of every face that holds mass but is not
      // projected; what is left is gravity's work over a step against the fall it causes, which
      // differ at dt^2: no step of PIC or APIC raises E (asserted, to 1e-9 E(0)); FLIP's update is
      // not an average, so its rises are only gated. For APIC this holds at this CFL (1), not at
      // every one (docs/findings/energy-and-projections.md).
      result.expect(r.projection.largest <= 1e-6,
                    fmt::format("{}: a projection raised the faces' kinetic energy in its own norm by {:.2e}",
                                key, r.projection.largest));
      const std::string rose =
          fmt::format("{}: the total energy rose by {:.2e} E(0) from t = {:.2f} to {:.2f} s", key, r.rise,
                      r.rise_from, r.rise_to);
      if (projection == pic::PicProjection::mass && m.transfer != pic::PicTransfer::flip)
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
      // extrapolates massed faces between two air cells). The particles fall by RK2, not forward
      // Euler, so for PIC this is asserted rather than proven. APIC's steps can exceed W, as its
      // energy is counted (the affine part at the particle's new position) and with the floor; they
      // are reported, and warned about over 1e-9, as FLIP's are.
      const std::string beyond = fmt::format(
          "{}: a step raised E by {:.2e} E(0) more than the pressure's work in the particles' masses", key,
          r.beyond_work);
      if (m.transfer == pic::PicTransfer::pic)
        result.expect(r.beyond_work <= 1e-9, beyond);
      else if (r.beyond_work > 1e-9)
        result.warnings.push_back(beyond);
    }
  }
  const Run& pic = finest["regular-pic"];
  for (const char* name : {"adaptive-rbf", "adaptive-rbf-paper"}) {
    const Run& rbf = finest[name];
    result.expect(rbf.total.back() > pic.total.back(),
                  fmt::format("{} ends with E = {:.4f} E(0), PIC with {:.4f}: it kept no more energy", name,
                              rbf.total.back(), pic.total.back()));
  }
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
