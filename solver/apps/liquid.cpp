// liquid: runs a scene of the adaptive PIC solver (RBF Liquids) or of the adaptive SPH solver
// (Adams et al. 2007) and prints the paper's Table 1 row for it.
//
//   liquid scenes                                   the built-in scenes, one line each
//   liquid run dam-break-2d --out out/             a built-in scene (or a path to a .toml file)
//   liquid run drop-3d --finest 6 --method apic     overrides: levels, method, end
//   liquid run sph-dam-break-2d --spacing 0.005     an SPH scene; --regular: single resolution
//   liquid run dam-break-2d --method sph            a PIC scene run by SPH (spacing: half the finest cell)
//   liquid run --resume out/drop-3d_checkpoint_000040.h5 --out out/
//
// Exit status: 0 done; 1 the run failed while stepping (a NaN, a PPE that did not converge: the
// message names the step, phase and place; files written before stay); 2 bad input (a scene file,
// an option); 3 an internal error.
#include <fmt/format.h>
#include <omp.h>
#include <sys/resource.h>
#include <unistd.h>
#include <CLI/CLI.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>

#include "liquid/core/error.hpp"
#include "liquid/core/threads.hpp"
#include "liquid/io/files.hpp"
#include "liquid/linalg/solver.hpp"
#include "liquid/scene/runner.hpp"
#include "liquid/scene/sph_runner.hpp"

