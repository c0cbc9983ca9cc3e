// Case dam-break-convergence: the dam break's front and surface against a finer run, and what each
// method pays for its error (speed at equal error where adaptivity should pay).
//
// Problem. The dam-break scenes' column ([0, 0.4] x [0, 0.6], x [0, 1] in 3D) collapses in a closed
// unit tank under g = 9.81, dt = min(0.01, CFL 1). Methods: adaptive-rbf (the default transfer and
// reseeding; band at the finest level, interior three levels coarser), regular-apic and
// regular-flip on the uniform grid of the same finest h (`--methods` picks some). Rows: finest levels
// 4, 5 and 6 (`--levels A:B`, up to 8 in 2D and 7 in 3D; 2D in the quick tier, 4-8 in the full tier;
// 3D in the full tier as dam-break-convergence-3d).
// Exact solution: none. The reference is a run one level finer than the finest row, by default regular
// APIC, an established method independent of the adaptive rows' discretisation (against a reference
// of its own kind each method looks closer than it is); in 3D past level 7 the adaptive run, which
// this machine can afford there (`--reference-method` picks the method).
// Measured at t = 0.05, 0.1, 0.15 (the front runs across the tank) and 0.3 s (the run-up), from the
// solver's fluid cells: the front (where the last 0.5% of their volume begins, counted from the far wall)
// and the height profile (over 16 columns across the tank, each column's fluid volume over its floor).
// Distance of a run from the reference: the largest of |front - reference front| over the three times
// before the front meets the far wall and, over all four, the mean over the columns of |height - reference
// height| (an L1 norm of the profile), in column heights. The profile's largest column difference (L-inf)
// is reported beside it: at the front's tip the profile is a step, where L-inf does not fall with h (a
// shift of the tip by one column is a whole column height), so it is not the measure
// (docs/findings/dam-break-convergence.md). Seconds: the run's wall time to 0.3 s. Expected (asserted): every
// method's distance falls from the coarsest row to the finest (it converges towards the reference); warned
// about when it falls by less than a quarter. Reported: each method's distance against seconds (plotted in
// the report), and the adaptive run's speed at equal distance against the fastest regular method, at
// every row's distance inside the adaptive rows' range (log-log between rows; where a regular method's
// rows do not bracket it, a one-sided bound from its most accurate or cheapest row). Gated: the distance of
// every method and row (default levels and methods).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "common/case.hpp"
#include "common/fit.hpp"
#include "liquid/core/timer.hpp"
#include "liquid/pic/adaptive_pic.hpp"
#include "liquid/scene/scene.hpp"
#include "studies/flow_measures.hpp"

