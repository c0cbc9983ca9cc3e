// Case sph-adaptivity-gain: what adaptive sampling saves on a dam break, and what it costs the flow
// (Adams et al. 2007, Table 1; the front against Martin and Moyce 1952).
//
// Problem. A water column a wide and 2a high (a = 0.2 m; Martin and Moyce's n^2 = 2) in the corner of
// a tank [0, 5a] x [0, 3a] (3D: 2a deep, the column filling the depth), settled behind a gate for
// 0.2 s (AdaptiveSph::relax), released at t = 0 and run to T = t sqrt(2g/a) = 3, by
//   single: all particles at level 0, spacing s;   adaptive: levels 0..3,
// both with the default passes (once the fastest particle may have travelled half a spacing;
// --resample-travel 0: the paper's every 5th step).
// Quick tier: 2D, s = a/20 (800 particles). Full tier (sph-adaptivity-gain-full): 2D s = a/80
// (12800) and 3D s = a/16.
// Measured: particles over the run (mean, and its ratio single / adaptive: the memory gain), seconds a
// step per phase and in total (their ratio: the speed gain), the front position Z = x_front / a
// (x_front = the largest x of a particle plus half its spacing) against T for both and against the
// experiment (Martin and Moyce 1952, Fig. 3, n^2 = 2, a = 2 1/4 in, as digitised in the literature),
// the largest relative difference of the adaptive front from the single one over the run, and the churn
// (merges of a split's child and splits of a merged particle within sph::kChurnPasses passes).
// Expected (targets, reported rather than asserted at this size): adaptive at least 4 times fewer
// particles and 3 times faster in 3D; front within 5% of single. Asserted: both runs finish
// without a non-finite value, the adaptive one with fewer particles on average, and both fronts
// within 25% of the experiment from T = 1.2 on (SPH without a free-surface correction runs ahead
// early, and the experiment's own gate opening delays its start).
// Gated: particles (mean) and both fronts' largest distance from the experiment; in the quick tier the
// adaptive ones are medians over 5 runs with different split-direction seeds (one run's figures move
// by more than the gate's tolerance when a sum is merely reordered). The adaptive front's distance from
// the single one is asserted below 5% for every seed in the quick tier, not gated.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>

#include <fmt/format.h>

#include "common/case.hpp"
#include "dam.hpp"
#include "liquid/core/timer.hpp"
#include "liquid/levelset/levelset.hpp"
#include "liquid/sph/adaptive_sph.hpp"

