#include "liquid/scene/runner.hpp"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>

#include "liquid/core/error.hpp"
#include "liquid/io/archive.hpp"
#include "liquid/io/point_output.hpp"
#include "liquid/io/series.hpp"
#include "liquid/io/tree_output.hpp"
#include "liquid/scene/checkpoint_detail.hpp"

namespace liquid::scene {

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

namespace detail {

double next_step(const SceneTime& time, double stable, double now) {
  double dt = std::clamp(stable, time.dt_min, time.dt_max);
  if (time.steps < 0) {
    const double left = time.end - now;
    if (dt > left || left - dt < 1e-3 * dt) dt = left;  // land on the end time, no sliver step after
  }
  return dt;
}

bool run_done(const SceneTime& time, long step, double now) {
  if (time.steps >= 0) return step >= time.steps;
  return now >= time.end * (1 - 1e-12);
}

bool frame_due(const SceneOutput& output, double now, double next_frame) {
  return output.every > 0 && now >= next_frame - 1e-9 * output.every;
}

double next_frame_time(const SceneOutput& output, double now) {
  return output.every > 0 ? (std::floor(now / output.every + 1e-9) + 1) * output.every
                          : std::numeric_limits<double>::infinity();
}

std::unique_ptr<io::SeriesWriter> open_output(const RunSettings& settings, const std::string& name) {
  if (settings.out.empty()) return nullptr;
  std::error_code ec;
  std::filesystem::create_directories(settings.out, ec);
  LIQUID_VERIFY(!ec, "cannot create the output folder '{}': {}", settings.out, ec.message());
  if (!settings.frames) return nullptr;
  return std::make_unique<io::SeriesWriter>((std::filesystem::path(settings.out) / (name + ".xmf")).string());
}

std::string file_stem(const std::string& out, const std::string& name, const char* what, long index) {
  return (std::filesystem::path(out) / fmt::format("{}_{}_{:06d}", name, what, index)).string();
}

namespace {
constexpr char grid_separator = '\x1e';  // between the grids of one frame in a checkpoint
}  // namespace

/// FNV-1a over the scene file's bytes: what a checkpoint keeps to know its scene again.
std::string scene_fingerprint(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  LIQUID_VERIFY(in.good(), "cannot read the scene file {}", path);
  std::uint64_t h = 0xcbf29ce484222325ULL;
  char c = 0;
  while (in.get(c)) h = (h ^ static_cast<unsigned char>(c)) * 0x100000001b3ULL;
  return fmt::format("{:016x}", h);
}

void put_run_settings(io::ArchiveWriter& w, const RunSettings& settings, const std::string& scene_path) {
  w.put_string("scene/path", std::filesystem::absolute(scene_path).string());
  w.put_string("scene/fingerprint", scene_fingerprint(scene_path));
  const SceneOverrides& o = settings.overrides;
  w.put_string("overrides/method", o.method.empty() ? "-" : o.method);
  w.put_scalar("overrides/adaptive", static_cast<std::int64_t>(o.adaptive));
  w.put_scalar("overrides/finest", static_cast<std::int64_t>(o.finest));
  w.put_scalar("overrides/steps", static_cast<std::int64_t>(o.steps));
  w.put_scalar("overrides/until", o.until);
  w.put_string("overrides/surface", o.surface.empty() ? "-" : o.surface);
  w.put_scalar("overrides/spacing", o.spacing);
  w.put_scalar("overrides/paper", static_cast<std::int64_t>(o.paper));
  w.put_scalar("run/checkpoint_every", static_cast<std::int64_t>(settings.checkpoint_every));
}

void get_run_settings(const io::ArchiveReader& r, RunSettings& settings) {
  settings.scene_path = r.string("scene/path");
  SceneOverrides& o = settings.overrides;
  o.method = r.string("overrides/method") == "-" ? "" : r.string("overrides/method");
  o.adaptive = static_cast<int>(r.scalar_int("overrides/adaptive"));
  o.finest = static_cast<int>(r.scalar_int("overrides/finest"));
  o.steps = r.scalar_int("overrides/steps");
  o.until = r.scalar_double("overrides/until");
  o.surface = r.string("overrides/surface") == "-" ? "" : r.string("overrides/surface");
  // Checkpoints written before SPH runs existed lack the spacing: they kept the scene's.
  o.spacing = r.has("overrides/spacing") ? r.scalar_double("overrides/spacing") : -1;
  o.paper = r.has("overrides/paper") && r.scalar_int("overrides/paper") != 0;
  if (settings.checkpoint_every == 0) settings.checkpoint_every = r.scalar_int("run/checkpoint_every");
  LIQUID_VERIFY(std::filesystem::is_regular_file(settings.scene_path),
                "{}: its scene file {} is gone; a checkpoint needs the scene it was made from", r.path(),
                settings.scene_path);
  // Checkpoints written before the fingerprint existed resume as before.
  if (r.has("scene/fingerprint"))
    LIQUID_VERIFY(r.string("scene/fingerprint") == scene_fingerprint(settings.scene_path),
                  "{}: its scene file {} has changed since the checkpoint was written; resuming would mix "
                  "two scenes (restore the file, or start the new scene afresh)",
                  r.path(), settings.scene_path);
}

void put_series(io::ArchiveWriter& w, const io::SeriesWriter* series) {
  std::vector<double> times;
  if (series)
    for (const io::SeriesFrame& f : series->frames()) {
      std::string text;
      for (std::size_t i = 0; i < f.grids.size(); ++i)
        text += (i ? std::string(1, grid_separator) : "") + f.grids[i];
      w.put_string(fmt::format("run/series/frame_{}", times.size()), text);
      times.push_back(f.time);
    }
  w.put("run/series/times", std::span<const double>(times));
}

namespace {

/// `grid` with every reference to an HDF5 file of the folder it was written in (">NAME.h5:/...")
/// led through `prefix` ("../run1/").
std::string relocate_references(const std::string& grid, const std::string& prefix) {
  std::string out;
  std::size_t at = 0;
  for (;;) {
    const std::size_t open = grid.find('>', at);
    if (open == std::string::npos) break;
    const std::size_t colon = grid.find(".h5:/", open);
    const std::size_t close = grid.find('<', open);
    out.append(grid, at, open + 1 - at);
    at = open + 1;
    if (colon != std::string::npos && colon < close &&
        grid.find_first_of("/\\", open + 1) > colon)  // a bare file name
      out += prefix;
  }
  out.append(grid, at, std::string::npos);
  return out;
}

}  // namespace

std::vector<io::SeriesFrame> get_series(const io::ArchiveReader& r, const std::string& out) {
  std::vector<io::SeriesFrame> frames;
  const std::vector<double> times = r.doubles("run/series/times");
  for (std::size_t f = 0; f < times.size(); ++f) {
    io::SeriesFrame frame{times[f], std::vector<std::string>(1)};
    for (char ch : r.string(fmt::format("run/series/frame_{}", f)))
      if (ch == grid_separator)
        frame.grids.emplace_back();
      else
        frame.grids.back() += ch;
    frames.push_back(std::move(frame));
  }
  // Resumed into another folder (--out): the earlier frames' files stay where the checkpoint is,
  // and the new series reaches them through a relative path, so that it opens whole.
  namespace fs = std::filesystem;
  std::error_code e1, e2;
  const fs::path from = fs::weakly_canonical(fs::absolute(r.path()).parent_path(), e1);
  const fs::path to = fs::weakly_canonical(fs::absolute(out), e2);
  if (!e1 && !e2 && from != to) {
    const std::string prefix = from.lexically_relative(to).generic_string() + "/";
    for (io::SeriesFrame& f : frames)
      for (std::string& g : f.grids) g = relocate_references(g, prefix);
  }
  return frames;
}

void restore_series(const io::ArchiveReader& r, const std::string& out, io::SeriesWriter& series) {
  std::vector<io::SeriesFrame> frames = get_series(r, out);
  if (frames.empty()) return;
  try {
    series.restore(std::move(frames));
  } catch (const Error& e) {
    // The frames came from the checkpoint: a damaged one is its fault.
    throw Error(fmt::format("{}: run/series: {}", r.path(), e.what()));
  }
}

}  // namespace detail

bool checkpoint_is_sph(const std::string& path) {
  const io::ArchiveReader r(path);
  return r.has("sph/time");
}

int checkpoint_dimension(const std::string& path) {
  const io::ArchiveReader r(path);
  const std::int64_t dim = r.scalar_int("dimension");
  LIQUID_VERIFY(dim == 2 || dim == 3, "{}: 'dimension' is {}; not a checkpoint of this program", path, dim);
  return static_cast<int>(dim);
}

template <int Dim>
void apply_overrides(const SceneOverrides& o, Scene<Dim>& scene) {
  pic::PicOptions<Dim>& p = scene.pic;
  if (!o.method.empty()) {
    const bool was_sph = scene.sph;
    scene.sph = o.method == "sph";
    if (!scene.sph) {
      LIQUID_VERIFY(scene.grid_given, "{}: method '{}' runs on a grid, and the scene has no [grid] table",
                    scene.path, o.method);
      p.transfer = pic::parse_pic_transfer(o.method);
      if (p.transfer != pic::PicTransfer::rbf) scene.adaptive = p.adaptive = false;
    }
    if (was_sph != scene.sph && !scene.output.fields_given)
      scene.output.fields = scene.sph ? SceneOutput::sph_fields() : SceneOutput::pic_fields();
    if (scene.sph && !was_sph) {
      // A PIC scene run by SPH: SPH's step is bounded by the speed of sound, so the PIC step's
      // bounds and CFL number do not carry over.
      scene.time.cfl = 0.25;
      scene.time.dt_max = std::min(scene.time.dt_max, 1e-3);
      scene.time.dt_min = std::min(1e-9, scene.time.dt_max);
    }
  }
  const std::string wrong = field_not_written(scene.output.fields, scene.sph);
  LIQUID_VERIFY(wrong.empty(), "{}: output.fields names '{}', which method {} does not write", scene.path,
                wrong, scene.method());
  if (o.adaptive >= 0) scene.adaptive = p.adaptive = o.adaptive == 1;
  if (o.paper) {
    LIQUID_VERIFY(!scene.sph,
                  "--paper: the paper's preset is the PIC solver's transfer and reseeding; an "
                  "SPH run has neither");
    p.apply_paper_preset();
    scene.paper_preset = true;
  }
  if (!o.surface.empty()) {
    if (scene.sph) {
      bool found = false;
      for (sph::SurfaceModel m :
           {sph::SurfaceModel::distance, sph::SurfaceModel::zhu_bridson, sph::SurfaceModel::blobby})
        if (o.surface == sph::to_string(m)) scene.sph_scene.surface = m, found = true;
      LIQUID_VERIFY(found,
                    "--surface {}: an SPH run meshes the 'distance', 'zhu-bridson' or 'blobby' surface",
                    o.surface);
    } else {
      LIQUID_VERIFY(o.surface == "air" || o.surface == "levelset",
                    "--surface {}: a PIC run's pressure surface is 'air' or 'levelset'", o.surface);
      p.surface = pic::parse_pic_surface(o.surface);
    }
  }
  if (!o.solver.empty()) {
    LIQUID_VERIFY(!scene.sph, "--solver {}: an SPH run solves no pressure equation", o.solver);
    p.solver.kind = linalg::parse_solver(o.solver);
    scene.ppe_solver_given = true;
  }
  if (!scene.ppe_solver_given) p.solver.kind = default_ppe_solver(p.adaptive, Dim);
  if (o.amg_reuse != -1) {  // -1: keep the scene's; anything else must be a factor (NaN included)
    LIQUID_VERIFY(std::isfinite(o.amg_reuse) && o.amg_reuse >= 0.0,
                  "--amg-reuse {} must be 0 (a new AMG hierarchy every step) or a positive factor",
                  o.amg_reuse);
    p.solver.amg.reuse_factor = o.amg_reuse;
  }
  LIQUID_VERIFY(scene.sph || !p.adaptive || p.transfer == pic::PicTransfer::rbf,
                "method '{}' runs on a regular grid only; drop --adaptive or use --method rbf",
                to_string(p.transfer));
  if (o.spacing != -1) {
    LIQUID_VERIFY(scene.sph,
                  "--spacing {}: the particle spacing is an SPH run's (--method sph); a PIC run's size is "
                  "--finest",
                  o.spacing);
    LIQUID_VERIFY(std::isfinite(o.spacing) && o.spacing > 0.0, "--spacing {} must be a positive length",
                  o.spacing);
    scene.sph_scene.options.spacing = o.spacing;
    scene.sph_scene.spacing_given = true;
    scene.sph_scene.spacing_where = "--spacing";
  }
  if (o.finest >= 0 && scene.sph)
    LIQUID_VERIFY(
        !scene.sph_scene.spacing_given,
        "--finest {}: this SPH run's spacing is {} (sph.spacing or --spacing); --finest sets it only "
        "when the scene gives none (half the finest cell)",
        o.finest, scene.sph_scene.options.spacing);
  if (o.finest >= 0) {
    LIQUID_VERIFY(o.finest >= 1 && o.finest <= morton::max_level<Dim>, "--finest {} is outside [1, {}]",
                  o.finest, morton::max_level<Dim>);
    const int shift = o.finest - p.finest_level;
    p.finest_level = o.finest;
    p.coarse_level = std::clamp(p.coarse_level + shift, 0, p.finest_level);
  }
  if (o.steps >= 0) {
    LIQUID_VERIFY(o.steps >= 1 && o.steps <= kMaxSteps, "--steps {} is outside [1, {}]", o.steps, kMaxSteps);
    scene.time.steps = o.steps;
    scene.time.end = std::numeric_limits<double>::infinity();
  }
  if (!(o.until < 0)) {  // a negative time keeps the scene's end; NaN is refused below
    LIQUID_VERIFY(o.until > 0 && std::isfinite(o.until), "--until {} must be a positive time", o.until);
    LIQUID_VERIFY(
        o.until / scene.time.dt_max <= static_cast<double>(kMaxSteps),
        "--until {} s needs at least {:.3g} steps of the scene's dt_max = {} s, more than a run may "
        "take ({})",
        o.until, o.until / scene.time.dt_max, scene.time.dt_max, kMaxSteps);
    scene.time.end = o.until;
    scene.time.steps = -1;
  }
  if (scene.sph) sph_options<Dim>(scene);  // refuses what the SPH solver cannot run
  check_sph_table<Dim>(scene);
}

template <int Dim>
struct SceneRunner<Dim>::Private {
  std::unique_ptr<io::SeriesWriter> series;
};

template <int Dim>
SceneRunner<Dim>::SceneRunner(Scene<Dim> scene, RunSettings settings)
    : SceneRunner(std::move(scene), std::move(settings), true) {}

template <int Dim>
SceneRunner<Dim>::SceneRunner(Scene<Dim> scene, RunSettings settings, bool seed)
    : scene_(std::move(scene)), settings_(std::move(settings)), io_(std::make_unique<Private>()) {
  LIQUID_VERIFY(!scene_.sph, "{}: an SPH scene runs with SphSceneRunner, not the PIC runner", scene_.path);
  LIQUID_VERIFY(settings_.checkpoint_every >= 0, "checkpoint interval {} is negative",
                settings_.checkpoint_every);
  LIQUID_VERIFY(settings_.checkpoint_every == 0 || !settings_.out.empty(),
                "checkpoints need an output folder (--out)");
  io_->series = detail::open_output(settings_, scene_.name);
  sim_ = std::make_unique<pic::AdaptivePic<Dim>>(scene_.pic);
  if (seed) {
    sim_->seed(scene_.liquid, scene_.velocity);
    write_frame();
  }
}

template <int Dim>
SceneRunner<Dim>::~SceneRunner() = default;
template <int Dim>
SceneRunner<Dim>::SceneRunner(SceneRunner&&) noexcept = default;

template <int Dim>
bool SceneRunner<Dim>::done() const {
  return detail::run_done(scene_.time, sim_->steps(), sim_->time());
}

template <int Dim>
std::string SceneRunner<Dim>::stem(const char* what, long index) const {
  return detail::file_stem(settings_.out, scene_.name, what, index);
}

template <int Dim>
const pic::PicStepReport& SceneRunner<Dim>::step() {
  const auto t0 = std::chrono::steady_clock::now();
  const SceneTime& t = scene_.time;
  const double dt = detail::next_step(t, sim_->stable_dt(t.cfl, t.dt_max), sim_->time());
  last_ = sim_->advance(dt);
  ++steps_;
  ppe_iterations_ +=
      last_.ppe.iterations + last_.ppe_gravity.iterations;  // the split projection solves twice
  ppe_failures_ += (last_.ppe.converged() ? 0 : 1) + (last_.ppe_gravity.converged() ? 0 : 1);
  ppe_reused_ += last_.ppe.hierarchy_reused ? 1 : 0;
  ppe_fallbacks_ += last_.ppe_fallbacks;
  sum_fluid_ += static_cast<double>(last_.n_fluid_cells);
  sum_cells_ += static_cast<double>(last_.n_cells);
  sum_particles_ += static_cast<double>(last_.n_particles);
  // The regular grid's count for the same liquid at the same finest h (see RunSummary).
  const tree::CellGraph<Dim>& g = sim_->graph();
  const int finest = scene_.pic.finest_level;
  double regular = 0.0;
  long fine_cells = 0, fine_particles = 0;
  for (tree::CellId c : sim_->classification().fluid) {
    regular += std::ldexp(1.0, Dim * (finest - g.level(c)));
    if (g.level(c) == finest) ++fine_cells, fine_particles += sim_->bins().count(c);
  }
  sum_regular_cells_ += regular;
  sum_regular_particles_ += fine_cells > 0 ? regular * static_cast<double>(fine_particles) / fine_cells
                                           : static_cast<double>(last_.n_particles);
  if (settings_.frames && !settings_.out.empty() &&
      (done() || detail::frame_due(scene_.output, sim_->time(), next_frame_)))
    write_frame();
  if (settings_.checkpoint_every > 0 && sim_->steps() % settings_.checkpoint_every == 0) checkpoint();
  wall_ += seconds_since(t0);
  return last_;
}

template <int Dim>
void SceneRunner<Dim>::write_frame() {
  if (settings_.out.empty() || !settings_.frames) return;
  const pic::AdaptivePic<Dim>& s = *sim_;
  std::vector<std::string> grids;
  if (scene_.output.cells) {
    const tree::CellGraph<Dim>& g = s.graph();
    std::vector<double> type(g.cell_capacity(), 0.0);
    for (tree::CellId c = 0; c < g.cell_capacity(); ++c)
      if (g.alive(c)) type[c] = static_cast<double>(s.classification().type[c]);
    std::vector<io::CellField> fields;
    if (scene_.output.writes("pressure")) fields.push_back({"pressure", s.pressure()});
    if (scene_.output.writes("type")) fields.push_back({"type", type});
    const io::TreeFiles f = io::write_tree<Dim>(stem("cells", frame_), g, fields);
    written_.push_back(f.h5);
    grids.push_back(f.grid);
  }
  if (scene_.output.particles) {
    const particles::Particles<Dim>& p = s.particles();
    std::vector<double> v(static_cast<std::size_t>(p.size()) * Dim), speed(p.size());
    for (int i = 0; i < p.size(); ++i) {
      for (int d = 0; d < Dim; ++d) v[static_cast<std::size_t>(i) * Dim + d] = p.v[i][d];
      speed[i] = p.v[i].norm();
    }
    std::vector<io::PointField> fields;
    if (scene_.output.writes("velocity")) fields.push_back({"velocity", Dim, v});
    if (scene_.output.writes("speed")) fields.push_back({"speed", 1, speed});
    const io::PointFiles f = io::write_points<Dim>(stem("particles", frame_), p.x, fields);
    written_.push_back(f.h5);
    grids.push_back(f.grid);
  }
  if (!grids.empty()) {
    io_->series->add(s.time(), grids);
    written_.push_back(io_->series->path());
  }
  ++frame_;
  next_frame_ = detail::next_frame_time(scene_.output, s.time());
}

template <int Dim>
std::string SceneRunner<Dim>::checkpoint() {
  LIQUID_VERIFY(!settings_.out.empty(), "a checkpoint needs an output folder (--out)");
  const pic::PicState<Dim> st = sim_->state();
  const std::string path = stem("checkpoint", st.step) + ".h5";
  io::ArchiveWriter w(path);
  w.put_scalar("dimension", static_cast<std::int64_t>(Dim));
  detail::put_run_settings(w, settings_, settings_.scene_path.empty() ? scene_.path : settings_.scene_path);

  const tree::CellGraphState<Dim>& gs = st.graph;
  w.put("pic/graph/domain_lo", std::span<const double>(gs.domain.lo.data(), Dim));
  w.put("pic/graph/domain_hi", std::span<const double>(gs.domain.hi.data(), Dim));
  const std::vector<std::int32_t> graph_options = {gs.options.max_jump, gs.options.min_level,
                                                   gs.options.max_level};
  w.put("pic/graph/options", std::span<const std::int32_t>(graph_options));
  w.put("pic/graph/level", std::span<const std::int32_t>(gs.level));
  w.put("pic/graph/address", std::span<const std::int64_t>(gs.address));
  w.put("pic/graph/faces", std::span<const std::int32_t>(gs.faces));
  w.put("pic/graph/face_alive", std::span<const std::uint8_t>(gs.face_alive));
  w.put("pic/graph/free_cells", std::span<const std::int32_t>(gs.free_cells));
  w.put("pic/graph/free_faces", std::span<const std::int32_t>(gs.free_faces));
  w.put("pic/particles/x", std::span<const double>(st.x));
  w.put("pic/particles/v", std::span<const double>(st.v));
  w.put("pic/particles/cell", std::span<const std::int32_t>(st.particle_cell));
  std::vector<std::int32_t> components(st.field_components.begin(), st.field_components.end());
  w.put("pic/particles/field_components", std::span<const std::int32_t>(components));
  for (std::size_t f = 0; f < st.field_names.size(); ++f) {
    w.put_string(fmt::format("pic/particles/field_name_{}", f), st.field_names[f]);
    w.put(fmt::format("pic/particles/field_{}", f), std::span<const double>(st.field_values[f]));
  }
  w.put("pic/u", std::span<const double>(st.u));
  w.put("pic/p", std::span<const double>(st.p));
  w.put("pic/known", std::span<const std::uint8_t>(st.known));
  w.put_scalar("pic/time", st.time);
  w.put_scalar("pic/step", static_cast<std::int64_t>(st.step));

  w.put_scalar("run/frame", static_cast<std::int64_t>(frame_));
  w.put_scalar("run/next_frame", next_frame_);
  w.put_scalar("run/steps", static_cast<std::int64_t>(steps_));
  w.put_scalar("run/ppe_iterations", static_cast<std::int64_t>(ppe_iterations_));
  w.put_scalar("run/ppe_failures", static_cast<std::int64_t>(ppe_failures_));
  w.put_scalar("run/ppe_fallbacks", static_cast<std::int64_t>(ppe_fallbacks_));
  w.put_scalar("run/ppe_reused", static_cast<std::int64_t>(ppe_reused_));
  const std::vector<double> sums = {sum_fluid_, sum_cells_, sum_particles_, sum_regular_cells_,
                                    sum_regular_particles_};
  w.put("run/sums", std::span<const double>(sums));
  detail::put_series(w, io_->series.get());
  w.commit();
  written_.push_back(path);
  return path;
}

template <int Dim>
SceneRunner<Dim> SceneRunner<Dim>::resume(const std::string& checkpoint, RunSettings settings) {
  const io::ArchiveReader r(checkpoint);
  LIQUID_VERIFY(r.scalar_int("dimension") == Dim, "{}: a {}D checkpoint, not {}D", checkpoint,
                r.scalar_int("dimension"), Dim);
  LIQUID_VERIFY(!checkpoint_is_sph(checkpoint), "{}: an SPH run's checkpoint, not a PIC run's", checkpoint);
  detail::get_run_settings(r, settings);
  const SceneOverrides& o = settings.overrides;
  Scene<Dim> scene = load_scene<Dim>(settings.scene_path);
  apply_overrides<Dim>(o, scene);

  pic::PicState<Dim> st;
  // The tree's own settings as saved; AdaptivePic::restore() checks them against the scene's.
  const std::vector<double> lo = r.doubles("pic/graph/domain_lo"), hi = r.doubles("pic/graph/domain_hi");
  const std::vector<std::int32_t> graph_options = r.int32s("pic/graph/options");
  LIQUID_VERIFY(lo.size() == Dim && hi.size() == Dim && graph_options.size() == 3,
                "{}: the saved tree's domain or options have the wrong size", checkpoint);
  for (int d = 0; d < Dim; ++d) st.graph.domain.lo[d] = lo[d], st.graph.domain.hi[d] = hi[d];
  st.graph.options.max_jump = graph_options[0];
  st.graph.options.min_level = graph_options[1];
  st.graph.options.max_level = graph_options[2];
  st.graph.level = r.int32s("pic/graph/level");
  st.graph.address = r.int64s("pic/graph/address");
  st.graph.faces = r.int32s("pic/graph/faces");
  st.graph.face_alive = r.uint8s("pic/graph/face_alive");
  st.graph.free_cells = r.int32s("pic/graph/free_cells");
  st.graph.free_faces = r.int32s("pic/graph/free_faces");
  st.x = r.doubles("pic/particles/x");
  st.v = r.doubles("pic/particles/v");
  st.particle_cell = r.int32s("pic/particles/cell");
  const std::vector<std::int32_t> components = r.int32s("pic/particles/field_components");
  for (std::size_t f = 0; f < components.size(); ++f) {
    st.field_names.push_back(r.string(fmt::format("pic/particles/field_name_{}", f)));
    st.field_components.push_back(components[f]);
    st.field_values.push_back(r.doubles(fmt::format("pic/particles/field_{}", f)));
  }
  st.u = r.doubles("pic/u");
  st.p = r.doubles("pic/p");
  st.known = r.uint8s("pic/known");
  st.time = r.scalar_double("pic/time");
  st.step = r.scalar_int("pic/step");

  SceneRunner run(std::move(scene), std::move(settings), false);
  try {
    run.sim_->restore(st);
  } catch (const Error& e) {
    throw Error(fmt::format("{}: {}", checkpoint, e.what()));
  }
  run.frame_ = static_cast<int>(r.scalar_int("run/frame"));
  run.next_frame_ = r.scalar_double("run/next_frame");
  run.steps_ = r.scalar_int("run/steps");
  run.ppe_iterations_ = r.scalar_int("run/ppe_iterations");
  run.ppe_failures_ = r.scalar_int("run/ppe_failures");
  // Checkpoints written before the count existed lack it: those runs kept no hierarchy.
  run.ppe_reused_ = r.has("run/ppe_reused") ? r.scalar_int("run/ppe_reused") : 0;
  run.ppe_fallbacks_ = r.has("run/ppe_fallbacks") ? r.scalar_int("run/ppe_fallbacks") : 0;
  const std::vector<double> sums = r.doubles("run/sums");
  LIQUID_VERIFY(sums.size() == 5, "{}: run/sums has {} entries, expected 5", checkpoint, sums.size());
  run.sum_fluid_ = sums[0], run.sum_cells_ = sums[1], run.sum_particles_ = sums[2];
  run.sum_regular_cells_ = sums[3], run.sum_regular_particles_ = sums[4];
  if (run.io_->series) {
    detail::restore_series(r, run.settings_.out, *run.io_->series);
  }
  return run;
}

template <int Dim>
RunSummary SceneRunner<Dim>::summary() const {
  RunSummary s;
  s.steps = steps_;
  s.time = sim_->time();
  const double n = std::max<long>(steps_, 1);
  s.fluid_cells = sum_fluid_ / n;
  s.cells = sum_cells_ / n;
  s.particles = sum_particles_ / n;
  s.regular_cells = sum_regular_cells_ / n;
  s.regular_particles = sum_regular_particles_ / n;
  const PhaseTimer& t = sim_->timer();
  const auto total = t.entries().find("total");
  const double calls = total == t.entries().end() ? 1.0 : std::max<double>(total->second.calls, 1.0);
  for (const auto& [name, e] : t.entries()) s.seconds[name] = e.seconds / calls;
  s.ppe_iterations = ppe_iterations_;
  s.ppe_failures = ppe_failures_;
  s.ppe_reused = ppe_reused_;
  s.ppe_fallbacks = ppe_fallbacks_;
  s.threads = omp_get_max_threads();
  s.wall = wall_;
  return s;
}

template void apply_overrides<2>(const SceneOverrides&, Scene<2>&);
template void apply_overrides<3>(const SceneOverrides&, Scene<3>&);
template class SceneRunner<2>;
template class SceneRunner<3>;

}  // namespace liquid::scene