namespace {

using namespace liquid;

struct Args {
  std::string scene, out, json, resume;
  scene::SceneOverrides overrides;
  long checkpoint_every = 0;
  double memory_gb = 0.0;  ///< --memory: the PIC memory budget in GB (0: half the machine's memory)
  bool regular = false, adaptive = false, no_frames = false, quiet = false;
};

/// The run stopped while stepping (exit 1), as opposed to bad input (exit 2).
struct RunFailure {
  std::string message;
};

/// The last lines of the echo: when the run ends, what it writes, the threads.
void echo_time_and_output(const scene::SceneTime& time, const scene::SceneOutput& output,
                          const scene::RunSettings& settings, const char* cfl_note,
                          const std::string& threads_note = "") {
  if (time.steps >= 0)
    fmt::print("  time        {} steps", time.steps);
  else
    fmt::print("  time        to t = {} s", time.end);
  fmt::print(", CFL {}{}, dt in [{:.2g}, {:.2g}] s\n", time.cfl, cfl_note, time.dt_min, time.dt_max);
  if (settings.out.empty())
    fmt::print("  output      none (no --out)\n");
  else
    fmt::print("  output      {}: {}{}\n", settings.out,
               settings.frames ? (output.every > 0 ? fmt::format("a frame every {} s", output.every)
                                                   : std::string("first and last frame"))
                               : std::string("no frames"),
               settings.checkpoint_every > 0
                   ? fmt::format(", a checkpoint every {} steps", settings.checkpoint_every)
                   : "");
  fmt::print("  threads     {}{}\n", thread_summary(), threads_note);
  std::fflush(stdout);
}

template <int Dim>
void echo(const scene::Scene<Dim>& s, const scene::RunSettings& settings, bool resumed) {
  const pic::PicOptions<Dim>& o = s.pic;
  fmt::print("liquid run: scene {} ({}D) from {}{}\n", s.name, Dim, s.path, resumed ? " (resumed)" : "");
  if (!s.description.empty()) fmt::print("  {}\n", s.description);
  fmt::print("  domain      [{}] to [{}]\n", fmt::join(o.domain.lo.data(), o.domain.lo.data() + Dim, ", "),
             fmt::join(o.domain.hi.data(), o.domain.hi.data() + Dim, ", "));
  fmt::print("  grid        {}; finest level {} (h = {:.4g}), coarse {}, band {}, level jump {}\n",
             o.adaptive ? "adaptive tree" : "regular grid", o.finest_level,
             std::ldexp(o.domain.size().minCoeff(), -o.finest_level),
             o.adaptive ? o.coarse_level : o.finest_level, o.band,
             o.max_jump >= tree::unlimited_jump ? std::string("unlimited") : std::to_string(o.max_jump));
  const bool rbf_transfer = o.transfer == pic::PicTransfer::rbf;
  fmt::print("  method      {}{}; {}; reseeding {}{}{}{}\n", to_string(o.transfer),
             o.transfer == pic::PicTransfer::flip ? fmt::format(" (blend {})", o.flip) : "",
             o.integrator == particles::Integrator::rk2 ? "RK2" : "RK3", o.reseed ? "on" : "off",
             rbf_transfer && !o.rbf.share_factors ? "; each cell's own RBF factors" : "",
             rbf_transfer && o.rbf.condition_estimate == rbf::ConditionEstimate::hager_higham
                 ? "; full Hager-Higham condition estimates"
                 : "",
             o.poisson.nullspace == mac::Nullspace::pin ? "; a closed box's PPE pinned at one cell" : "");
  if (rbf_transfer)
    fmt::print("  transfer    {}PHS r^{} + degree {}{}{}{}\n",
               !o.adaptive || !o.uniform_patches ? ""
               : o.tent_at_level_changes
                   ? "APIC in uniform patches, particle -> face by tents and face -> particle by "
                   : "APIC in uniform patches, across level changes ",
               o.rbf.exponent, o.rbf.degree,
               o.adaptive && o.uniform_patches && o.rbf_gradient_affine ? " (its gradient as APIC's C)" : "",
               o.adaptive && o.uniform_patches && !o.tent_at_level_changes && o.level_change_tent_share > 0.0
                   ? fmt::format(", {:g}% of the tents' mean blended into its faces",
                                 100.0 * o.level_change_tent_share)
                   : "",
               s.paper_preset ? " (the paper's preset)" : "");
  if (o.reseed && rbf_transfer) {
    const int lo = Dim == 2 ? 3 : 5, hi = Dim == 2 ? 12 : 15;
    const bool open_top = o.reseeding.hi == std::numeric_limits<int>::max();
    if ((o.reseeding.lo == 0 && o.reseeding.hi == 0) ||
        (o.reseeding.lo == lo && open_top && o.reseeding.keep))
      fmt::print(
          "  reseeding   tops up cells holding fewer than {} particles (--paper: the paper's, which "
          "replaces every particle of a cell outside [{}, {}])\n",
          lo, lo, hi);
    else if (o.reseeding.lo == 1 && open_top)
      fmt::print("  reseeding   holes only\n");
    else
      fmt::print("  reseeding   {} the particles of a cell outside [{}, {}]{}\n",
                 o.reseeding.keep ? "thins or tops up" : "replaces",
                 o.reseeding.lo > 0 ? o.reseeding.lo : (Dim == 2 ? 3 : 5),
                 o.reseeding.hi > 0 ? o.reseeding.hi : (Dim == 2 ? 12 : 15),
                 s.paper_preset ? " (the paper's preset)" : "");
  }
  if (o.reseed && o.adaptive && o.refill_emptied)
    fmt::print(
        "  refill      cells inside the liquid that a step leaves empty (refill_emptied = false: not)\n");
  fmt::print("  surface     {}\n",
             o.surface == pic::PicSurface::air_cells
                 ? std::string("p = 0 at the air cells' centres")
                 : fmt::format("p = 0 at the particles' level set (radius {} h)", o.surface_radius));
  if (o.projection == pic::PicProjection::mass)
    fmt::print(
        "  projection  orthogonal in the faces' transferred masses (lightest face {} of a full cell's); it "
        "does not keep a still pool still (hydrostatic-pool)\n",
        o.min_face_mass);
  const bool amg = linalg::uses_amg(o.solver.kind);
  fmt::print("  ppe         {} to {:.1e}{}{}{}\n", linalg::to_string(o.solver.kind), o.solver.tolerance,
             !amg ? std::string()
             : o.solver.amg.reuse_factor > 0
                 ? fmt::format("; hierarchy kept while the layout stays (rebuilt past "
                               "{}x its first iterations)",
                               o.solver.amg.reuse_factor)
                 : std::string("; a new hierarchy every step"),
             o.ppe_fallback && !amg ? "; bicgstab-amg where it does not converge" : "",
             o.continue_on_ppe_failure ? ", going on when it does not converge" : "");
  if (o.adaptive)
    fmt::print(
        "  rbf-fd      PHS r^{} + degree {} rows at T-junctions on whole rings; face gradients degree {}{}\n",
        o.poisson.rbf.exponent, o.poisson.rbf.degree, o.poisson.gradient_degree,
        o.poisson.gradient_ring_cap > 0.0
            ? fmt::format(" on the nearest {:g}x their stencil size (ppe_gradient_cap)",
                          o.poisson.gradient_ring_cap)
            : std::string(" on whole rings"));
  if (linalg::needs_symmetric(o.solver.kind))
    fmt::print(
        "              (while the liquid fills the box the PPE is bordered and indefinite: BiCGSTAB with "
        "the same preconditioner solves it)\n");
  fmt::print("  gravity     ({}); solids {}; sources {}\n",
             fmt::join(o.gravity.data(), o.gravity.data() + Dim, ", "), o.solid ? "yes" : "none",
             o.sources.size());
  echo_time_and_output(s.time, s.output, settings, "");
}

template <int Dim>
void echo_sph(const scene::Scene<Dim>& s, const scene::RunSettings& settings, bool resumed) {
  const sph::SphOptions<Dim> o = scene::sph_options<Dim>(s);
  const scene::SphScene<Dim>& sc = s.sph_scene;
  fmt::print("liquid run: scene {} ({}D, SPH) from {}{}\n", s.name, Dim, s.path, resumed ? " (resumed)" : "");
  if (!s.description.empty()) fmt::print("  {}\n", s.description);
  fmt::print("  container   [{}] to [{}]\n",
             fmt::join(o.container.lo.data(), o.container.lo.data() + Dim, ", "),
             fmt::join(o.container.hi.data(), o.container.hi.data() + Dim, ", "));
  const std::string cadence =
      o.resample_travel > 0.0
          ? fmt::format(
                "{} at least {} steps apart, once the fastest particle may have travelled {:g} spacings",
                o.adaptive ? "resampled" : "redistanced", o.resample_every, o.resample_travel)
          : fmt::format("{} every {} steps", o.adaptive ? "resampled" : "redistanced", o.resample_every);
  fmt::print("  particles   spacing {:.4g} m (support radius {:.4g}), {}; {}\n", o.spacing,
             o.h_ratio * o.spacing,
             o.adaptive ? fmt::format("adaptive, levels 0-{} (alpha {}, beta {}){}", o.max_level,
                                      o.resampling.alpha, o.resampling.beta,
                                      o.merge_min_passes > 0
                                          ? fmt::format(", a split's children kept {} passes before a merge",
                                                        o.merge_min_passes)
                                          : "")
                        : std::string("single resolution (level 0 only)"),
             cadence);
  fmt::print("  fluid       rho_0 {} kg/m^{}, sound speed {:.3g} m/s{}, viscosity {} Pa s\n",
             o.fluid.rest_density, Dim, scene::sph_sound_speed<Dim>(s),
             sc.sound_speed > 0 ? "" : " (10x the fastest expected speed)", o.fluid.viscosity);
  fmt::print("  model       kernels {}, density {}, pressure {}, neighbours {}, surface {}\n",
             sph::to_string(o.fluid.kernels), sph::to_string(o.fluid.density_update),
             sph::to_string(o.fluid.pressure_form), sph::to_string(o.search), sph::to_string(sc.surface));
  fmt::print("  gravity     ({}); solids {}; sources {}{}\n",
             fmt::join(o.gravity.data(), o.gravity.data() + Dim, ", "), o.obstacles.empty() ? "none" : "yes",
             o.sources.size(),
             o.rotation.active()
                 ? fmt::format("; the container turns {:.4g} degrees in {} s",
                               o.rotation.angle * 180.0 / 3.141592653589793, o.rotation.duration)
                 : "");
  if (sc.settle > 0)
    fmt::print("  settle      {} s before t = 0{}\n", sc.settle, sc.gate ? ", held behind the gate" : "");
  echo_time_and_output(
      s.time, s.output, settings, " (of the sound speed)",
      o.serial_below > 0 ? fmt::format("; a step with fewer than {} particles on one thread", o.serial_below)
                         : "");
}

/// One line of progress: a bar on a terminal (rewritten in place), plain lines otherwise.
class Progress {
 public:
  explicit Progress(bool quiet) : tty_(isatty(fileno(stdout)) != 0), quiet_(quiet) {}
  template <int Dim>
  void update(const scene::SceneRunner<Dim>& run, bool last) {
    const scene::Scene<Dim>& s = run.scene();
    const pic::AdaptivePic<Dim>& sim = run.solver();
    const pic::PicStepReport& r = run.last();
    show(fraction(s, sim.steps(), sim.time()),
         fmt::format("t = {:.4f} s  step {}  particles {}  cells {} ({} fluid)  {:.3f} s/step", sim.time(),
                     sim.steps(), r.n_particles, r.n_cells, r.n_fluid_cells, per_step(sim.timer())),
         last);
  }
  template <int Dim>
  void update(const scene::SphSceneRunner<Dim>& run, bool last) {
    const scene::Scene<Dim>& s = run.scene();
    const sph::AdaptiveSph<Dim>& sim = run.solver();
    const sph::SphStepReport& r = run.last();
    std::string levels;
    for (std::size_t l = 0; l < r.per_level.size(); ++l)
      levels += fmt::format("{}{}", l ? "/" : "", r.per_level[l]);
    show(fraction(s, sim.steps(), sim.time()),
         fmt::format("t = {:.4f} s  step {}  particles {} (levels {})  {:.4f} s/step", sim.time(),
                     sim.steps(), r.particles, levels, per_step(sim.timer())),
         last);
  }

