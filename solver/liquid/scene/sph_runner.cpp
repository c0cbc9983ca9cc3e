#include "liquid/scene/sph_runner.hpp"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>

#include "liquid/core/error.hpp"
#include "liquid/io/archive.hpp"
#include "liquid/io/mesh_output.hpp"
#include "liquid/io/point_output.hpp"
#include "liquid/io/series.hpp"
#include "liquid/scene/checkpoint_detail.hpp"
#include "liquid/sph/distance_surface.hpp"
#include "liquid/surface/surface.hpp"

namespace liquid::scene {

namespace {

template <int Dim>
std::vector<double> flatten(const std::vector<Vec<Dim>>& v) {
  std::vector<double> out(v.size() * Dim);
  for (std::size_t i = 0; i < v.size(); ++i)
    for (int d = 0; d < Dim; ++d) out[i * Dim + d] = v[i][d];
  return out;
}

template <int Dim>
std::vector<Vec<Dim>> unflatten(const std::vector<double>& v, const std::string& name,
                                const std::string& path) {
  LIQUID_VERIFY(v.size() % Dim == 0, "{}: {} has {} values, not a multiple of {}", path, name, v.size(), Dim);
  std::vector<Vec<Dim>> out(v.size() / Dim);
  for (std::size_t i = 0; i < out.size(); ++i)
    for (int d = 0; d < Dim; ++d) out[i][d] = v[i * Dim + d];
  return out;
}

}  // namespace

template <int Dim>
struct SphSceneRunner<Dim>::Private {
  std::unique_ptr<io::SeriesWriter> series;
};

template <int Dim>
SphSceneRunner<Dim>::SphSceneRunner(Scene<Dim> scene, RunSettings settings)
    : SphSceneRunner(std::move(scene), std::move(settings), true) {}

template <int Dim>
SphSceneRunner<Dim>::SphSceneRunner(Scene<Dim> scene, RunSettings settings, bool seed)
    : scene_(std::move(scene)), settings_(std::move(settings)), io_(std::make_unique<Private>()) {
  LIQUID_VERIFY(scene_.sph, "{}: a PIC scene (method {}) runs with SceneRunner, not the SPH runner",
                scene_.path, scene_.method());
  LIQUID_VERIFY(settings_.checkpoint_every >= 0, "checkpoint interval {} is negative",
                settings_.checkpoint_every);
  LIQUID_VERIFY(settings_.checkpoint_every == 0 || !settings_.out.empty(),
                "checkpoints need an output folder (--out)");
  sim_ = std::make_unique<sph::AdaptiveSph<Dim>>(sph_options<Dim>(scene_));
  sum_per_level_.assign(sim_->options().max_level + 1, 0.0);
  io_->series = detail::open_output(settings_, scene_.name);
  if (!seed) return;
  sim_->seed(scene_.liquid);
  const SphScene<Dim>& sc = scene_.sph_scene;
  if (sc.settle > 0.0) sim_->relax(sc.settle, sc.gate ? &sc.gate_box : nullptr);
  if (scene_.velocity) {
    sph::SphParticles<Dim>& p = sim_->particles();
    for (int i = 0; i < p.size(); ++i) p.v[i] = scene_.velocity(p.x[i]);
  }
  min_particles_ = max_particles_ = sim_->particles().size();
  write_frame();
}

template <int Dim>
SphSceneRunner<Dim>::~SphSceneRunner() = default;
template <int Dim>
SphSceneRunner<Dim>::SphSceneRunner(SphSceneRunner&&) noexcept = default;

template <int Dim>
bool SphSceneRunner<Dim>::done() const {
  return detail::run_done(scene_.time, sim_->steps(), sim_->time());
}

template <int Dim>
std::string SphSceneRunner<Dim>::stem(const char* what, long index) const {
  return detail::file_stem(settings_.out, scene_.name, what, index);
}

template <int Dim>
const sph::SphStepReport& SphSceneRunner<Dim>::step() {
  const auto t0 = std::chrono::steady_clock::now();
  const SceneTime& t = scene_.time;
  const double dt = detail::next_step(t, sim_->stable_dt(t.cfl, t.dt_max), sim_->time());
  last_ = sim_->advance(dt);
  ++steps_;
  split_ += last_.resampling.split;
  merged_ += last_.resampling.merged;
  churn_merged_ += last_.resampling.churn_merged;
  churn_split_ += last_.resampling.churn_split;
  emitted_ += last_.emitted;
  sum_particles_ += last_.particles;
  min_particles_ = std::min(min_particles_, last_.particles);
  max_particles_ = std::max(max_particles_, last_.particles);
  double single = 0.0;
  for (std::size_t l = 0; l < last_.per_level.size(); ++l) {
    single += std::ldexp(static_cast<double>(last_.per_level[l]), static_cast<int>(l));
    sum_per_level_[l] += last_.per_level[l];
  }
  sum_single_ += single;
  max_density_error_ = std::max(max_density_error_, last_.max_density_error);
  max_compression_ = std::max(max_compression_, last_.max_compression);
  rested_ = std::max<long>(rested_, last_.rested);
  if (settings_.frames && !settings_.out.empty() &&
      (done() || detail::frame_due(scene_.output, sim_->time(), next_frame_)))
    write_frame();
  if (settings_.checkpoint_every > 0 && sim_->steps() % settings_.checkpoint_every == 0) checkpoint();
  wall_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return last_;
}

template <int Dim>
void SphSceneRunner<Dim>::write_frame() {
  if (settings_.out.empty() || !settings_.frames) return;
  const sph::SphParticles<Dim>& p = sim_->particles();
  const sph::SphRotation<Dim>& turn = sim_->options().rotation;
  const double time = sim_->time();
  const int n = p.size();
  std::vector<Vec<Dim>> x(p.x);
  if (turn.active())
    for (Vec<Dim>& xi : x) xi = turn.world(xi, time);
  std::vector<std::string> grids;
  if (scene_.output.particles) {
    const std::vector<double> v = flatten<Dim>(p.v);
    std::vector<double> speed(n), level(n), elfs(n);
    for (int i = 0; i < n; ++i) {
      speed[i] = p.v[i].norm();
      level[i] = p.level[i];
      // Not estimated yet (new particles, or a run that is not adaptive): written as -1.
      elfs[i] = std::isfinite(p.elfs[i]) ? p.elfs[i] : -1.0;
    }
    std::vector<io::PointField> fields;
    const auto add = [&](const char* name, int components, std::span<const double> values) {
      if (scene_.output.writes(name)) fields.push_back({name, components, values});
    };
    add("velocity", Dim, v);
    add("speed", 1, speed);
    add("pressure", 1, p.pressure);
    add("density", 1, p.density);
    add("level", 1, level);
    add("radius", 1, p.radius);
    add("distance", 1, p.distance);
    add("elfs", 1, elfs);
    const io::PointFiles f = io::write_points<Dim>(stem("particles", frame_), x, fields);
    written_.push_back(f.h5);
    grids.push_back(f.grid);
  }
  if (scene_.output.surface && n > 0) {
    const sph::PointTree<Dim> tree(p.x);
    const sph::SurfaceField<Dim> field(tree, p.x, p.radius, p.distance, scene_.sph_scene.surface,
                                       sim_->options().h_ratio);
    double reach = 0.0;
    Box<Dim> box{p.x[0], p.x[0]};
    for (int i = 0; i < n; ++i) {
      box.lo = box.lo.cwiseMin(p.x[i]), box.hi = box.hi.cwiseMax(p.x[i]);
      reach = std::max(reach, p.radius[i]);
    }
    box.lo.array() -= reach, box.hi.array() += reach;
    const double cell = (Dim == 2 ? 0.5 : 1.0) * sim_->options().spacing;
    surface::Mesh<Dim> mesh =
        surface::extract<Dim>([&field](const Vec<Dim>& y) { return -field.value(y); }, box, cell);
    if (turn.active())
      for (Vec<Dim>& y : mesh.vertices) y = turn.world(y, time);
    const io::MeshFiles f = io::write_mesh<Dim>(stem("surface", frame_), mesh.vertices, mesh.elements);
    written_.push_back(f.h5);
    grids.push_back(f.grid);
  }
  if (!grids.empty()) {
    io_->series->add(time, grids);
    written_.push_back(io_->series->path());
  }
  ++frame_;
  next_frame_ = detail::next_frame_time(scene_.output, time);
}

template <int Dim>
std::string SphSceneRunner<Dim>::checkpoint() {
  LIQUID_VERIFY(!settings_.out.empty(), "a checkpoint needs an output folder (--out)");
  const sph::SphState<Dim> st = sim_->state();
  const std::string path = stem("checkpoint", st.steps) + ".h5";
  io::ArchiveWriter w(path);
  w.put_scalar("dimension", static_cast<std::int64_t>(Dim));
  detail::put_run_settings(w, settings_, settings_.scene_path.empty() ? scene_.path : settings_.scene_path);
  const sph::SphParticles<Dim>& q = st.particles;
  w.put("sph/particles/x", std::span<const double>(flatten<Dim>(q.x)));
  w.put("sph/particles/v", std::span<const double>(flatten<Dim>(q.v)));
  w.put("sph/particles/a", std::span<const double>(flatten<Dim>(q.a)));
  w.put("sph/particles/foot", std::span<const double>(flatten<Dim>(q.foot)));
  std::vector<std::int32_t> level(q.level.begin(), q.level.end());
  w.put("sph/particles/level", std::span<const std::int32_t>(level));
  w.put("sph/particles/mass", std::span<const double>(q.mass));
  w.put("sph/particles/radius", std::span<const double>(q.radius));
  w.put("sph/particles/density", std::span<const double>(q.density));
  w.put("sph/particles/drho", std::span<const double>(q.drho));
  w.put("sph/particles/pressure", std::span<const double>(q.pressure));
  w.put("sph/particles/distance", std::span<const double>(q.distance));
  w.put("sph/particles/elfs", std::span<const double>(q.elfs));
  std::vector<std::int32_t> birth(q.birth.size());
  for (std::size_t i = 0; i < birth.size(); ++i) birth[i] = static_cast<std::int32_t>(q.birth[i]);
  w.put("sph/particles/birth", std::span<const std::int32_t>(birth));
  w.put("sph/particles/born", std::span<const std::int64_t>(q.born));
  w.put_scalar("sph/time", st.time);
  w.put_scalar("sph/step", static_cast<std::int64_t>(st.steps));
  w.put_string("sph/rng", st.rng);
  w.put_scalar("sph/travel", st.travel);
  w.put("sph/pass_steps", std::span<const std::int64_t>(st.pass_steps));
  w.put_scalar("run/frame", static_cast<std::int64_t>(frame_));
  w.put_scalar("run/next_frame", next_frame_);
  const std::vector<std::int64_t> counts = {steps_,         split_,         merged_, emitted_,
                                            min_particles_, max_particles_, rested_};
  w.put("run/counts", std::span<const std::int64_t>(counts));
  const std::vector<std::int64_t> churn = {churn_merged_, churn_split_};
  w.put("run/churn", std::span<const std::int64_t>(churn));
  const std::vector<double> sums = {sum_particles_, sum_single_, max_density_error_, max_compression_};
  w.put("run/sums", std::span<const double>(sums));
  w.put("run/per_level", std::span<const double>(sum_per_level_));
  detail::put_series(w, io_->series.get());
  w.commit();
  written_.push_back(path);
  return path;
}

template <int Dim>
SphSceneRunner<Dim> SphSceneRunner<Dim>::resume(const std::string& checkpoint, RunSettings settings) {
  const io::ArchiveReader r(checkpoint);
  LIQUID_VERIFY(r.scalar_int("dimension") == Dim, "{}: a {}D checkpoint, not {}D", checkpoint,
                r.scalar_int("dimension"), Dim);
  LIQUID_VERIFY(checkpoint_is_sph(checkpoint), "{}: a PIC run's checkpoint, not an SPH run's", checkpoint);
  detail::get_run_settings(r, settings);
  Scene<Dim> scene = load_scene<Dim>(settings.scene_path);
  apply_overrides<Dim>(settings.overrides, scene);
  LIQUID_VERIFY(scene.sph, "{}: its scene {} no longer runs with method sph", checkpoint,
                settings.scene_path);

  sph::SphState<Dim> st;
  sph::SphParticles<Dim>& q = st.particles;
  q.x = unflatten<Dim>(r.doubles("sph/particles/x"), "sph/particles/x", checkpoint);
  q.v = unflatten<Dim>(r.doubles("sph/particles/v"), "sph/particles/v", checkpoint);
  q.a = unflatten<Dim>(r.doubles("sph/particles/a"), "sph/particles/a", checkpoint);
  q.foot = unflatten<Dim>(r.doubles("sph/particles/foot"), "sph/particles/foot", checkpoint);
  for (std::int32_t l : r.int32s("sph/particles/level")) {
    LIQUID_VERIFY(l >= 0 && l <= 127, "{}: a particle level of {}", checkpoint, l);
    q.level.push_back(static_cast<std::int8_t>(l));
  }
  q.mass = r.doubles("sph/particles/mass");
  q.radius = r.doubles("sph/particles/radius");
  q.density = r.doubles("sph/particles/density");
  q.drho = r.doubles("sph/particles/drho");
  q.pressure = r.doubles("sph/particles/pressure");
  q.distance = r.doubles("sph/particles/distance");
  q.elfs = r.doubles("sph/particles/elfs");
  if (r.has("sph/particles/birth")) {  // absent before churn was counted: every particle then as seeded
    for (std::int32_t b : r.int32s("sph/particles/birth")) {
      LIQUID_VERIFY(b >= 0 && b <= 2, "{}: a particle birth of {}", checkpoint, b);
      q.birth.push_back(static_cast<typename sph::SphParticles<Dim>::Birth>(b));
    }
    q.born = r.int64s("sph/particles/born");
  } else {
    q.birth.assign(q.x.size(), sph::SphParticles<Dim>::Birth::seeded);
    q.born.assign(q.x.size(), -1);
  }
  st.time = r.scalar_double("sph/time");
  st.steps = r.scalar_int("sph/step");
  st.rng = r.string("sph/rng");
  if (r.has("sph/travel")) {  // absent before the travel rule: the next step then passes
    st.travel = r.scalar_double("sph/travel");
    st.pass_steps = r.int64s("sph/pass_steps");
  }

  SphSceneRunner run(std::move(scene), std::move(settings), false);
  try {
    run.sim_->restore(std::move(st));
  } catch (const Error& e) {
    throw Error(fmt::format("{}: {}", checkpoint, e.what()));
  }
  run.frame_ = static_cast<int>(r.scalar_int("run/frame"));
  run.next_frame_ = r.scalar_double("run/next_frame");
  const std::vector<std::int64_t> counts = r.int64s("run/counts");
  const std::vector<double> sums = r.doubles("run/sums"), per_level = r.doubles("run/per_level");
  LIQUID_VERIFY(counts.size() == 7 && sums.size() == 4 && per_level.size() == run.sum_per_level_.size(),
                "{}: the run's sums have the wrong sizes ({} counts, {} sums, levels {} saved, the scene has "
                "{}; a checkpoint from an older version of liquid?)",
                checkpoint, counts.size(), sums.size(), per_level.size(), run.sum_per_level_.size());
  run.steps_ = counts[0], run.split_ = counts[1], run.merged_ = counts[2], run.emitted_ = counts[3];
  if (r.has("run/churn")) {  // absent before churn was counted
    const std::vector<std::int64_t> churn = r.int64s("run/churn");
    LIQUID_VERIFY(churn.size() == 2, "{}: run/churn holds {} counts, not 2", checkpoint, churn.size());
    run.churn_merged_ = churn[0], run.churn_split_ = churn[1];
  }
  run.min_particles_ = static_cast<int>(counts[4]), run.max_particles_ = static_cast<int>(counts[5]);
  run.sum_particles_ = sums[0], run.sum_single_ = sums[1], run.max_density_error_ = sums[2];
  run.rested_ = counts[6], run.max_compression_ = sums[3];
  run.sum_per_level_ = per_level;
  if (run.io_->series) {
    detail::restore_series(r, run.settings_.out, *run.io_->series);
  }
  return run;
}

template <int Dim>
SphRunSummary SphSceneRunner<Dim>::summary() const {
  SphRunSummary s;
  s.steps = steps_;
  s.time = sim_->time();
  const double n = std::max<long>(steps_, 1);
  s.particles = sum_particles_ / n;
  s.min_particles = min_particles_;
  s.max_particles = max_particles_;
  s.single_particles = sum_single_ / n;
  for (double c : sum_per_level_) s.per_level.push_back(c / n);
  s.split = split_, s.merged = merged_, s.emitted = emitted_;
  s.churn_merged = churn_merged_, s.churn_split = churn_split_;
  s.max_density_error = max_density_error_;
  s.max_compression = max_compression_;
  s.rested = rested_;
  const PhaseTimer& t = sim_->timer();
  const auto total = t.entries().find("total");
  const double calls = total == t.entries().end() ? 1.0 : std::max<double>(total->second.calls, 1.0);
  for (const auto& [name, e] : t.entries()) s.seconds[name] = e.seconds / calls;
  s.sound_speed = std::sqrt(sim_->options().fluid.stiffness / sim_->options().fluid.rest_density);
  s.spacing = sim_->options().spacing;
  s.threads = omp_get_max_threads();
  s.wall = wall_;
  return s;
}

template class SphSceneRunner<2>;
template class SphSceneRunner<3>;

}  // namespace liquid::scene
