// Case sph-gain-scaling: how the adaptive gain grows with resolution, at sizes a full dam break
// cannot afford here (Adams et al. 2007, Table 1; the target: 4 times fewer particles and 3 times
// faster in 3D).
//
// Problem. sph-adaptivity-gain's dam break: a column a wide and 2a high (a = 0.2 m) in the corner
// of a tank [0, 5a] x [0, 3a] (3D: 2a deep, the column filling the depth), seeded as a lattice of
// spacing s, and for the adaptive run resampled at rest until no particle changes (what
// AdaptiveSph::seed does). Both runs then take `steps` steps of 0.25 s / c from the release (no
// settling: the first steps of the collapse), resampling every 5th.
// Measured per s: particles of both runs (their ratio: the memory gain), seconds a step (the median
// over windows of 5 steps, each with its resampling step; the two runs take their windows in turn, and
// the speed gain is the median of the paired windows' ratios), and the fitted growth of
// both gains with 1/s, extrapolated to the spacing where the goal would be met. This is the start of the dam
// break only: the gain over a whole run is sph-adaptivity-gain's (the liquid then spreads into thin sheets,
// which need small particles). Expected: both gains grow as s shrinks (the coarse interior grows as a^d / s^d
// while the level-0 band stays a few spacings thick: the memory gain tends to grow like 1/s). Asserted: the
// adaptive run has fewer particles at every size, and the memory gain at the finest size exceeds that at the
// coarsest. Full tier only (2D s = a/20 ... a/320, 3D s = a/16 ... a/80, 2M single-resolution particles;
// about 20 minutes here). Gated: the adaptive run's particles (mean over the steps) per size.
// `--sizes D:N,...` runs one dimension at the sizes given (e.g. --sizes 3:48 for the phase shares at a/48);
// the runs resample every 5th step (the paper's cadence; --resample-travel S uses the travel rule instead).

#include <algorithm>
#include <cmath>
#include <optional>

#include <fmt/format.h>

#include "common/case.hpp"
#include "common/fit.hpp"
#include "dam.hpp"
#include "liquid/core/error.hpp"
#include "liquid/core/timer.hpp"
#include "liquid/levelset/levelset.hpp"
#include "liquid/sph/adaptive_sph.hpp"

namespace liquid::verification {
namespace {

using sph_dam::kA;

using sph_dam::kPhases;

struct Sample {
  double particles = 0.0, seconds_per_step = 0.0;
  std::vector<double> phases;  ///< mean seconds a step of each of kPhases over the steps
};

/// One of the two runs of a size: the simulation, seeded, and what it has measured so far.
template <int Dim>
struct Contender {
  sph::AdaptiveSph<Dim> sim;
  std::vector<double> before;   ///< each phase's seconds after seeding (the seeding's own passes)
  std::vector<double> windows;  ///< seconds a step over each window
  Sample out;