 private:
  template <int Dim>
  static double fraction(const scene::Scene<Dim>& s, long step, double time) {
    return s.time.steps >= 0 ? static_cast<double>(step) / s.time.steps : time / s.time.end;
  }
  static double per_step(const PhaseTimer& timer) {
    const auto& phases = timer.entries();
    const auto total = phases.find("total");
    return total != phases.end() && total->second.calls > 0 ? total->second.seconds / total->second.calls
                                                            : 0.0;
  }
  void show(double f, const std::string& text, bool last) {
    if (quiet_) return;
    if (tty_) {
      const int width = 24, filled = static_cast<int>(std::round(std::clamp(f, 0.0, 1.0) * width));
      fmt::print("\r[{}{}] {:3.0f}%  {}\033[K", std::string(filled, '#'), std::string(width - filled, '.'),
                 100 * std::clamp(f, 0.0, 1.0), text);
      if (last) fmt::print("\n");
    } else {
      const int decile = static_cast<int>(std::floor(std::clamp(f, 0.0, 1.0) * 10));
      if (decile > printed_ || last) {
        printed_ = decile;
        fmt::print("  {:3.0f}%  {}\n", 100 * std::clamp(f, 0.0, 1.0), text);
      }
    }
    std::fflush(stdout);
  }

  bool tty_, quiet_;
  int printed_ = -1;
};

/// The paper's Table 1 row (RBF Liquids, Sec. 6) and every phase.
void print_summary(const scene::RunSummary& s, const std::string& name, int dim) {
  const auto pct = [](double a, double b) { return b > 0 ? 100.0 * a / b : 0.0; };
  const auto sec = [&](const char* phase) {
    const auto it = s.seconds.find(phase);
    return it == s.seconds.end() ? 0.0 : it->second;
  };
  fmt::print("\nTable 1 row ({}, {}D, {} steps to t = {:.4g} s, {} threads)\n", name, dim, s.steps, s.time,
             s.threads);
  fmt::print("  {:>12} {:>8} {:>12} {:>8} {:>9} {:>9} {:>11} {:>10} {:>9}\n", "fluid cells", "% reg",
             "particles", "% reg", "grid s", "ppe s", "laplacian s", "transfer s", "total s");
  fmt::print("  {:>12.0f} {:>7.1f}% {:>12.0f} {:>7.1f}% {:>9.4f} {:>9.4f} {:>11.4f} {:>10.4f} {:>9.4f}\n",
             s.fluid_cells, pct(s.fluid_cells, s.regular_cells), s.particles,
             pct(s.particles, s.regular_particles), sec("grid"), sec("ppe"), sec("laplacian"),
             sec("p2g") + sec("g2p"), sec("total"));
  fmt::print(
      "  regular grid at the same finest h, for the same liquid: {:.0f} fluid cells, {:.0f} particles\n",
      s.regular_cells, s.regular_particles);
  fmt::print(
      "  (computed from this run's fluid cells and its finest cells' particle density; a regular run\n"
      "   gives the measured figures: liquid run SCENE --method apic, or ci/bench-scenes)\n");
  fmt::print("  seconds per step by phase:");
  for (const auto& [phase, t] : s.seconds) fmt::print(" {} {:.4f}", phase, t);
  fmt::print("\n  PPE: {} iterations in all ({:.1f} per step){}{}{}\n", s.ppe_iterations,
             static_cast<double>(s.ppe_iterations) / std::max<long>(1, s.steps),
             s.ppe_reused
                 ? fmt::format(", {} of {} steps kept the last step's preconditioner", s.ppe_reused, s.steps)
                 : "",
             s.ppe_fallbacks ? fmt::format(", {} solves fell back to bicgstab-amg", s.ppe_fallbacks) : "",
             s.ppe_failures ? fmt::format(", {} steps did not converge", s.ppe_failures) : "");
  fmt::print("  wall time {:.2f} s\n", s.wall);
}

/// This machine's physical memory, in bytes.
double machine_memory() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page > 0 ? static_cast<double>(pages) * static_cast<double>(page) : 16e9;
}

