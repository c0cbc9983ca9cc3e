#pragma once
// Scenes: a liquid simulation described in a TOML file (every key: solver/scenes/README.md), read
// once into typed values. The dimension is the length of domain.lo (2 or 3).
//
//   const std::string path = find_scene("dam-break-2d");   // a built-in name or a file path
//   if (scene_dimension(path) == 2) { Scene<2> s = load_scene<2>(path); ... }
//
// A bad file is refused with liquid::Error and a message "FILE:LINE: key 'grid.finest': ..." that
// names the key: unknown keys (with the nearest known one), wrong types, sizes that are not
// positive, a fluid shape outside the domain, values out of range.

#include <limits>
#include <string>
#include <vector>

#include "liquid/levelset/levelset.hpp"
#include "liquid/linalg/solver.hpp"
#include "liquid/pic/adaptive_pic.hpp"
#include "liquid/sph/adaptive_sph.hpp"

namespace liquid::scene {

/// When a run ends and how its steps are sized.
/// The most steps a run may take (scene key time.steps, --steps; time.end and --until by dt_max).
inline constexpr long kMaxSteps = 100000000;

struct SceneTime {
  double end = std::numeric_limits<double>::infinity();  ///< simulated seconds
  long steps = -1;                                       ///< or a step count (-1: by `end`)
  double cfl = 1.0;                                      ///< dt = cfl * finest h / max speed ...
  double dt_min = 1e-5, dt_max = 0.01;                   ///< ... clamped to [dt_min, dt_max]
};

/// What the run writes.
struct SceneOutput {
  double every = 0.0;     ///< simulated seconds between frames (0: the first and the last only)
  bool cells = true;      ///< the tree's leaves with pressure, type and level
  bool particles = true;  ///< the particles with velocity and speed
  bool surface = true;    ///< SPH: the particles' surface as a mesh
  /// The fields written. PIC: cells "pressure", "type"; particles "velocity", "speed" (cell level and
  /// id are always written). SPH, per particle: "velocity", "speed", "pressure", "density", "level",
  /// "radius", "distance", "elfs".
  std::vector<std::string> fields{"pressure", "type", "velocity", "speed"};
  bool fields_given = false;  ///< output.fields is in the file (else the method's defaults)
  static std::vector<std::string> pic_fields() { return {"pressure", "type", "velocity", "speed"}; }
  static std::vector<std::string> sph_fields() {
    return {"velocity", "speed", "pressure", "density", "level", "radius", "distance", "elfs"};
  }
  bool writes(const std::string& field) const {
    for (const std::string& f : fields)
      if (f == field) return true;
    return false;
  }
};

/// The adaptive SPH side of a scene (solver.method = "sph", the [sph] table). The container is the
/// domain, the obstacles the solids, gravity and sources the scene's: sph_options() assembles them.
template <int Dim>
struct SphScene {
  sph::SphOptions<Dim> options;  ///< the [sph] table's values (fluid, levels, resampling, turn, ...)
  bool spacing_given = false;    ///< sph.spacing is in the file (else half the finest cell of [grid])
  /// Where the spacing came from, for messages: "FILE:LINE: key 'sph.spacing'", "--spacing", or the
  /// [grid] table's "FILE:LINE: [grid]".
  std::string spacing_where;
  /// Speed of sound (m/s); 0: ten times the fastest speed the scene can reach, sqrt(v0^2 + 2 |g| H)
  /// with v0 the fastest initial or inflow speed and H the fall from the top of the liquid or of a
  /// source to the bottom of the domain (a turning container: its diagonal). Stiffness k = rho_0 c^2;
  /// density errors stay near (v / c)^2, about 1%.
  double sound_speed = 0.0;
  double settle = 0.0;  ///< seconds the liquid settles (AdaptiveSph::relax) before t = 0
  bool gate = false;    ///< it settles held in gate_box (a dam's gate, gone at t = 0)
  Box<Dim> gate_box;
  sph::SurfaceModel surface = sph::SurfaceModel::distance;  ///< the surface meshed in the frames
};

/// An inflow of the scene ([[source]]): where, how fast, and when.
template <int Dim>
struct SceneSource {
  levelset::Function<Dim> region;  ///< < 0 inside
  Box<Dim> bounds;                 ///< the region's bounding box
  Vec<Dim> velocity = Vec<Dim>::Zero();
  double start = 0.0, stop = std::numeric_limits<double>::infinity();  ///< seconds
};

/// A scene as read: what every method shares (the tank, gravity, the liquid, solids and sources, the
/// time and the output), then each solver's own tables: `pic` ([grid], [solver], [ppe]; its domain,
/// gravity, solids and sources copied from the shared ones) and `sph_scene` ([sph]; sph_options()
/// assembles the SPH solver's options from it and the shared ones).
template <int Dim>
struct Scene {
  std::string name;         ///< the file's `name`, or its stem
  std::string description;  ///< one line
  std::string figure;       ///< the paper's figure the scene reproduces ("" if none)
  std::string path;         ///< the file read
  std::string fluid_where;  ///< "FILE:LINE: [[fluid]]", the first fluid table (for messages)
  Box<Dim> domain{Vec<Dim>::Zero(), Vec<Dim>::Ones()};  ///< the tank: the PIC domain, the SPH container
  Vec<Dim> gravity = pic::PicOptions<Dim>::default_gravity();
  bool adaptive = true;           ///< solver.adaptive: the tree (PIC) or the particle levels (SPH)
  levelset::Function<Dim> solid;  ///< the [[solid]] shapes combined (< 0 inside; empty: none)
  std::vector<SceneSource<Dim>> sources;
  pic::PicOptions<Dim> pic;  ///< the PIC solver's options
  levelset::Function<Dim> liquid;
  /// Initial velocity by position: that of the last [[fluid]] shape holding the point (0 if none).
  std::function<Vec<Dim>(const Vec<Dim>&)> velocity;
  SceneTime time;
  SceneOutput output;
  bool ppe_solver_given = false;  ///< ppe.solver is in the file (else default_ppe_solver())
  bool grid_given = false;        ///< the file has a [grid] table (PIC methods need it)
  bool sph = false;               ///< solver.method = "sph": the adaptive SPH solver runs it
  bool paper_preset = false;      ///< solver.preset = "paper" (PicOptions::apply_paper_preset)
  /// Where the scene's [sph] table is ("FILE:LINE: [sph]"), or "" without one: a run that is not SPH
  /// (after --method) refuses it, since it would be ignored.
  std::string sph_table;
  SphScene<Dim> sph_scene;
  Box<Dim> liquid_bounds;          ///< the bounding box of the [[fluid]] shapes that add liquid
  double max_initial_speed = 0.0;  ///< the fastest [[fluid]] velocity given
  /// "sph" or the PIC transfer's name.
  std::string method() const { return sph ? "sph" : to_string(pic.transfer); }
};

/// The first of `fields` that the method does not write ("" when all are written).
std::string field_not_written(const std::vector<std::string>& fields, bool sph);

/// The SPH solver's options for a scene with solver.method = "sph": the [sph] table's, with the
/// domain as container, the solids as one obstacle, the scene's gravity, sources and adaptivity, the
/// spacing (given, or half the finest cell) and the stiffness rho_0 c^2 (SphScene::sound_speed).
/// Throws liquid::Error naming the [sph] key at fault (no spacing to be had, a liquid too large for
/// the particle budget, values SphOptions::check() refuses).
template <int Dim>
sph::SphOptions<Dim> sph_options(const Scene<Dim>& scene);
/// The sound speed a scene runs with (SphScene::sound_speed, or its default; throws when nothing in
/// the scene moves and none is given).
template <int Dim>
double sph_sound_speed(const Scene<Dim>& scene);

/// The PPE solver of a scene that names none: for the adaptive tree's non-symmetric matrix
/// BiCGSTAB+ILUT in 2D and BiCGSTAB+Jacobi in 3D (a moving surface makes AMG rebuild its hierarchy
/// every step, and that setup outweighs the iterations it saves); Jacobi-preconditioned CG for the
/// regular grid's symmetric one (the paper's regular baseline). Each was the fastest `ppe` phase on
/// the built-in scenes; a solve that does not converge falls back to AMG (PicOptions::ppe_fallback).
/// Why these defaults: docs/findings/amg.md.
linalg::SolverKind default_ppe_solver(bool adaptive, int dim);

/// 2 or 3, from domain.lo of the file (throws as load_scene does on a file that cannot be read).
int scene_dimension(const std::string& path);
/// Reads and checks a scene file; dimension must be Dim.
/// What a PIC run of the scene will hold at its start, estimated from the scene alone (no tree is
/// built): the liquid's volume and, on a tree, the band around its surface, sampled from the level
/// sets on a lattice of the domain; 2^Dim particles a liquid cell (fine in the band, coarse inside);
/// and bytes per particle and per cell, larger on a tree (its RBF stencils), set above the peak
/// memory measured at 2^-7 so that the estimate bounds it (docs/findings/table1-scale.md). Sources add liquid
/// later and are not counted.
struct PicSize {
  double particles = 0, cells = 0, bytes = 0;
};
template <int Dim>
PicSize estimate_pic_size(const Scene<Dim>& s);

/// Refuses a scene whose [sph] table its method would ignore (Scene::sph_table).
template <int Dim>
void check_sph_table(const Scene<Dim>& s);

template <int Dim>
Scene<Dim> load_scene(const std::string& path);

/// The folder of the built-in scenes (LIQUID_SCENES, else the source tree's solver/scenes).
std::string scenes_folder();
/// A path as given when it names a file; else the built-in scene of that name (NAME.toml in
/// scenes_folder()). Throws listing the built-in names when neither exists.
std::string find_scene(const std::string& name_or_path);
/// The built-in scenes: (name, description), sorted by name.
std::vector<std::pair<std::string, std::string>> builtin_scenes();

extern template sph::SphOptions<2> sph_options<2>(const Scene<2>&);
extern template sph::SphOptions<3> sph_options<3>(const Scene<3>&);
extern template double sph_sound_speed<2>(const Scene<2>&);
extern template double sph_sound_speed<3>(const Scene<3>&);
extern template Scene<2> load_scene<2>(const std::string&);
extern template Scene<3> load_scene<3>(const std::string&);

}  // namespace liquid::scene