  Contender(bool adaptive, double s, std::optional<double> travel)
      : sim([&] {
          sph::SphOptions<Dim> o = sph_dam::options<Dim>(adaptive, s);
          // From rest the liquid travels a tiny fraction of a spacing in these steps: the travel rule
          // would skip every pass after the first, so the window keeps the paper's fixed cadence.
          o.resample_travel = travel.value_or(0.0);
          return o;
        }()) {
    sim.seed(levelset::box<Dim>(sph_dam::column<Dim>()));
    for (const char* phase : kPhases) before.push_back(sim.timer().seconds(phase));
  }
  /// `count` steps of dt, timed as one window.
  void window(double dt, int count) {
    Stopwatch clock;
    for (int k = 0; k < count; ++k) out.particles += sim.advance(dt).particles;
    windows.push_back(clock.seconds() / count);
  }
  void finish(int steps) {
    out.particles /= steps;
    for (std::size_t k = 0; k < before.size(); ++k)
      out.phases.push_back((sim.timer().seconds(kPhases[k]) - before[k]) / steps);
  }
};

/// Both runs of size s, `steps` steps each, taken in alternating windows of one resampling period
/// (5 steps, one resampling each), so that a slow spell of this shared machine falls on both: the
/// speed gain is the median over window pairs of their ratio, the seconds a step the medians of each
/// run's windows (run one after the other, the gain moves with the machine's load).
template <int Dim>
std::pair<Sample, Sample> run_both(double s, int steps, std::optional<double> travel, double& speed_gain) {
  Contender<Dim> single(false, s, travel), adaptive(true, s, travel);
  const double dt = 0.25 * s / sph_dam::sound_speed();
  const int every = adaptive.sim.options().resample_every;
  std::vector<double> ratios;
  for (int k = 0; k < steps; k += every) {
    single.window(dt, every), adaptive.window(dt, every);
    ratios.push_back(single.windows.back() / adaptive.windows.back());
  }
  const int taken = static_cast<int>(ratios.size()) * every;
  single.finish(taken), adaptive.finish(taken);
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  single.out.seconds_per_step = median(single.windows);
  adaptive.out.seconds_per_step = median(adaptive.windows);
  speed_gain = median(ratios);
  return {single.out, adaptive.out};
}

template <int Dim>
void study(CaseResult& result, const std::vector<int>& divisions, int steps, std::optional<double> travel) {
  Table table(
      fmt::format("{}D dam break, the first {} steps: single resolution against adaptive", Dim, steps),
      {"s", "single particles", "adaptive particles", "memory gain", "single s/step", "adaptive s/step",
       "speed gain"});
  Table phases(fmt::format("{}D: seconds a step by phase (means over the steps)", Dim),
               {"s", "run", "neighbours", "forces", "redistance", "elfs", "resample", "integrate",
                "collisions", "total", "total per particle", "surface share"});
  std::vector<double> h, memory, speed;
  for (int division : divisions) {
    const double s = kA / division;
    double speed_gain = 0.0;
    const std::pair<Sample, Sample> both = run_both<Dim>(s, steps, travel, speed_gain);
    const Sample &single = both.first, &adaptive = both.second;
    for (const Sample* r : {&single, &adaptive}) {
      std::vector<Table::Cell> row;
      row.reserve(r->phases.size() + 4);
      row.emplace_back(fmt::format("a/{}", division));
      row.emplace_back(std::string(r == &single ? "single" : "adaptive"));
      for (double v : r->phases) row.emplace_back(v);
      row.push_back(r->phases.back() / r->particles);
      // Redistancing, the feature sizes and resampling: the work adaptivity adds (issue goal: at most
      // a quarter of the adaptive step).
      row.push_back((r->phases[2] + r->phases[3] + r->phases[4]) / r->phases.back());
      phases.add_row(std::move(row));
    }
    h.push_back(s / kA);
    memory.push_back(single.particles / adaptive.particles);
    speed.push_back(speed_gain);
    table.add_row({fmt::format("a/{}", division), single.particles, adaptive.particles, memory.back(),
                   single.seconds_per_step, adaptive.seconds_per_step, speed.back()});
    result.expect(adaptive.particles < single.particles,
                  fmt::format("{}D, s = a/{}: adaptive {:.0f} particles, single {:.0f}", Dim, division,
                              adaptive.particles, single.particles));
    result.gate.push_back({fmt::format("{}D adaptive particles at a/{}", Dim, division),
                           GateFigure::Kind::count, std::round(adaptive.particles)});
  }
  result.tables.push_back(std::move(table));
  result.tables.push_back(std::move(phases));
  if (divisions.size() < 2) return;  // one size: no growth to assert or fit
  result.expect(memory.back() > memory.front(),
                fmt::format("{}D: the memory gain grows with resolution ({:.2f} at a/{}, {:.2f} at a/{})",
                            Dim, memory.front(), divisions.front(), memory.back(), divisions.back()));
  // gain ~ (s/a)^k: k from the two finest sizes (the coarse ones are pre-asymptotic: no coarse
  // particle fits in the column there) and from all, and where the goal would be met.
  const std::size_t n = h.size();
  Table fit(fmt::format("{}D: growth of the gains with resolution, gain ~ (s/a)^k", Dim),
            {"gain", "k (all sizes)", "k (two finest)", "goal", "s/a where the goal is met (two finest)"});
  for (const auto& [name, g, goal] : {std::tuple{"memory", &memory, 4.0}, std::tuple{"speed", &speed, 3.0}}) {
    const double k_all = fit_order(h, *g);
    const double k_last = std::log((*g)[n - 1] / (*g)[n - 2]) / std::log(h[n - 1] / h[n - 2]);
    std::string where;
    if ((*g)[n - 1] >= goal)
      where = fmt::format("met at 1/{:.0f}", 1.0 / h[n - 1]);
    else if (k_last < -0.05)
      where = fmt::format("1/{:.0f} (extrapolated)",
                          1.0 / (h[n - 1] * std::pow(goal / (*g)[n - 1], 1.0 / k_last)));
    else
      where = "not while it grows this slowly";
    fit.add_row({std::string(name), k_all, k_last, goal, where});
  }
  result.tables.push_back(std::move(fit));
}

CaseResult run_full(const CaseOptions& options) {
  CaseResult result;
  if (options.sizes) {
    const SizeList& sizes = *options.sizes;
    // The single-resolution run holds 2 N^2 (2D) or 4 N^3 (3D) particles at s = a/N; about 2 kB each
    // with its neighbour lists, so 4M is what this machine's memory allows beside the adaptive run.
    const long n = sizes.divisions.back();
    const long single = sizes.dim == 2 ? 2 * n * n : 4 * n * n * n;
    LIQUID_VERIFY(
        single <= 4'000'000,
        "--sizes {}:{}: a/{} needs {} single-resolution particles, over the 4000000 this case allows "
        "(3D up to a/100, 2D up to a/1000)",
        sizes.dim, n, n, single);
    const int steps = sizes.dim == 2 ? 80 : 40;
    if (sizes.dim == 2)
      study<2>(result, sizes.divisions, steps, options.resample_travel);
    else
      study<3>(result, sizes.divisions, steps, options.resample_travel);
    return result;
  }
  study<2>(result, {20, 40, 80, 160, 320}, 80, options.resample_travel);
  study<3>(result, {16, 24, 32, 48, 64, 80}, 40, options.resample_travel);
  return result;
}

}  // namespace

LIQUID_VERIFICATION_CASE(
    {"sph-gain-scaling",
     "SPH dam break start, single against adaptive at 2D s = a/20..a/320 and 3D s = a/16..a/80: memory and "
     "speed gains against resolution, extrapolated to the target (4x fewer particles, 3x faster)",
     false,
     run_full,
     {Option::sizes, Option::resample_travel}});

}  // namespace liquid::verification