/// Refuses, before anything is built, a PIC run whose start is estimated above the memory budget.
template <int Dim>
void check_memory_budget(const scene::Scene<Dim>& s, double memory_gb) {
  const scene::PicSize size = scene::estimate_pic_size<Dim>(s);
  const double budget = memory_gb > 0.0 ? memory_gb * 1e9 : machine_memory();
  LIQUID_VERIFY(size.bytes <= budget,
                "{}: at finest level {} the run would start with about {:.3g} particles and {:.3g} cells, "
                "about {:.3g} GB, over the budget of {:.3g} GB ({}); a smaller grid.finest (--finest) runs, "
                "--memory GB raises the budget",
                s.path, s.pic.finest_level, size.particles, size.cells, size.bytes / 1e9, budget / 1e9,
                memory_gb > 0.0 ? "--memory" : "this machine's memory");
}

/// The process's peak resident memory so far, in MB (getrusage; Linux reports kB).
double peak_memory_mb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;
}

void write_json(const std::string& path, const scene::RunSummary& s, const std::string& name, int dim) {
  std::string phases;
  for (const auto& [phase, t] : s.seconds)
    phases += fmt::format("{}\"{}\": {:.6g}", phases.empty() ? "" : ", ", phase, t);
  const std::string text = fmt::format(
      "{{\n  \"scene\": \"{}\", \"dimension\": {}, \"steps\": {}, \"time\": {:.9g}, \"threads\": {},\n"
      "  \"fluid_cells\": {:.6g}, \"cells\": {:.6g}, \"particles\": {:.6g},\n"
      "  \"regular_cells\": {:.6g}, \"regular_particles\": {:.6g},\n"
      "  \"ppe_iterations\": {}, \"ppe_failures\": {}, \"ppe_reused\": {}, \"ppe_fallbacks\": {},\n"
      "  \"wall_seconds\": {:.6g},\n"
      "  \"peak_memory_mb\": {:.1f},\n"
      "  \"seconds_per_step\": {{{}}}\n}}\n",
      name, dim, s.steps, s.time, s.threads, s.fluid_cells, s.cells, s.particles, s.regular_cells,
      s.regular_particles, s.ppe_iterations, s.ppe_failures, s.ppe_reused, s.ppe_fallbacks, s.wall,
      peak_memory_mb(), phases);
  liquid::io::write_text_file(path, text);
}

