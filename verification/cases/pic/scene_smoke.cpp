// Case scene-smoke: every built-in scene runs a few steps at coarse levels, with frames.
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

namespace liquid::verification {
namespace {

constexpr long kSteps = 6;

template <int Dim>
double fluid_volume(const AdaptivePic<Dim>& sim) {
  return pic::volume_of<Dim>(sim.graph(), sim.classification().fluid);
}

/// The volume of one layer of surface cells: what a moving surface can add to or take from the
/// cell-counted volume without any liquid being lost.
template <int Dim>
double surface_volume(const AdaptivePic<Dim>& sim) {
  return pic::volume_of<Dim>(sim.graph(), sim.classification().surface);
}

template <int Dim>
void smoke(const std::string& name, const std::string& method, Table& table, CaseResult& result,
           const std::string& surface = "") {
  const std::string path = find_scene(name);
  Scene<Dim> scene = load_scene<Dim>(path);
  SceneOverrides o;
  o.finest = Dim == 2 ? 5 : 3;
  o.steps = kSteps;
  o.method = method;
  o.surface = surface;
  const std::string label = surface.empty() ? method : method + "-" + surface;
  apply_overrides<Dim>(o, scene);
  RunSettings settings;
  settings.out =
      (std::filesystem::temp_directory_path() / "liquid-scene-smoke" / (name + "-" + label)).string();
  std::filesystem::remove_all(settings.out);
  settings.overrides = o;
  settings.scene_path = path;
  const bool sources = !scene.pic.sources.empty();
  const bool adaptive = scene.pic.adaptive;
  const std::string key = fmt::format("{} {}", name, label);
  try {
    SceneRunner<Dim> run(std::move(scene), settings);
    const double v0 = fluid_volume(run.solver());
    double layer = surface_volume(run.solver()) / v0;
    const long n0 = run.solver().particles().size();
    while (!run.done()) run.step();
    const double change = fluid_volume(run.solver()) / v0 - 1.0;
    layer = std::max(layer, surface_volume(run.solver()) / v0);
    const long n1 = run.solver().particles().size();
    const RunSummary s = run.summary();
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

CaseResult run(const CaseOptions&) {
  CaseResult result;
  Table table("every built-in scene, 6 steps at coarse levels",
              {"dim", "scene", "method", "steps", "t", "particles at start", "particles at end",
               "volume change", "surface layer", "phases timed", "of", "frames", "s/step"});
  for (const auto& [name, description] : builtin_scenes()) {
    if (scene_dimension(find_scene(name)) == 2) {
      smoke<2>(name, "rbf", table, result);
      smoke<2>(name, "apic", table, result);
      smoke<2>(name, "rbf", table, result, "levelset");
    } else {
      smoke<3>(name, "rbf", table, result);
    }
  }
  result.notes.push_back(
      "frames are checked against their HDF5 files by ctest scene.frames-xdmf (check_xdmf.py); this case "
      "counts them");
  result.tables.push_back(std::move(table));
  return result;
}

}  // namespace

LIQUID_VERIFICATION_CASE(
    {"scene-smoke", "every built-in scene, 2D and 3D, a few steps: no NaN, volume kept, phases timed, frames",
     true, run, no_options});

}  // namespace liquid::verification
