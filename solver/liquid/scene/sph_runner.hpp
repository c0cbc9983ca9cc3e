#pragma once
// SphSceneRunner<Dim>: runs a scene with solver.method = "sph" (the adaptive SPH of Adams et al.
// 2007) to its end, as SceneRunner runs the PIC solvers: steps sized by the speed of sound
// (AdaptiveSph::stable_dt with the scene's CFL number), frames (HDF5 + XDMF, one ParaView time
// series), checkpoints from which a run continues bit for bit, and the per-step statistics behind
// the paper's Table 1.
//
//   SphSceneRunner<2> run(load_scene<2>(find_scene("sph-dam-break-2d")), settings);
//   while (!run.done()) run.step();
//   const SphRunSummary s = run.summary();
//
// Files in settings.out (created when missing), all written under a temporary name and renamed:
//   NAME.xmf                          the time series (every frame written so far)
//   NAME_particles_FFFFFF.{h5,xmf}    the particles: velocity, speed, pressure, density, level, radius,
//                                     distance (to the surface), elfs (output.fields picks them)
//   NAME_surface_FFFFFF.{h5,xmf}      the surface (output.surface): segments (2D) or triangles (3D) of
//                                     the zero set of the scene's surface model (sph.surface), extracted
//                                     on a grid of half the level-0 spacing (2D) or the spacing (3D)
//   NAME_checkpoint_SSSSSS.h5         the full state after step SSSSSS (with --checkpoint-every)
// A container that turns (sph.turn_angle) is simulated in its own frame; the frames show the world:
// positions and the surface turned by the container's angle at the frame's time (velocities stay in
// the container's frame).

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "liquid/scene/runner.hpp"
#include "liquid/sph/adaptive_sph.hpp"

namespace liquid::scene {

/// Averages over the steps of an SPH run: the paper's Table 1 (Adams et al. 2007) columns.
struct SphRunSummary {
  long steps = 0;
  double time = 0.0;
  double particles = 0.0;  ///< average per step
  int min_particles = 0, max_particles = 0;
  /// What a single-resolution run needs for the same liquid: the total mass in level-0 particles
  /// (exact: resampling conserves mass), averaged per step.
  double single_particles = 0.0;
  std::vector<double> per_level;  ///< average particles of each level per step
  long split = 0, merged = 0, emitted = 0;
  /// Churn (sph::kChurnPasses): merges of a split's child and splits of a merged particle, soon after
  long churn_merged = 0, churn_split = 0;
  double max_density_error = 0.0;  ///< the largest |rho / rho_0 - 1| of any step
  double max_compression = 0.0;    ///< the largest rho / rho_0 - 1 of any step
  /// The most particles alone in one step, whose densities were set to rho_0
  /// (FluidConstants::free_particles_at_rest).
  long rested = 0;
  std::map<std::string, double> seconds;  ///< per phase, average per step
  double sound_speed = 0.0, spacing = 0.0;
  int threads = 1;
  double wall = 0.0;  ///< seconds of the whole run (frames and checkpoints included)
};

template <int Dim>
class SphSceneRunner {
 public:
  /// Seeds the liquid (a lattice of level-0 particles), lets it settle when the scene asks
  /// (sph.settle, behind sph.gate_lo/hi), gives it the scene's initial velocities and writes the
  /// first frame. The scene must have solver.method = "sph".
  SphSceneRunner(Scene<Dim> scene, RunSettings settings);
  /// Continues the run saved in `checkpoint` (a file written by this class).
  static SphSceneRunner resume(const std::string& checkpoint, RunSettings settings);
  ~SphSceneRunner();
  SphSceneRunner(SphSceneRunner&&) noexcept;

  bool done() const;
  const sph::SphStepReport& step();
  std::string checkpoint();

  const Scene<Dim>& scene() const { return scene_; }
  const sph::AdaptiveSph<Dim>& solver() const { return *sim_; }
  const sph::SphStepReport& last() const { return last_; }
  SphRunSummary summary() const;
  const std::vector<std::string>& written() const { return written_; }
  int n_frames() const { return frame_; }

 private:
  struct Private;
  SphSceneRunner(Scene<Dim> scene, RunSettings settings, bool seed);
  void write_frame();
  std::string stem(const char* what, long index) const;

  Scene<Dim> scene_;
  RunSettings settings_;
  std::unique_ptr<sph::AdaptiveSph<Dim>> sim_;
  std::unique_ptr<Private> io_;
  sph::SphStepReport last_;
  int frame_ = 0;
  double next_frame_ = 0.0;
  // Sums for the summary (restored from checkpoints).
  long steps_ = 0, split_ = 0, merged_ = 0, emitted_ = 0, churn_merged_ = 0, churn_split_ = 0;
  int min_particles_ = 0, max_particles_ = 0;
  double sum_particles_ = 0.0, sum_single_ = 0.0, max_density_error_ = 0.0, wall_ = 0.0;
  double max_compression_ = 0.0;
  long rested_ = 0;
  std::vector<double> sum_per_level_;
  std::vector<std::string> written_;
};

extern template class SphSceneRunner<2>;
extern template class SphSceneRunner<3>;

}  // namespace liquid::scene