/// The paper's Table 1 columns (Adams et al. 2007, Sec. 6) and every phase.
/// `serial_below`: the run's [sph] serial_below; the header says when some steps ran on one thread.
void print_sph_summary(const scene::SphRunSummary& s, const std::string& name, int dim, bool adaptive,
                       int serial_below) {
  const auto sec = [&](const char* phase) {
    const auto it = s.seconds.find(phase);
    return it == s.seconds.end() ? 0.0 : it->second;
  };
  const std::string serial =
      s.threads > 1 && s.min_particles < serial_below
          ? fmt::format("; the steps with fewer than {} particles on one", serial_below)
          : "";
  fmt::print("\nTable 1 row, {} SPH ({}, {}D, {} steps to t = {:.4g} s, {} threads{})\n",
             adaptive ? "adaptive" : "single-resolution (--regular)", name, dim, s.steps, s.time, s.threads,
             serial);
  fmt::print("  {:>10} {:>10} {:>8} {:>11} {:>8} {:>10} {:>9} {:>8} {:>9} {:>9}\n", "particles", "single res",
             "gain", "neighbours", "forces", "projection", "redist.", "elfs", "resample", "total s");
  fmt::print(
      "  {:>10.0f} {:>10.0f} {:>7.2f}x {:>11.4f} {:>8.4f} {:>10.4f} {:>9.4f} {:>8.4f} {:>9.4f} {:>9.4f}\n",
      s.particles, s.single_particles, s.particles > 0 ? s.single_particles / s.particles : 0.0,
      sec("neighbours"), sec("forces"), sec("integrate") + sec("collisions"), sec("redistance"), sec("elfs"),
      sec("resample"), sec("total"));
  fmt::print(
      "  single res: the level-0 particles a single-resolution run holds for the same liquid (its mass in\n"
      "  level-0 particles; a measured single-resolution run: the same command with --regular)\n");
  std::string levels;
  for (std::size_t l = 0; l < s.per_level.size(); ++l)
    levels += fmt::format("{}{:.0f}", l ? " / " : "", s.per_level[l]);
  fmt::print("  particles per level (mean): {}; fewest {}, most {}\n", levels, s.min_particles,
             s.max_particles);
  fmt::print("  split {}, merged {}, added by sources {}\n", s.split, s.merged, s.emitted);
  if (s.split + s.merged > 0)
    fmt::print(
        "  churn       {} merges of a split's child, {} splits of a merged particle, within {} passes\n",
        s.churn_merged, s.churn_split, sph::kChurnPasses);
  fmt::print(
      "  largest compression {:.3g}%; largest density error {:.3g}% (with spray and fragments, which expand "
      "at zero pressure); at most {} particles alone at once (their densities set to rest)\n",
      100 * s.max_compression, 100 * s.max_density_error, s.rested);
  fmt::print("  spacing {:.4g} m, sound speed {:.3g} m/s\n", s.spacing, s.sound_speed);
  fmt::print("  seconds per step by phase:");
  for (const auto& [phase, t] : s.seconds) fmt::print(" {} {:.5f}", phase, t);
  fmt::print("\n  wall time {:.2f} s\n", s.wall);
}

