// Case scene-smoke: every built-in scene runs a few steps at coarse levels, with frames.
//
// SPH (solver.method = "sph", and every 2D PIC scene run by SPH as `liquid run --method sph` would):
// 6 steps through SphSceneRunner at a coarse spacing (SPH scenes: 0.02 in 2D, 0.05 in 3D; PIC scenes:
// half their finest cell at level 5), settling first where the scene asks. Measured: the liquid's
// mass in level-0 particles before and after (split and merge conserve it; sources add exactly
// what they emitted), the phases timed, the frames (particles and surface mesh) written.
// Expected: the mass kept to round-off (1e-12), `total` timed once per step (and `sources` in scenes
// with sources), at least two frames.
//
// Problem. Each scene of solver/scenes (2D at finest level 5, 3D at 3, the coarse level shifted
// with it) runs 6 steps through SceneRunner, as `liquid run` does, with its frames written to a
// temporary folder; the 2D scenes run again with the regular APIC baseline, and with the
// level-set surface (p = 0 at the particles' level set). A NaN, a PPE that does not converge or a
// refused state stops the run: the case records it as a failure.
// Measured: the fluid volume (sum of fluid cell volumes) and the particle count after 6 steps
// against the start; the phases timed; the frames written.
// Expected: no failure; the volume changes by at most the volume of the surface cells (a free
// surface moving across a coarse grid changes the cell count by a layer; sources only add); every
// phase of the step timed once per step (grid on adaptive trees only, sources only in scenes with
// sources); at least two frames.

#include <filesystem>

#include <fmt/format.h>

#include "common/case.hpp"
#include "liquid/scene/runner.hpp"
#include "liquid/scene/sph_runner.hpp"