namespace liquid::verification {
namespace {

constexpr double kTimes[] = {0.05, 0.1, 0.15, 0.3};
constexpr int kColumns = 16;
constexpr double kHeight = 0.6;  ///< the column's height
/// The front meets the far wall at about 0.27 s (Martin and Moyce's Z(T) for a = 0.4); after that the
/// "front" is the run-up's volume against the wall, not a front, so it is compared before this time.
constexpr double kImpact = 0.25;

const FlowMethod kMethods[] = {{"adaptive-rbf", true, pic::PicTransfer::rbf},
                               {"regular-apic", false, pic::PicTransfer::apic},
                               {"regular-flip", false, pic::PicTransfer::flip}};

/// The front and the height profile at one instant.
struct Shape {
  double front = 0.0;
  std::array<double, kColumns> height{};
  double volume = 0.0;  ///< the fluid cells' volume (the column's 0.24 at the start)
};

struct Run {
  std::vector<Shape> at;  ///< at kTimes
  double seconds = 0.0;
  long steps = 0;
  double particles = 0.0;  ///< average over the steps
};

// The liquid as the solver sees it: its fluid cells (cells holding particles, and the holes it fills).
// Both measures weigh volume, so they do not lean on how many particles a method keeps where (the
// adaptive tree holds more per volume in its band than in its coarse interior), and a lone spray
// particle counts for no more than its cell.
template <int Dim>
Shape measure(const pic::AdaptivePic<Dim>& sim) {
  Shape s;
  const tree::CellGraph<Dim>& graph = sim.graph();
  struct Slab {
    double lo, hi, volume;  // the cell's x extent and volume
  };
  std::vector<Slab> slabs;
  for (tree::CellId c : sim.classification().fluid) {
    const Box<Dim> b = graph.box(c);
    slabs.push_back({b.lo[0], b.hi[0], graph.volume(c)});
    s.volume += graph.volume(c);
  }
  // The height profile: each column's liquid volume over its floor area (the tank is 1 deep in 3D),
  // a cell shared between columns in proportion to its overlap.
  for (const Slab& b : slabs)
    for (int c = std::max(0, static_cast<int>(b.lo * kColumns)); c < kColumns && c < b.hi * kColumns; ++c) {
      const double overlap =
          std::min(b.hi, (c + 1.0) / kColumns) - std::max(b.lo, c / static_cast<double>(kColumns));
      if (overlap > 0.0) s.height[c] += b.volume * overlap / (b.hi - b.lo) * kColumns;
    }
  // The front: where the last 0.5% of the liquid's volume begins, counted from the far wall (bisection
  // on the volume beyond x, which falls continuously from the whole to 0 over [0, 1]).
  const auto beyond = [&](double x) {
    double v = 0.0;
    for (const Slab& b : slabs)
      if (b.hi > x) v += b.volume * (b.hi - std::max(b.lo, x)) / (b.hi - b.lo);
    return v;
  };
  double lo = 0.0, hi = 1.0;
  for (int i = 0; i < 50; ++i) {
    const double mid = 0.5 * (lo + hi);
    (beyond(mid) > 0.005 * s.volume ? lo : hi) = mid;
  }
  s.front = 0.5 * (lo + hi);
  return s;
}

template <int Dim>
Run run_method(const FlowMethod& m, int level, std::optional<int> band) {
  pic::PicOptions<Dim> o;
  o.adaptive = m.adaptive;
  if (band) o.band = *band;  // a regular run has no band
  o.transfer = m.transfer;
  o.finest_level = level;
  o.coarse_level = m.adaptive ? std::max(1, level - 3) : level;
  o.solver.kind = scene::default_ppe_solver(m.adaptive, Dim);  // as a scene file would
  if (m.paper) o.apply_paper_preset();
  pic::AdaptivePic<Dim> sim(o);
  Vec<Dim> hi = Vec<Dim>::Ones();
  hi[0] = 0.4, hi[1] = kHeight;
  sim.seed(levelset::box<Dim>({Vec<Dim>::Zero(), hi}));
  Run run;
  Stopwatch clock;
  for (double t : kTimes) {
    while (sim.time() < t - 1e-12) {
      const double dt = std::min(sim.stable_dt(1.0, 0.01), t - sim.time());
      run.particles += static_cast<double>(sim.advance(dt).n_particles);
      ++run.steps;
    }
    run.at.push_back(measure<Dim>(sim));
  }
  run.seconds = clock.seconds();
  run.particles /= static_cast<double>(std::max(1L, run.steps));
  return run;
}

/// A run's distance from the reference, in column heights: the largest over the instants of each part.
struct Distance {
  double front = 0.0;    ///< |front - reference front|
  double profile = 0.0;  ///< mean over the columns of |height - reference height|
  double worst = 0.0;    ///< largest column difference (L-inf; reported, not the measure)
  double measure() const { return std::max(front, profile); }
};

Distance distance(const Run& r, const Run& ref) {
  Distance d;
  for (std::size_t k = 0; k < r.at.size(); ++k) {
    if (kTimes[k] < kImpact) d.front = std::max(d.front, std::abs(r.at[k].front - ref.at[k].front) / kHeight);
    double sum = 0.0;
    for (int c = 0; c < kColumns; ++c) {
      const double diff = std::abs(r.at[k].height[c] - ref.at[k].height[c]) / kHeight;
      sum += diff;
      d.worst = std::max(d.worst, diff);
    }
    d.profile = std::max(d.profile, sum / kColumns);
  }
  return d;
}

template <int Dim>
CaseResult run(const CaseOptions& options) {
  CaseResult result;
  const char* name = Dim == 2 ? "dam-break-convergence" : "dam-break-convergence-3d";
  // The full tier's 2D rows reach finest 8, where the adaptive run pays at equal distance.
  const LevelRange range =
      options.levels.value_or(Dim == 2 && options.full ? LevelRange{4, 8} : LevelRange{4, 6});
  LIQUID_VERIFY(
      range.first >= 3 && range.last <= (Dim == 2 ? 8 : 7) && range.last > range.first,
      "{}: --levels {}:{} must be two or more finest levels within 3:{} (the reference runs one level "
      "finer)",
      name, range.first, range.last, Dim == 2 ? 8 : 7);
  std::vector<int> levels;
  for (int level = range.first; level <= range.last; ++level) levels.push_back(level);
  const std::vector<FlowMethod> methods = chosen_methods(kMethods, options.methods);
  const int ref_level = levels.back() + 1;
  // By default regular APIC: an established method, independent of the adaptive rows' discretisation
  // (a reference of their own kind favours them: docs/findings/dam-break-convergence.md). In 3D past
  // level 7 (the reference of --levels 6:7) the adaptive run, since regular APIC there needs 32M
  // particles and hours. `--reference-method` picks any of the case's methods.
  const bool affordable = Dim == 2 || ref_level <= 7;
  const FlowMethod ref_method =
      options.reference ? chosen_methods(kMethods, {*options.reference}, "--reference-method").front()
                        : (affordable ? kMethods[1] : kMethods[0]);
  // The reference keeps the default band whatever --band sets, so that rows of any band are measured
  // against the same run.
  const Run reference = run_method<Dim>(ref_method, ref_level, std::nullopt);
  result.notes.push_back(
      fmt::format("reference: {} at finest level {}, {:.1f} s, {:.0f} particles{}", ref_method.name,
                  ref_level, reference.seconds, reference.particles,
                  options.reference || affordable
                      ? ""
                      : " (the default past level 7 in 3D: regular APIC there takes hours; "
                        "rows of the reference's own kind are favoured, see --reference-method)"));
  if (options.band) result.notes.push_back(band_note(*options.band));
  Table table(fmt::format("dam break ({}D): distance from the reference (front and surface heights, in "
                          "column heights) against seconds to 0.3 s",
                          Dim),
              {"method", "finest", "steps", "particles", "distance", "front", "profile L1", "profile L-inf",
               "seconds", "front at 0.15 s", "reference", "volume at 0.3 s"});
  Json series = Json::array();
  std::map<std::string, ErrorCurve> curves;
  for (const FlowMethod& m : methods) {
    std::vector<double> errors, seconds, hs;
    for (int level : levels) {
      const Run r = run_method<Dim>(m, level, options.band);
      const Distance d = distance(r, reference);
      const double e = d.measure();
      fmt::print("  {} L{}: distance from the reference {:.3f} (front {:.3f}, profile {:.3f}) in {:.2f} s\n",
                 m.name, level, e, d.front, d.profile, r.seconds);
      std::fflush(stdout);
      table.add_row({std::string(m.name), long(level), r.steps, r.particles, e, d.front, d.profile, d.worst,
                     r.seconds, r.at[2].front, reference.at[2].front, r.at.back().volume});
      errors.push_back(e), seconds.push_back(r.seconds), hs.push_back(std::ldexp(1.0, -level));
      result.gate.push_back(
          {fmt::format("{} L{} error", m.name, level), GateFigure::Kind::error, std::max(e, 1e-6)});
    }
    if (errors.back() > 0.75 * errors.front())
      result.warnings.push_back(fmt::format(
          "{}: the distance from the reference fell only from {:.3g} to {:.3g} over the levels: the rows are "
          "not converging towards the reference, so their speed at equal error says little",
          m.name, errors.front(), errors.back()));
    result.expect(errors.back() < errors.front(),
                  fmt::format("{}: the error did not fall from level {} ({:.3g}) to level {} ({:.3g})",
                              m.name, levels.front(), errors.front(), levels.back(), errors.back()));
    series.push(
        series_entry(fmt::format("{}: distance from the reference against h", name), m.name, hs, errors));
    series.push(series_entry(fmt::format("{}: seconds against the distance from the reference", name), m.name,
                             errors, seconds, "distance from the reference (column heights)",
                             "seconds to 0.3 s"));
    curves[m.name] = {m.name, errors, seconds};
  }
  result.fields.set("series", std::move(series));
  result.tables.push_back(std::move(table));
  if (!curves.contains("adaptive-rbf")) return result;
  // Speed at equal error, wherever it can be read: at every row's distance inside the adaptive rows'
  // range, the adaptive run's seconds (between its rows) against the fastest regular method's.
  std::vector<ErrorCurve> regular;
  for (const FlowMethod& m : methods)
    if (!m.adaptive) regular.push_back(curves[m.name]);
  if (regular.empty()) return result;
  const std::vector<EqualErrorRow> equal = speed_at_equal_error(curves["adaptive-rbf"], regular);
  if (equal.empty()) {
    result.notes.push_back(
        "speed at equal error: the adaptive rows give no range of distances to read it over");
    return result;
  }
  result.tables.push_back(equal_error_table(
      equal,
      "speed at equal error: at each row's distance within the adaptive rows' range, the adaptive run's "
      "seconds (log-log between its rows) against the fastest regular method's",
      "distance", "adaptive RBF"));
  result.notes.push_back(
      "speed at equal error, adaptive RBF against the fastest regular method (by distance "
      "from the reference, largest first): " +
      equal_error_summary(equal));
  return result;
}

}  // namespace

LIQUID_VERIFICATION_CASE(
    {"dam-break-convergence",
     "dam break (2D, levels 4-6, full tier 4-8, reference one finer): front and surface against a finer "
     "regular APIC run, speed at equal error for adaptive RBF, APIC and FLIP",
     true,
     run<2>,
     {Option::levels, Option::methods, Option::reference, Option::band}});
LIQUID_VERIFICATION_CASE({"dam-break-convergence-3d",
                          "dam break (3D, levels 4-6, reference at 7): front and surface against a finer "
                          "regular APIC run, speed at equal error for adaptive RBF, APIC and FLIP",
                          false,
                          run<3>,
                          {Option::levels, Option::methods, Option::reference, Option::band}});

}  // namespace liquid::verification
