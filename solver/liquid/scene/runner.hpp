#pragma once
// SceneRunner<Dim>: runs a scene to its end: time steps sized by the CFL number, frames (HDF5 +
// XDMF, one ParaView time series), checkpoints from which a run continues bit for bit, and the
// per-step statistics behind the paper's Table 1.
//
//   SceneRunner<2> run(load_scene<2>(find_scene("dam-break-2d")), settings);
//   while (!run.done()) run.step();
//   const RunSummary s = run.summary();
//
// Files in settings.out (created when missing), all written under a temporary name and renamed:
//   NAME.xmf                           the time series (every frame written so far)
//   NAME_cells_FFFFFF.{h5,xmf}         the tree's leaves: pressure, type (0 air, 1 fluid, 2 solid), level
//   NAME_particles_FFFFFF.{h5,xmf}     the particles: velocity, speed
//   NAME_checkpoint_SSSSSS.h5          the full state after step SSSSSS (with --checkpoint-every)

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "liquid/pic/adaptive_pic.hpp"
#include "liquid/scene/scene.hpp"

namespace liquid::scene {

/// How a run differs from its scene file (the command line's overrides), kept in checkpoints so
/// that a resumed run rebuilds the same solver.
struct SceneOverrides {
  std::string method;     ///< "" keeps the scene's; pic, flip and apic also set adaptive = false; sph
                          ///< runs the adaptive SPH solver
  int adaptive = -1;      ///< -1 keeps the scene's; 0 regular grid; 1 adaptive tree
  int finest = -1;        ///< -1 keeps the scene's; else the finest level (the coarse level shifts with it)
  long steps = -1;        ///< -1 keeps the scene's end; else a step count
  double until = -1;      ///< < 0 keeps the scene's end; else the end time
  std::string surface;    ///< "" keeps the scene's; else "air" or "levelset" (PIC), or the SPH surface
                          ///< model meshed in the frames: "distance", "zhu-bridson", "blobby"
  std::string solver;     ///< "" keeps the scene's; else a PPE solver's name (linalg::solver_names())
  double amg_reuse = -1;  ///< -1 keeps the scene's; else AmgOptions::reuse_factor (>= 0)
  double spacing = -1;    ///< SPH: -1 keeps the scene's; else the level-0 particle spacing
  bool paper = false;     ///< PIC: the paper's transfer and reseeding (PicOptions::apply_paper_preset)
};

/// 2 or 3: the dimension of the run saved in a checkpoint file.
int checkpoint_dimension(const std::string& path);
/// True when a checkpoint file holds an SPH run (SphSceneRunner), false for a PIC run.
bool checkpoint_is_sph(const std::string& path);

/// Applies `o` to a loaded scene (checks the result as the loader does).
template <int Dim>
void apply_overrides(const SceneOverrides& o, Scene<Dim>& scene);

struct RunSettings {
  std::string out;            ///< output folder; "" writes nothing
  bool frames = true;         ///< write frames (the scene's output cadence)
  long checkpoint_every = 0;  ///< write a checkpoint every N steps (0: never)
  SceneOverrides overrides;   ///< stored in checkpoints
  std::string scene_path;     ///< stored in checkpoints (the file read)
};

/// Averages over the steps of a run: the paper's Table 1 row, and every phase.
struct RunSummary {
  long steps = 0;
  double time = 0.0;
  double fluid_cells = 0.0, cells = 0.0, particles = 0.0;  ///< averages per step
  /// The same run's liquid as finest-level cells: sum over fluid cells of 2^(Dim (finest - level)),
  /// averaged; and particles at the density the run keeps in its finest fluid cells. What a regular
  /// grid at the same finest h needs for the same liquid (computed from this run, not a second run).
  double regular_cells = 0.0, regular_particles = 0.0;
  std::map<std::string, double> seconds;  ///< per phase, average per step
  long ppe_iterations = 0;                ///< total (both solves of the split projection)
  long ppe_failures = 0;                  ///< PPE solves that did not converge (continue_on_failure)
  /// PPE solves retried with AMG after the first solver failed (PicOptions::ppe_fallback).
  long ppe_fallbacks = 0;
  long ppe_reused = 0;  ///< steps whose PPE kept the last step's preconditioner (same matrix or layout)
  int threads = 1;
  double wall = 0.0;  ///< seconds of the whole run (frames and checkpoints included)
};

template <int Dim>
class SceneRunner {
 public:
  SceneRunner(Scene<Dim> scene, RunSettings settings);
  /// Continues the run saved in `checkpoint` (a file written by this class); `settings.out` is
  /// where it goes on writing (frames after the checkpoint's time are dropped from the series).
  static SceneRunner resume(const std::string& checkpoint, RunSettings settings);
  ~SceneRunner();
  SceneRunner(SceneRunner&&) noexcept;

  bool done() const;
  /// One time step (and the frame or checkpoint due after it).
  const pic::PicStepReport& step();
  /// Writes a checkpoint of the current state now; returns its path.
  std::string checkpoint();

  const Scene<Dim>& scene() const { return scene_; }
  const pic::AdaptivePic<Dim>& solver() const { return *sim_; }
  const pic::PicStepReport& last() const { return last_; }
  RunSummary summary() const;
  /// Paths of the files written so far (frames, series, checkpoints), in order.
  const std::vector<std::string>& written() const { return written_; }
  int n_frames() const { return frame_; }

 private:
  struct Private;
  SceneRunner(Scene<Dim> scene, RunSettings settings, bool seed);
  void write_frame();
  std::string stem(const char* what, long index) const;

  Scene<Dim> scene_;
  RunSettings settings_;
  std::unique_ptr<pic::AdaptivePic<Dim>> sim_;
  std::unique_ptr<Private> io_;
  pic::PicStepReport last_;
  int frame_ = 0;
  double next_frame_ = 0.0;
  // Sums for the summary (restored from checkpoints so that a resumed run reports the whole run).
  long steps_ = 0, ppe_iterations_ = 0, ppe_failures_ = 0, ppe_reused_ = 0, ppe_fallbacks_ = 0;
  double sum_fluid_ = 0, sum_cells_ = 0, sum_particles_ = 0, sum_regular_cells_ = 0,
         sum_regular_particles_ = 0;
  double wall_ = 0.0;
  std::vector<std::string> written_;
};

extern template class SceneRunner<2>;
extern template class SceneRunner<3>;

}  // namespace liquid::scene