void write_sph_json(const std::string& path, const scene::SphRunSummary& s, const std::string& name, int dim,
                    bool adaptive) {
  std::string phases, levels;
  for (const auto& [phase, t] : s.seconds)
    phases += fmt::format("{}\"{}\": {:.6g}", phases.empty() ? "" : ", ", phase, t);
  for (std::size_t l = 0; l < s.per_level.size(); ++l)
    levels += fmt::format("{}{:.6g}", l ? ", " : "", s.per_level[l]);
  liquid::io::write_text_file(
      path,
      fmt::format(
          "{{\n  \"scene\": \"{}\", \"method\": \"sph\", \"adaptive\": {}, \"dimension\": {}, \"steps\": {}, "
          "\"time\": {:.9g}, "
          "\"threads\": {},\n  \"particles\": {:.6g}, \"single_particles\": {:.6g}, \"min_particles\": {}, "
          "\"max_particles\": {},\n  \"particles_per_level\": [{}], \"split\": {}, \"merged\": {}, "
          "\"emitted\": {},\n"
          "  \"max_density_error\": {:.6g}, \"max_compression\": {:.6g}, \"rested\": {}, \"spacing\": "
          "{:.6g}, \"sound_speed\": {:.6g}, \"wall_seconds\": "
          "{:.6g},\n"
          "  \"seconds_per_step\": {{{}}}\n}}\n",
          name, adaptive, dim, s.steps, s.time, s.threads, s.particles, s.single_particles, s.min_particles,
          s.max_particles, levels, s.split, s.merged, s.emitted, s.max_density_error, s.max_compression,
          s.rested, s.spacing, s.sound_speed, s.wall, phases));
}

scene::RunSettings settings_of(const Args& a, const std::string& scene_path) {
  scene::RunSettings settings;
  settings.out = a.out;
  settings.frames = !a.no_frames;
  settings.checkpoint_every = a.checkpoint_every;
  settings.overrides = a.overrides;
  settings.scene_path = scene_path;
  return settings;
}

/// Steps a run (SceneRunner or SphSceneRunner) to its end with a progress line; an error while
/// stepping is a RunFailure (exit 1) that says the files written so far are complete.
template <class Runner>
void run_to_end(Runner& run, const Args& a) {
  Progress progress(a.quiet);
  while (!run.done()) {
    try {
      run.step();
    } catch (const Error& e) {
      throw RunFailure{
          fmt::format("{}{}", e.what(),
                      a.out.empty() ? "" : fmt::format(" (files written so far in {} are complete)", a.out))};
    }
    progress.update(run, run.done());
  }
}

template <int Dim>
int run_sph(const Args& a, const std::string& scene_path, scene::Scene<Dim>* loaded) {
  const scene::RunSettings settings = settings_of(a, scene_path);
  std::unique_ptr<scene::SphSceneRunner<Dim>> run;
  if (!a.resume.empty()) {
    run =
        std::make_unique<scene::SphSceneRunner<Dim>>(scene::SphSceneRunner<Dim>::resume(a.resume, settings));
    echo_sph<Dim>(run->scene(), settings, true);
    fmt::print("  continuing from step {} (t = {:.6g} s)\n", run->solver().steps(), run->solver().time());
  } else {
    echo_sph<Dim>(*loaded, settings, false);
    const std::string fluid_where = loaded->fluid_where;
    try {
      run = std::make_unique<scene::SphSceneRunner<Dim>>(std::move(*loaded), settings);
    } catch (const InputError& e) {
      throw Error(fmt::format("{}: the [[fluid]] shapes, less the solids, leave the run no liquid: {}",
                              fluid_where, e.what()));
    } catch (const Error& e) {
      throw RunFailure{fmt::format("the start of the run (seeding, the first frame) failed: {}", e.what())};
    }
  }
  run_to_end(*run, a);
  const scene::SphRunSummary s = run->summary();
  print_sph_summary(s, run->scene().name, Dim, run->scene().adaptive,
                    scene::sph_options<Dim>(run->scene()).serial_below);
  if (!a.json.empty()) write_sph_json(a.json, s, run->scene().name, Dim, run->scene().adaptive);
  if (!a.out.empty()) fmt::print("  frames: {} in {}/{}.xmf\n", run->n_frames(), a.out, run->scene().name);
  return 0;
}