namespace liquid::verification {
namespace {

constexpr long kSteps = 6;

template <int Dim>
double fluid_volume(const pic::AdaptivePic<Dim>& sim) {
  return pic::volume_of<Dim>(sim.graph(), sim.classification().fluid);
}

/// The volume of one layer of surface cells: what a moving surface can add to or take from the
/// cell-counted volume without any liquid being lost.
template <int Dim>
double surface_volume(const pic::AdaptivePic<Dim>& sim) {
  return pic::volume_of<Dim>(sim.graph(), sim.classification().surface);
}

template <int Dim>
void smoke(const std::string& name, const std::string& method, Table& table, CaseResult& result,
           const std::string& surface = "") {
  const std::string path = scene::find_scene(name);
  scene::Scene<Dim> scene = scene::load_scene<Dim>(path);
  scene::SceneOverrides o;
  o.finest = Dim == 2 ? 5 : 3;
  o.steps = kSteps;
  o.method = method;
  o.surface = surface;
  const std::string label = surface.empty() ? method : method + "-" + surface;
  scene::apply_overrides<Dim>(o, scene);
  scene::RunSettings settings;
  settings.out =
      (std::filesystem::temp_directory_path() / "liquid-scene-smoke" / (name + "-" + label)).string();
  std::filesystem::remove_all(settings.out);
  settings.overrides = o;
  settings.scene_path = path;
  const bool sources = !scene.pic.sources.empty();
  const bool adaptive = scene.pic.adaptive;
  const std::string key = fmt::format("{} {}", name, label);
  try {
    scene::SceneRunner<Dim> run(std::move(scene), settings);
    const double v0 = fluid_volume(run.solver());
    double layer = surface_volume(run.solver()) / v0;
    const long n0 = run.solver().particles().size();
    while (!run.done()) run.step();
    const double change = fluid_volume(run.solver()) / v0 - 1.0;
    layer = std::max(layer, surface_volume(run.solver()) / v0);
    const long n1 = run.solver().particles().size();
    const scene::RunSummary s = run.summary();
    int timed = 0, expected = 0;
    for (const char* phase : {"sources", "classify", "grid", "p2g", "forces", "laplacian", "ppe", "project",
                              "extrapolate", "g2p", "advect", "reseed", "total"}) {
      const std::string p = phase;
      if ((p == "grid" && !adaptive) || (p == "sources" && !sources)) continue;
      ++expected;
      const auto& e = run.solver().timer().entries();
      const auto it = e.find(p);
      if (it != e.end() && it->second.calls == kSteps) ++timed;
      result.expect(it != e.end() && it->second.calls == kSteps,
                    fmt::format("{}: phase {} timed {} times in {} steps", key, p,
                                it == e.end() ? 0 : it->second.calls, kSteps));
    }
    table.add_row({long(Dim), name, label, long(s.steps), s.time, n0, n1, change, layer, long(timed),
                   long(expected), long(run.n_frames()), s.seconds.at("total")});
    result.expect(
        sources ? change >= -layer : std::abs(change) <= layer,
        fmt::format("{}: fluid volume changed by {:.2f}% in {} steps, more than a layer of surface cells "
                    "({:.2f}%)",
                    key, 100 * change, kSteps, 100 * layer));
    result.expect(run.n_frames() >= 2, fmt::format("{}: {} frames written", key, run.n_frames()));
    result.gate.push_back(
        {key + " volume change", GateFigure::Kind::error, std::max(std::abs(change), 1e-6)});
  } catch (const Error& e) {
    result.expect(false, fmt::format("{}: {}", key, e.what()));
    table.add_row({long(Dim), name, label, 0L, 0.0, 0L, 0L, 0.0, 0.0, 0L, 0L, 0L, 0.0});
  }
}

template <int Dim>
void smoke_sph(const std::string& name, Table& table, CaseResult& result) {
  const std::string path = scene::find_scene(name);
  scene::Scene<Dim> scene = scene::load_scene<Dim>(path);
  scene::SceneOverrides o;
  o.steps = kSteps;
  if (scene.sph)
    o.spacing = Dim == 2 ? 0.02 : 0.05;
  else
    o.method = "sph", o.finest = 5;
  scene::apply_overrides<Dim>(o, scene);
  scene::RunSettings settings;
  settings.out = (std::filesystem::temp_directory_path() / "liquid-scene-smoke" / (name + "-sph")).string();
  std::filesystem::remove_all(settings.out);
  settings.overrides = o;
  settings.scene_path = path;
  const bool sources = !scene.pic.sources.empty();
  const std::string key = fmt::format("{} sph", name);
  const auto level0 = [](const sph::AdaptiveSph<Dim>& sim) {
    return sim.particles().total_mass() / sim.sizes().mass;
  };
  try {
    scene::SphSceneRunner<Dim> run(std::move(scene), settings);
    const double m0 = level0(run.solver());
    const long n0 = run.solver().particles().size();
    while (!run.done()) run.step();
    const scene::SphRunSummary s = run.summary();
    const double change = (level0(run.solver()) - static_cast<double>(s.emitted)) / m0 - 1.0;
    const auto& e = run.solver().timer().entries();
    const auto calls = [&](const char* phase) {
      const auto it = e.find(phase);
      return it == e.end() ? 0L : it->second.calls;
    };
    int timed = 0, expected = 0;
    for (const char* phase : {"total", "sources"}) {
      if (std::string(phase) == "sources" && !sources) continue;
      ++expected;
      timed += calls(phase) == kSteps ? 1 : 0;
      result.expect(calls(phase) == kSteps,
                    fmt::format("{}: phase {} timed {} times in {} steps", key, phase, calls(phase), kSteps));
    }
    for (const char* phase : {"neighbours", "forces", "redistance", "integrate", "collisions"}) {
      ++expected;
      timed += calls(phase) >= 1 ? 1 : 0;
      result.expect(calls(phase) >= 1, fmt::format("{}: phase {} never timed", key, phase));
    }
    table.add_row({long(Dim), name, std::string("sph"), long(s.steps), s.time, n0,
                   long(run.solver().particles().size()), change, 0.0, long(timed), long(expected),
                   long(run.n_frames()), s.seconds.at("total")});
    result.expect(
        std::abs(change) <= 1e-12,
        fmt::format("{}: the mass in level-0 particles moved by {:.3g} (relative) in {} steps, beyond "
                    "what the sources added",
                    key, change, kSteps));
    result.expect(run.n_frames() >= 2, fmt::format("{}: {} frames written", key, run.n_frames()));
  } catch (const Error& e) {
    result.expect(false, fmt::format("{}: {}", key, e.what()));
    table.add_row({long(Dim), name, std::string("sph"), 0L, 0.0, 0L, 0L, 0.0, 0.0, 0L, 0L, 0L, 0.0});
  }
}

CaseResult run(const CaseOptions&) {
  CaseResult result;
  Table table("every built-in scene, 6 steps at coarse levels",
              {"dim", "scene", "method", "steps", "t", "particles at start", "particles at end",
               "volume change", "surface layer", "phases timed", "of", "frames", "s/step"});
  for (const auto& [name, description] : scene::builtin_scenes()) {
    const bool two = scene::scene_dimension(scene::find_scene(name)) == 2;
    const bool sph = two ? scene::load_scene<2>(scene::find_scene(name)).sph
                         : scene::load_scene<3>(scene::find_scene(name)).sph;
    if (sph) {
      if (two)
        smoke_sph<2>(name, table, result);
      else
        smoke_sph<3>(name, table, result);
    } else if (two) {
      smoke<2>(name, "rbf", table, result);
      smoke<2>(name, "apic", table, result);
      smoke<2>(name, "rbf", table, result, "levelset");
      smoke_sph<2>(name, table, result);
    } else {
      smoke<3>(name, "rbf", table, result);
    }
  }
  result.notes.push_back(
      "frames are checked against their HDF5 files by ctest scene.frames-xdmf (check_xdmf.py); this case "
      "counts them");
  result.notes.push_back(
      "sph rows: 'volume change' is the change of the mass in level-0 particles beyond what sources added "
      "(split and merge conserve it exactly); their surface layer is not measured (0)");
  result.tables.push_back(std::move(table));
  return result;
}

}  // namespace

LIQUID_VERIFICATION_CASE(
    {"scene-smoke", "every built-in scene, 2D and 3D, a few steps: no NaN, volume kept, phases timed, frames",
     true, run, no_options});

}  // namespace liquid::verification