namespace liquid::verification {
namespace {

using sph_dam::kA;
using sph_dam::kGravity;
/// Martin and Moyce 1952, Fig. 3, n^2 = 2, a = 2 1/4 in: (T = t sqrt(2g/a), Z = front / a).
constexpr double kExperiment[][2] = {{0.832, 1.217}, {1.219, 1.474}, {1.997, 2.292}, {2.547, 2.995}};
using sph_dam::kPhases;
/// Split-direction seeds of the quick tier's adaptive run (the full tier's runs take minutes: one).
constexpr int kSeeds = 5;

struct Run {
  std::vector<double> T, Z;
  double particles = 0.0, seconds_per_step = 0.0;
  long steps = 0, split = 0, merged = 0, churn_merged = 0, churn_split = 0;
  int min_particles = 1 << 30, max_particles = 0;
  PhaseTimer timer;
};

template <int Dim>
Run run_dam(bool adaptive, double s, std::uint64_t seed, int merge_wait, std::optional<double> travel) {
  sph::SphOptions<Dim> options = sph_dam::options<Dim>(adaptive, s);
  options.seed = seed;
  options.merge_min_passes = merge_wait;
  if (travel) options.resample_travel = *travel;
  sph::AdaptiveSph<Dim> sim(options);
  const Box<Dim> gate = sph_dam::column<Dim>();
  sim.seed(levelset::box<Dim>(gate));
  sim.relax(0.2, &gate);
  const double scale = std::sqrt(2 * kGravity / kA), end = 3.0 / scale;
  const double dt = 0.25 * s / sph_dam::sound_speed();
  Run run;
  Stopwatch clock;
  double seconds = 0.0;
  auto record = [&] {
    const auto& p = sim.particles();
    double front = 0.0;
    for (int i = 0; i < p.size(); ++i) front = std::max(front, p.x[i][0] + 0.5 * p.radius[i] / 2.5);
    run.T.push_back(sim.time() * scale), run.Z.push_back(front / kA);
  };
  record();
  while (sim.time() < end - 1e-12) {
    clock.restart();
    const sph::SphStepReport r = sim.advance(std::min(dt, end - sim.time()));
    seconds += clock.seconds();
    ++run.steps;
    run.split += r.resampling.split, run.merged += r.resampling.merged;
    run.churn_merged += r.resampling.churn_merged, run.churn_split += r.resampling.churn_split;
    run.particles += r.particles;
    run.min_particles = std::min(run.min_particles, r.particles);
    run.max_particles = std::max(run.max_particles, r.particles);
    if (run.steps % 20 == 0) record();
  }
  record();
  run.particles /= static_cast<double>(run.steps);
  run.seconds_per_step = seconds / static_cast<double>(run.steps);
  run.timer = sim.timer();
  return run;
}

/// Z at T by linear interpolation in a run's record.
double front_at(const Run& r, double T) {
  for (std::size_t k = 1; k < r.T.size(); ++k)
    if (r.T[k] >= T) {
      const double f = (T - r.T[k - 1]) / (r.T[k] - r.T[k - 1]);
      return r.Z[k - 1] + f * (r.Z[k] - r.Z[k - 1]);
    }
  return r.Z.back();
}

/// One dam break at spacing s; pushes its front curves to `series` (the report draws them).
/// Z's largest relative difference between two runs over the first one's record.
double front_difference(const Run& a, const Run& b) {
  double worst = 0.0;
  for (std::size_t k = 0; k < a.T.size(); ++k)
    worst = std::max(worst, std::abs(front_at(b, a.T[k]) / a.Z[k] - 1.0));
  return worst;
}

/// The median of v (the upper one of an even count).
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

/// One dam break at spacing s; pushes its front curves to `series` (the report draws them). The adaptive
/// run is made once per split-direction seed (1..seeds): one split or merge decided differently changes
/// the rest of the run, and a sum in another order (round-off) does that as a new seed does, so its
/// figures are medians over the seeds.
template <int Dim>
CaseResult run_case(double s, int seeds, const std::string& tag, Json& series, int merge_wait,
                    std::optional<double> travel) {
  CaseResult result;
  const Run single = run_dam<Dim>(false, s, 1, 0, travel);
  std::vector<Run> runs;
  for (int k = 0; k < seeds; ++k) runs.push_back(run_dam<Dim>(true, s, 1 + k, merge_wait, travel));
  if (travel)
    result.notes.push_back(
        fmt::format("{}both runs resample once the fastest particle may have travelled {:g} "
                    "spacings (--resample-travel; 0: every 5th step, the paper's)",
                    tag, *travel));
  if (merge_wait > 0)
    result.notes.push_back(
        fmt::format("{}a split's children wait {} resampling passes before they may merge "
                    "(--merge-wait; the paper's: 0)",
                    tag, merge_wait));
  auto name_of = [&](const Run* r) {
    if (r == &single) return std::string("single");
    return seeds == 1 ? std::string("adaptive") : fmt::format("adaptive, seed {}", 1 + (r - runs.data()));
  };
  Table table(fmt::format("{}D dam break, s = a/{:.0f}: single resolution against adaptive (paper Table 1)",
                          Dim, kA / s),
              {"run", "particles (mean)", "min", "max", "steps", "s/step", "split", "merged",
               "churn: merged children", "churn: split merges"});
  std::vector<const Run*> all{&single};
  for (const Run& r : runs) all.push_back(&r);
  for (const Run* r : all)
    table.add_row({name_of(r), r->particles, long(r->min_particles), long(r->max_particles), r->steps,
                   r->seconds_per_step, r->split, r->merged, r->churn_merged, r->churn_split});
  Table phases(
      "seconds per step by phase (the paper's columns: neighbourhood = neighbours, projection = integrate "
      "+ collisions, redistancing = redistance)",
      {"run", "neighbours", "forces", "redistance", "elfs", "resample", "integrate", "collisions", "total"});
  for (const Run* r : all) {
    auto per = [&](const char* ph) { return r->timer.seconds(ph) / static_cast<double>(r->steps); };
    phases.add_row({name_of(r), per(kPhases[0]), per(kPhases[1]), per(kPhases[2]), per(kPhases[3]),
                    per(kPhases[4]), per(kPhases[5]), per(kPhases[6]), per(kPhases[7])});
  }
  // The adaptive figures: each one's median over the seeds.
  Run adaptive = runs.front();
  std::vector<double> particles, seconds, from_single, from_experiment;
  double worst_single = 0.0;
  for (const auto& e : kExperiment)
    if (e[0] >= 1.2) worst_single = std::max(worst_single, std::abs(front_at(single, e[0]) / e[1] - 1.0));
  for (const Run& r : runs) {
    particles.push_back(r.particles), seconds.push_back(r.seconds_per_step);
    from_single.push_back(front_difference(single, r));
    double worst = 0.0;
    for (const auto& e : kExperiment)
      if (e[0] >= 1.2) worst = std::max(worst, std::abs(front_at(r, e[0]) / e[1] - 1.0));
    from_experiment.push_back(worst);
  }
  adaptive.particles = median(particles), adaptive.seconds_per_step = median(seconds);
  const double worst_pair = median(from_single), worst_adaptive = median(from_experiment);
  if (seeds > 1)
    table.add_row({fmt::format("adaptive, median of {}", seeds), adaptive.particles, std::string("-"),
                   std::string("-"), adaptive.steps, adaptive.seconds_per_step, std::string("-"),
                   std::string("-"), std::string("-"), std::string("-")});
  const double memory = single.particles / adaptive.particles,
               speed = single.seconds_per_step / adaptive.seconds_per_step;
  Table gain("gain: memory (particles) / speed, ours beside the paper's Table 1",
             {"example", "memory gain", "speed gain"});
  gain.add_row({fmt::format("ours: {}D dam break, s = a/{:.0f}", Dim, kA / s), memory, speed});
  for (const auto& [name, m, v] :
       {std::tuple{"paper: flooding", 8.0, 6.6}, std::tuple{"paper: desk toy (2D)", 3.0, 2.8},
        std::tuple{"paper: teapot", 7.9, 7.7}, std::tuple{"paper: armadillos", 4.5, 4.3}})
    gain.add_row({std::string(name), m, v});
  Table front(
      seeds == 1
          ? std::string("front Z = x / a against T = t sqrt(2g/a)")
          : fmt::format("front Z = x / a against T = t sqrt(2g/a) (adaptive: the median of {} seeds)", seeds),
      {"T", "experiment", "single", "adaptive"});
  for (const auto& e : kExperiment) {
    std::vector<double> z;
    for (const Run& r : runs) z.push_back(front_at(r, e[0]));
    front.add_row({e[0], e[1], front_at(single, e[0]), median(z)});
  }
  result.notes.push_back(fmt::format(
      "the adaptive front differs from the single one by at most {:.1f}% over the "
      "run; from the experiment (T >= 1.2) single {:.1f}%, adaptive {:.1f}%{}",
      100 * worst_pair, 100 * worst_single, 100 * worst_adaptive,
      seeds == 1 ? std::string()
                 : fmt::format(" (adaptive: medians over {} split-direction seeds; their "
                               "spread: {:.1f}-{:.1f}% from single, particles {:.0f}-{:.0f})",
                               seeds, 100 * *std::min_element(from_single.begin(), from_single.end()),
                               100 * *std::max_element(from_single.begin(), from_single.end()),
                               *std::min_element(particles.begin(), particles.end()),
                               *std::max_element(particles.begin(), particles.end()))));
  if (memory < 4.0 || speed < 3.0 || worst_pair > 0.05)
    result.warnings.push_back(
        fmt::format("the targets (4x fewer particles, 3x faster, front within 5%) are "
                    "not met at this size: {:.2f}x, {:.2f}x, {:.1f}%",
                    memory, speed, 100 * worst_pair));
  result.expect(adaptive.particles < single.particles,
                fmt::format("adaptive used {:.0f} particles on average, single {:.0f}", adaptive.particles,
                            single.particles));
  result.expect(worst_single < 0.25 && worst_adaptive < 0.25,
                fmt::format("fronts {:.1f}% (single) and {:.1f}% (adaptive) from the experiment",
                            100 * worst_single, 100 * worst_adaptive));
  result.gate.push_back(
      {tag + "adaptive particles (mean)", seeds > 1 ? GateFigure::Kind::error : GateFigure::Kind::count,
       std::round(adaptive.particles)});  // a median over seeds moves by a few: a cost, not a count
  // The adaptive front's distance from the single one is a small difference that moves by a third
  // between seeds: asserted against the 5% target per seed, not gated.
  if (seeds > 1)
    for (int k = 0; k < seeds; ++k)
      result.expect(from_single[k] < 0.05,
                    fmt::format("adaptive (seed {}): front up to {:.1f}% from the single "
                                "run's, more than the 5% target",
                                1 + k, 100 * from_single[k]));
  result.gate.push_back({tag + "single front from experiment", GateFigure::Kind::error, worst_single});
  result.gate.push_back({tag + "adaptive front from experiment", GateFigure::Kind::error, worst_adaptive});
  std::vector<double> et, ez;
  for (const auto& e : kExperiment) et.push_back(e[0]), ez.push_back(e[1]);
  const std::string group =
      fmt::format("{}front Z = x/a against T = t sqrt(2g/a), {}D, s = a/{:.0f}", tag, Dim, kA / s);
  using Curve = std::tuple<const char*, const std::vector<double>*, const std::vector<double>*>;
  for (const auto& [label, x, y] :
       {Curve{"single", &single.T, &single.Z},
        Curve{seeds == 1 ? "adaptive" : "adaptive (seed 1)", &adaptive.T, &adaptive.Z},
        Curve{"Martin and Moyce 1952", &et, &ez}}) {
    Json curve = series_entry(group, label, *x, *y, "T", "Z = x / a");
    curve.set("scale", "linear");
    series.push(std::move(curve));
  }
  for (Table* t : {&table, &phases, &gain, &front}) result.tables.push_back(std::move(*t));
  return result;
}

CaseResult run_quick(const CaseOptions& options) {
  Json series = Json::array();
  CaseResult r =
      run_case<2>(kA / 20, kSeeds, "", series, options.merge_wait.value_or(0), options.resample_travel);
  r.fields.set("series", std::move(series));
  return r;
}

CaseResult run_full(const CaseOptions& options) {
  Json series = Json::array();
  const int wait = options.merge_wait.value_or(0);
  CaseResult result = run_case<2>(kA / 80, 1, "2D ", series, wait, options.resample_travel);
  result.append(run_case<3>(kA / 16, 1, "3D ", series, wait, options.resample_travel));
  result.fields.set("series", std::move(series));
  return result;
}

}  // namespace

LIQUID_VERIFICATION_CASE(
    {"sph-adaptivity-gain",
     "SPH dam break (2D, s = a/20): adaptive against single resolution, particles, phase times, "
     "front against Martin and Moyce (Table 1)",
     true,
     run_quick,
     {Option::merge_wait, Option::resample_travel}});
LIQUID_VERIFICATION_CASE(
    {"sph-adaptivity-gain-full",
     "SPH dam break, 2D at s = a/80 and 3D at s = a/16: the gain table beside the paper's Table 1",
     false,
     run_full,
     {Option::merge_wait, Option::resample_travel}});

}  // namespace liquid::verification