template <int Dim>
int run_scene(const Args& a, const std::string& scene_path) {
  const scene::RunSettings settings = settings_of(a, scene_path);
  std::unique_ptr<scene::SceneRunner<Dim>> run;
  if (!a.resume.empty()) {
    if (scene::checkpoint_is_sph(a.resume)) return run_sph<Dim>(a, scene_path, nullptr);
    run = std::make_unique<scene::SceneRunner<Dim>>(scene::SceneRunner<Dim>::resume(a.resume, settings));
  } else {
    scene::Scene<Dim> scene = scene::load_scene<Dim>(scene_path);
    scene::apply_overrides<Dim>(a.overrides, scene);
    if (scene.sph) return run_sph<Dim>(a, scene_path, &scene);
    check_memory_budget<Dim>(scene, a.memory_gb);
    echo<Dim>(scene, settings, false);
    const std::string fluid_where = scene.fluid_where;
    try {
      run = std::make_unique<scene::SceneRunner<Dim>>(std::move(scene), settings);
    } catch (const InputError& e) {
      throw Error(fmt::format("{}: the [[fluid]] shapes, less the solids, leave the run no liquid: {}",
                              fluid_where, e.what()));
    } catch (const Error& e) {
      throw RunFailure{fmt::format("the start of the run (seeding, the first frame) failed: {}", e.what())};
    }
  }
  if (!a.resume.empty()) {
    echo<Dim>(run->scene(), settings, true);
    fmt::print("  continuing from step {} (t = {:.6g} s)\n", run->solver().steps(), run->solver().time());
  }
  run_to_end(*run, a);
  const scene::RunSummary s = run->summary();
  print_summary(s, run->scene().name, Dim);
  if (!a.json.empty()) write_json(a.json, s, run->scene().name, Dim);
  if (!a.out.empty()) fmt::print("  frames: {} in {}/{}.xmf\n", run->n_frames(), a.out, run->scene().name);
  return 0;
}

/// One Markdown row of a built-in scene, read from its file.
template <int Dim>
void print_scene_row(const std::string& name, const std::string& path) {
  const scene::Scene<Dim> s = scene::load_scene<Dim>(path);
  const std::string grid =
      s.sph ? std::string("particles") : fmt::format("{} / {}", s.pic.coarse_level, s.pic.finest_level);
  const std::string length =
      std::isfinite(s.time.end) ? fmt::format("{:g}", s.time.end) : fmt::format("{} steps", s.time.steps);
  const std::string method =
      s.sph ? std::string("adaptive SPH")
            : (s.pic.adaptive ? std::string("adaptive ") : std::string("regular ")) + s.method();
  fmt::print("| `{}` | {}D | {} | {} | {} | {} | {} |\n", name, Dim, method,
             s.figure.empty() ? std::string("-") : s.figure, s.description, grid, length);
}

/// The built-in scenes as the README's Markdown table.
void print_scene_table() {
  fmt::print(
      "| scene | dim | method | paper figure | what it shows | levels (coarse / finest) | simulated (s) |\n");
  fmt::print("| --- | --- | --- | --- | --- | --- | --- |\n");
  for (const auto& [name, description] : scene::builtin_scenes()) {
    const std::string path = scene::find_scene(name);
    if (scene::scene_dimension(path) == 2)
      print_scene_row<2>(name, path);
    else
      print_scene_row<3>(name, path);
  }
}

}  // namespace

int main(int argc, char** argv) {
  use_passive_waiting(argv);
  CLI::App app{
      "liquid: the adaptive RBF liquid solver, its regular PIC/FLIP/APIC baselines, and adaptive SPH"};
  app.require_subcommand(1);
  auto* scenes = app.add_subcommand("scenes", "list the built-in scenes");
  bool scenes_markdown = false;
  scenes->add_flag("--markdown", scenes_markdown, "print the scenes as a Markdown table (the README's)");
  Args a;
  auto* run = app.add_subcommand("run", "run a scene (a built-in name or a .toml file)");
  run->add_option("scene", a.scene, "built-in scene name or path to a scene file");
  run->add_option("--out", a.out, "folder for frames (HDF5 + XDMF) and checkpoints");
  auto* steps =
      run->add_option("--steps", a.overrides.steps, "run this many steps (instead of the scene's end)")
          ->check(CLI::PositiveNumber);
  run->add_option("--until", a.overrides.until, "run to this time in seconds (instead of the scene's end)")
      ->check(CLI::PositiveNumber)
      ->excludes(steps);
  run->add_option("--method", a.overrides.method,
                  "rbf, pic, flip, apic (pic, flip, apic run on a regular grid) or sph (adaptive SPH)")
      ->check(CLI::IsMember({"rbf", "pic", "flip", "apic", "sph"}));
  run->add_option(
         "--surface", a.overrides.surface,
         "PIC: air (p = 0 in the air cells) or levelset (p = 0 at the particles' level set); SPH: the "
         "surface meshed in the frames, distance, zhu-bridson or blobby")
      ->check(CLI::IsMember({"air", "levelset", "distance", "zhu-bridson", "blobby"}));
  run->add_option("--spacing", a.overrides.spacing, "SPH: the level-0 particle spacing in metres")
      ->check(CLI::PositiveNumber);
  run->add_option("--solver", a.overrides.solver, "PPE solver (instead of the scene's)")
      ->check(CLI::IsMember(linalg::solver_names()));
  run->add_option(
         "--amg-reuse", a.overrides.amg_reuse,
         "AMG: keep the hierarchy while the PPE's layout stays, rebuilding it once a step needs more "
         "than this many times the iterations of the step that built it; 0: rebuild every step")
      ->check(CLI::Range(0.0, 100.0));
  auto* regular = run->add_flag("--regular", a.regular,
                                "run on a regular grid at the finest level (SPH: single resolution)");
  run->add_flag("--adaptive", a.adaptive, "run on the adaptive tree (rbf) or with adaptive particles (sph)")
      ->excludes(regular);
  run->add_flag("--paper", a.overrides.paper,
                "the paper's exact transfer (PHS r^5 + degree 2) and reseeding, instead of the defaults");
  run->add_option("--finest", a.overrides.finest, "finest level (the coarse level moves with it)")
      ->check(CLI::Range(1, 20));
  run->add_option("--json", a.json, "write the summary (Table 1 row, phases) as JSON to FILE");
  run->add_option("--checkpoint-every", a.checkpoint_every, "write a checkpoint every N steps (needs --out)")
      ->check(CLI::PositiveNumber);
  run->add_option("--resume", a.resume, "continue the run saved in this checkpoint")
      ->check(CLI::ExistingFile);
  run->add_flag("--no-frames", a.no_frames, "write no frames (checkpoints still)");
  run->add_flag("--quiet", a.quiet, "no progress lines");
  run->add_option("--memory", a.memory_gb,
                  "PIC: refuse a run estimated to need more than GB gigabytes at its start (default: this "
                  "machine's memory)")
      ->check(CLI::PositiveNumber);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }

  try {
    if (*scenes) {
      if (scenes_markdown) {
        print_scene_table();
        return 0;
      }
      for (const auto& [name, description] : scene::builtin_scenes())
        fmt::print("{:<26} {}\n", name, description);
      return 0;
    }
    LIQUID_VERIFY(std::isfinite(a.memory_gb), "--memory: {} is not a number of gigabytes", a.memory_gb);
    if (a.regular) a.overrides.adaptive = 0;
    if (a.adaptive) a.overrides.adaptive = 1;
    LIQUID_VERIFY(!a.scene.empty() || !a.resume.empty(),
                  "liquid run: give a scene (liquid scenes lists them) or --resume FILE");
    LIQUID_VERIFY(a.scene.empty() || a.resume.empty(),
                  "liquid run: give a scene or --resume, not both (a checkpoint names its scene)");
    if (!a.resume.empty())
      LIQUID_VERIFY(
          a.overrides.method.empty() && a.overrides.adaptive < 0 && a.overrides.finest < 0 &&
              a.overrides.steps < 0 && a.overrides.until < 0 && a.overrides.surface.empty() &&
              a.overrides.solver.empty() && a.overrides.amg_reuse == -1 && a.overrides.spacing == -1 &&
              !a.overrides.paper,
          "liquid run --resume continues the saved run as it was: --method, --regular, --adaptive, --finest, "
          "--spacing, --surface, --solver, --amg-reuse, --paper, --steps and --until are refused with it");
    LIQUID_VERIFY(a.checkpoint_every == 0 || !a.out.empty(),
                  "liquid run: --checkpoint-every needs an output folder (--out DIR)");
    // Every output is checked before any work, so that a run cannot fail at its end for a path.
    if (run->count("--out")) liquid::io::check_output_folder("--out", a.out);
    if (run->count("--json")) liquid::io::check_output_file("--json", a.json);
    int dim = 0;
    std::string path;
    if (a.resume.empty()) {
      path = scene::find_scene(a.scene);
      dim = scene::scene_dimension(path);
    } else {
      dim = static_cast<int>(scene::checkpoint_dimension(a.resume));
    }
    return dim == 2 ? run_scene<2>(a, path) : run_scene<3>(a, path);
  } catch (const RunFailure& f) {
    fmt::print(stderr, "\nliquid: the run failed: {}\n", f.message);
    return 1;
  } catch (const liquid::Error& e) {
    fmt::print(stderr, "liquid: error: {}\n", e.what());
    return 2;
  } catch (const std::bad_alloc&) {
    fmt::print(stderr, "liquid: internal error: out of memory (a smaller --finest needs less)\n");
    return 3;
  } catch (const std::exception& e) {
    fmt::print(stderr, "liquid: internal error: {}\n", e.what());
    return 3;
  }
}
