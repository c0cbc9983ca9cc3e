// Scenes: every built-in scene file loads; the loader's values and overrides; a run resumed from a
// checkpoint ends bit for bit where the uninterrupted run ends, frames included.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>

#include "liquid/core/error.hpp"
#include "liquid/io/archive.hpp"
#include "liquid/scene/runner.hpp"
#include "liquid/scene/sph_runner.hpp"

namespace liquid {
namespace {

std::string temp_folder(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("liquid-scene-test-" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

/// Writes `text` as NAME.toml in a fresh temp folder NAME and returns its path.
std::string scene_file(const std::string& name, const std::string& text) {
  const std::string path = temp_folder(name) + "/" + name + ".toml";
  std::ofstream(path) << text;
  return path;
}

/// The text of the built-in scene `name` with `keys` (lines) added to its [solver] table.
std::string builtin_with_solver_keys(const std::string& name, const std::string& keys) {
  std::ifstream in(scene::find_scene(name));
  std::stringstream text;
  text << in.rdbuf();
  std::string toml = text.str();
  const auto at = toml.find("[solver]");
  return at == std::string::npos ? toml + "\n[solver]\n" + keys + "\n" : toml.insert(at + 8, "\n" + keys);
}

TEST(Scene, EveryBuiltinSceneLoadsInItsDimension) {
  const auto scenes = scene::builtin_scenes();
  ASSERT_GE(scenes.size(), 14u);  // seven scenes, 2D and 3D
  for (const auto& [name, description] : scenes) {
    const std::string path = scene::find_scene(name);
    EXPECT_FALSE(description.empty()) << name;
    const int dim = scene::scene_dimension(path);
    EXPECT_EQ(name.substr(name.size() - 2), dim == 2 ? "2d" : "3d") << name;
    if (dim == 2) {
      const scene::Scene<2> s = scene::load_scene<2>(path);
      EXPECT_EQ(s.name, name);
      EXPECT_TRUE(static_cast<bool>(s.liquid));
    } else {
      const scene::Scene<3> s = scene::load_scene<3>(path);
      EXPECT_EQ(s.name, name);
    }
  }
}

TEST(Scene, ValuesAndOverridesReachTheSolverOptions) {
  scene::Scene<2> s = scene::load_scene<2>(scene::find_scene("drop-2d"));
  EXPECT_EQ(s.pic.finest_level, 6);
  EXPECT_EQ(s.pic.coarse_level, 3);
  EXPECT_EQ(s.pic.max_jump, 2);
  EXPECT_TRUE(s.pic.adaptive);
  EXPECT_DOUBLE_EQ(s.time.end, 0.8);
  // The drop moves down, the pool is at rest.
  EXPECT_DOUBLE_EQ(s.velocity(Vec<2>(0.5, 0.7))[1], -1.0);
  EXPECT_DOUBLE_EQ(s.velocity(Vec<2>(0.5, 0.1)).norm(), 0.0);
  EXPECT_LT(s.liquid(Vec<2>(0.5, 0.7)), 0.0);
  EXPECT_GT(s.liquid(Vec<2>(0.5, 0.5)), 0.0);
  scene::SceneOverrides o;
  o.method = "apic";
  o.finest = 5;
  o.steps = 3;
  scene::apply_overrides<2>(o, s);
  EXPECT_EQ(s.pic.transfer, pic::PicTransfer::apic);
  EXPECT_FALSE(s.pic.adaptive);
  EXPECT_EQ(s.pic.finest_level, 5);
  EXPECT_EQ(s.pic.coarse_level, 2);
  EXPECT_EQ(s.time.steps, 3);
  scene::SceneOverrides bad;
  bad.method = "pic";
  bad.adaptive = 1;
  EXPECT_THROW(scene::apply_overrides<2>(bad, s), Error);
  EXPECT_TRUE(s.pic.rbf.share_factors);  // the defaults
  EXPECT_EQ(s.pic.rbf.condition_estimate, rbf::ConditionEstimate::probes);
  EXPECT_EQ(s.pic.poisson.nullspace, mac::Nullspace::zero_mean);
  EXPECT_EQ(s.pic.rbf.exponent, 3);  // the default transfer; reseeding left to the method (top-up)
  EXPECT_EQ(s.pic.rbf.degree, 1);
  EXPECT_EQ(s.pic.reseeding.lo, 0);
  EXPECT_TRUE(s.pic.refill_emptied);
  EXPECT_FALSE(s.paper_preset);
  {
    // --paper: the paper's transfer and its reseeding band, remembered by the scene.
    scene::Scene<2> paper = scene::load_scene<2>(scene::find_scene("drop-2d"));
    scene::SceneOverrides p;
    p.paper = true;
    scene::apply_overrides<2>(p, paper);
    EXPECT_TRUE(paper.paper_preset);
    EXPECT_TRUE(paper.pic.paper_preset());
    EXPECT_EQ(paper.pic.rbf.exponent, 5);
    EXPECT_EQ(paper.pic.rbf.degree, 2);
    EXPECT_EQ(paper.pic.reseeding.lo, 3);
    EXPECT_EQ(paper.pic.reseeding.hi, 12);
    EXPECT_FALSE(paper.pic.refill_emptied);
  }
  {
    // [solver] preset = "paper" does the same; a key after it overrides what the preset set.
    const std::string path = scene_file(
        "paper-preset", builtin_with_solver_keys("drop-2d", "preset = \"paper\"\ntransfer_degree = 1"));
    const scene::Scene<2> paper = scene::load_scene<2>(path);
    EXPECT_TRUE(paper.paper_preset);
    EXPECT_EQ(paper.pic.rbf.exponent, 5);
    EXPECT_EQ(paper.pic.rbf.degree, 1);
    EXPECT_EQ(paper.pic.reseeding.lo, 3);
  }
  {
    // [solver] share_factors = false and condition_estimate = "hager-higham" reach the transfer's
    // options, nullspace = "pin" the PPE's, and the transfer kernel and holes-only reseeding theirs.
    std::string toml = builtin_with_solver_keys(
        "drop-2d",
        "share_factors = false\ncondition_estimate = \"hager-higham\"\nnullspace = \"pin\""
        "\ntransfer_exponent = 3\ntransfer_degree = 1\nreseed_mode = \"holes\"\nppe_degree = 3"
        "\nppe_rows = \"flux\"");
    const std::string path = ::testing::TempDir() + "/own-factors.toml";
    std::ofstream(path) << toml;
    const scene::Scene<2> own = scene::load_scene<2>(path);
    EXPECT_FALSE(own.pic.rbf.share_factors);
    EXPECT_EQ(own.pic.poisson.rbf.degree, 3);  // ppe_degree: the RBF-FD rows and the face gradients
    EXPECT_EQ(own.pic.poisson.gradient_degree, 3);
    EXPECT_EQ(own.pic.poisson.irregular, mac::IrregularRows::flux);
    // The paper's preset (liquid run --paper, applied after the scene's keys) restores its degree 2,
    // and a PPE of another degree is not the paper's.
    pic::PicOptions<2> paper = own.pic;
    EXPECT_FALSE(paper.paper_preset());
    paper.apply_paper_preset();
    EXPECT_TRUE(paper.paper_preset());
    EXPECT_EQ(paper.poisson.rbf.degree, 2);
    EXPECT_EQ(paper.poisson.gradient_degree, 2);
    EXPECT_EQ(paper.poisson.irregular, mac::IrregularRows::laplacian);
    paper.poisson.gradient_degree = 3;
    EXPECT_FALSE(paper.paper_preset());
    paper.poisson.gradient_degree = 2;
    paper.poisson.irregular = mac::IrregularRows::flux;
    EXPECT_FALSE(paper.paper_preset());
    EXPECT_EQ(own.pic.rbf.condition_estimate, rbf::ConditionEstimate::hager_higham);
    EXPECT_EQ(own.pic.poisson.nullspace, mac::Nullspace::pin);
    EXPECT_EQ(own.pic.rbf.exponent, 3);
    EXPECT_EQ(own.pic.rbf.degree, 1);
    EXPECT_EQ(own.pic.reseeding.lo, 1);  // holes only: no cell with a particle is reseeded
    EXPECT_EQ(own.pic.reseeding.hi, std::numeric_limits<int>::max());
    EXPECT_FALSE(own.pic.reseeding.keep);
    // top-up: sparse cells keep their particles and get new ones; crowded cells are never thinned.
    const auto mode = toml.find("reseed_mode = \"holes\"");
    ASSERT_NE(mode, std::string::npos);
    std::string top = toml;
    top.replace(mode, 21, "reseed_mode = \"top-up\"");
    std::ofstream(path) << top;
    const scene::Scene<2> topped = scene::load_scene<2>(path);
    EXPECT_EQ(topped.pic.reseeding.lo, 3);
    EXPECT_EQ(topped.pic.reseeding.hi, std::numeric_limits<int>::max());
    EXPECT_TRUE(topped.pic.reseeding.keep);
  }
  {
    // The face gradients' cap: 2 in 3D by default, none in 2D; [solver] ppe_gradient_cap sets it
    // (0: whole rings), and the paper's preset leaves it.
    const scene::Scene<3> drop = scene::load_scene<3>(scene::find_scene("drop-3d"));
    EXPECT_EQ(drop.pic.poisson.gradient_ring_cap, 2.0);
    EXPECT_EQ(drop.pic.poisson.ring_cap, 0.0);  // the Laplacian rows keep whole rings
    EXPECT_EQ(scene::load_scene<2>(scene::find_scene("drop-2d")).pic.poisson.gradient_ring_cap, 0.0);
    const scene::Scene<3> whole = scene::load_scene<3>(
        scene_file("gradient-cap", builtin_with_solver_keys("drop-3d", "ppe_gradient_cap = 0")));
    EXPECT_EQ(whole.pic.poisson.gradient_ring_cap, 0.0);
    pic::PicOptions<3> paper = drop.pic;
    paper.apply_paper_preset();
    EXPECT_EQ(paper.poisson.gradient_ring_cap, 2.0);
  }
  {
    // reseed_max: without reseed_mode the RBF transfer tops up sparse cells and thins cells holding
    // more than it to 2^d of their own; with a mode it bounds that mode's range; 0 never thins.
    const scene::Scene<3> thin = scene::load_scene<3>(
        scene_file("reseed-max", builtin_with_solver_keys("drop-3d", "reseed_max = 32")));
    EXPECT_EQ(thin.pic.reseeding.lo, 5);
    EXPECT_EQ(thin.pic.reseeding.hi, 32);
    EXPECT_TRUE(thin.pic.reseeding.keep);
    const scene::Scene<2> replace = scene::load_scene<2>(
        scene_file("reseed-max-replace",
                   builtin_with_solver_keys("drop-2d", "reseed_mode = \"replace\"\nreseed_max = 20")));
    EXPECT_EQ(replace.pic.reseeding.lo, 3);
    EXPECT_EQ(replace.pic.reseeding.hi, 20);
    EXPECT_FALSE(replace.pic.reseeding.keep);
    const scene::Scene<2> apic = scene::load_scene<2>(scene_file(
        "reseed-max-apic",
        builtin_with_solver_keys("drop-2d", "method = \"apic\"\nadaptive = false\nreseed_max = 0")));
    EXPECT_EQ(apic.pic.reseeding.lo, 3);
    EXPECT_EQ(apic.pic.reseeding.hi, std::numeric_limits<int>::max());
    EXPECT_FALSE(apic.pic.reseeding.keep);  // the regular methods' own mode replaces
    const scene::Scene<3> paper = scene::load_scene<3>(scene_file(
        "reseed-max-paper", builtin_with_solver_keys("drop-3d", "preset = \"paper\"\nreseed_max = 24")));
    EXPECT_EQ(paper.pic.reseeding.hi, 24);  // a key after the preset overrides it
    EXPECT_FALSE(paper.pic.paper_preset());
  }
  const scene::Scene<3> obstacles = scene::load_scene<3>(scene::find_scene("dam-break-obstacles-3d"));
  ASSERT_TRUE(static_cast<bool>(obstacles.pic.solid));
  EXPECT_LT(obstacles.pic.solid(Vec<3>(0.6, 0.9, 0.3)), 0.0);  // inside the pillar (infinite along y)
  EXPECT_GT(obstacles.pic.solid(Vec<3>(0.2, 0.5, 0.5)), 0.0);
  const scene::Scene<2> sources = scene::load_scene<2>(scene::find_scene("two-sources-2d"));
  ASSERT_EQ(sources.pic.sources.size(), 2u);
  EXPECT_DOUBLE_EQ(sources.pic.sources[1].velocity[0], -1.5);
  EXPECT_TRUE(sources.pic.sources[0].active(0.25));
  EXPECT_FALSE(sources.pic.sources[0].active(0.5));
}

TEST(Scene, OutputFieldsAndTheRegularGridsSolverAreRead) {
  const std::string path = scene_file(
      "fields",
      "[domain]\nlo = [0.0, 0.0]\nhi = [1.0, 1.0]\n[grid]\nfinest = 4\n[solver]\nmethod = \"apic\"\n"
      "[time]\nsteps = 2\n[output]\nfields = [\"speed\", \"type\"]\n"
      "[[fluid]]\nshape = \"box\"\nlo = [0.0, 0.0]\nhi = [1.0, 0.5]\n");
  const scene::Scene<2> s = scene::load_scene<2>(path);
  EXPECT_TRUE(s.output.writes("speed"));
  EXPECT_TRUE(s.output.writes("type"));
  EXPECT_FALSE(s.output.writes("pressure"));
  EXPECT_FALSE(s.output.writes("velocity"));
  EXPECT_FALSE(s.pic.adaptive);  // apic runs on a regular grid
  // The regular grid's PPE is the symmetric FD matrix: conjugate gradients unless the file says.
  EXPECT_EQ(s.pic.solver.kind, linalg::SolverKind::cg_jacobi);
  const scene::Scene<2> tree = scene::load_scene<2>(scene::find_scene("pool-2d"));
  EXPECT_EQ(tree.pic.solver.kind, linalg::SolverKind::bicgstab_ilut);
}

// A fluid's velocity given as expressions in x, y: the field is evaluated where the shape holds the
// point (the last shape wins), zero elsewhere, and its largest speed over the shape is kept.
TEST(Scene, VelocityExpressionsGiveTheInitialField) {
  const std::string path =
      scene_file("velocity",
                 "[domain]\nlo = [0.0, 0.0]\nhi = [2.0, 2.0]\n[grid]\nfinest = 4\n[time]\nsteps = 2\n"
                 "[[fluid]]\nshape = \"box\"\nlo = [0.0, 0.0]\nhi = [2.0, 1.0]\n"
                 "velocity = [\"sin(pi*x)*y\", \"-2*x\"]\n"
                 "[[fluid]]\nshape = \"sphere\"\ncentre = [1.5, 1.5]\nradius = 0.25\nvelocity = [0.5, 0]\n");
  const scene::Scene<2> s = scene::load_scene<2>(path);
  ASSERT_TRUE(s.velocity);
  const Vec<2> a(0.25, 0.5);
  EXPECT_DOUBLE_EQ(s.velocity(a)[0], std::sin(std::numbers::pi * 0.25) * 0.5);
  EXPECT_DOUBLE_EQ(s.velocity(a)[1], -0.5);
  EXPECT_DOUBLE_EQ(s.velocity(Vec<2>(1.5, 1.5))[0], 0.5);
  EXPECT_EQ(s.velocity(Vec<2>(0.5, 1.7)), Vec<2>::Zero());
  // The largest speed over the box's lattice: at x = 2, y = 1, |(0, -4)| = 4 (above the sphere's 0.5).
  EXPECT_NEAR(s.max_initial_speed, 4.0, 1e-12);
}

TEST(Scene, TheMemoryEstimateHoldsTheSeededParticlesAndGrowsWithTheLevel) {
  // On a uniform grid the estimate counts the particles the seeding makes (within the sampling's
  // error); on a tree it bounds them; one level finer multiplies it by about 2^Dim (uniform).
  for (const char* name : {"dam-break-2d", "drop-2d", "dam-break-obstacles-2d"})
    for (int adaptive : {0, 1}) {
      scene::SceneOverrides o;
      o.finest = 6;
      o.steps = 1;
      o.adaptive = adaptive;
      if (!adaptive) o.method = "apic";
      scene::Scene<2> scene = scene::load_scene<2>(scene::find_scene(name));
      scene::apply_overrides<2>(o, scene);
      const scene::PicSize size = scene::estimate_pic_size<2>(scene);
      scene::RunSettings settings;
      settings.overrides = o;
      settings.scene_path = scene::find_scene(name);
      const scene::SceneRunner<2> run(scene, settings);
      const double seeded = run.solver().particles().size();
      if (adaptive) {
        EXPECT_GE(size.particles, seeded) << name;
        EXPECT_LT(size.particles, 4.0 * seeded) << name;
      } else {
        EXPECT_NEAR(size.particles / seeded, 1.0, 0.1) << name;
      }
      o.finest = 7;
      scene::Scene<2> finer = scene::load_scene<2>(scene::find_scene(name));
      scene::apply_overrides<2>(o, finer);
      if (!adaptive) {
        EXPECT_NEAR(scene::estimate_pic_size<2>(finer).particles / size.particles, 4.0, 0.2) << name;
      }
    }
}

TEST(Scene, ResumedRunEndsBitForBitLikeTheUninterruptedOne) {
  for (const char* name : {"dam-break-obstacles-2d", "two-sources-2d"}) {
    const std::string path = scene::find_scene(name);
    scene::SceneOverrides o;
    o.finest = 5;
    o.steps = 10;
    scene::RunSettings settings;
    settings.out = temp_folder(std::string(name) + "-a");
    settings.checkpoint_every = 5;
    settings.overrides = o;
    settings.scene_path = path;
    scene::Scene<2> scene = scene::load_scene<2>(path);
    scene::apply_overrides<2>(o, scene);
    scene::SceneRunner<2> full(scene, settings);
    while (!full.done()) full.step();
    const std::string half =
        (std::filesystem::path(settings.out) / (std::string(name) + "_checkpoint_000005.h5")).string();
    ASSERT_TRUE(std::filesystem::exists(half));

    scene::RunSettings again;
    again.out = temp_folder(std::string(name) + "-b");
    scene::SceneRunner<2> resumed = scene::SceneRunner<2>::resume(half, again);
    EXPECT_EQ(resumed.solver().steps(), 5);
    while (!resumed.done()) resumed.step();
    const auto& a = full.solver().particles();
    const auto& b = resumed.solver().particles();
    ASSERT_EQ(a.size(), b.size()) << name;
    for (int i = 0; i < a.size(); ++i) {
      ASSERT_EQ(a.x[i], b.x[i]) << name << " particle " << i;
      ASSERT_EQ(a.v[i], b.v[i]) << name << " particle " << i;
    }
    EXPECT_EQ(full.solver().time(), resumed.solver().time());
    // The summary covers the whole run on both sides.
    EXPECT_EQ(full.summary().steps, resumed.summary().steps);
    EXPECT_EQ(full.summary().fluid_cells, resumed.summary().fluid_cells);
    EXPECT_EQ(full.n_frames(), resumed.n_frames());
  }
}

TEST(Scene, CheckpointOfAnotherDimensionOrWithoutItsSceneIsRefused) {
  const std::string path = scene::find_scene("pool-2d");
  scene::RunSettings settings;
  settings.out = temp_folder("refuse");
  settings.scene_path = path;
  settings.frames = false;
  scene::Scene<2> scene = scene::load_scene<2>(path);
  scene.pic.finest_level = 4;
  scene.pic.coarse_level = 2;
  scene::SceneRunner<2> run(scene, settings);
  run.step();
  const std::string saved = run.checkpoint();
  EXPECT_EQ(scene::checkpoint_dimension(saved), 2);
  EXPECT_THROW(scene::SceneRunner<3>::resume(saved, scene::RunSettings{}), Error);
}

TEST(SphScene, KeysReachTheSolverOptions) {
  const scene::Scene<2> s = scene::load_scene<2>(scene::find_scene("sph-dam-break-2d"));
  ASSERT_TRUE(s.sph);
  EXPECT_FALSE(s.grid_given);
  const sph::SphOptions<2> o = scene::sph_options<2>(s);
  EXPECT_DOUBLE_EQ(o.spacing, 0.01);
  EXPECT_EQ(o.max_level, 3);
  EXPECT_TRUE(o.adaptive);
  EXPECT_DOUBLE_EQ(s.sph_scene.settle, 0.2);
  ASSERT_TRUE(s.sph_scene.gate);
  EXPECT_DOUBLE_EQ(s.sph_scene.gate_box.hi[1], 0.6);
  // Sound speed: 10 sqrt(2 g 0.6), the column's fall to the floor; stiffness rho_0 c^2.
  EXPECT_NEAR(scene::sph_sound_speed<2>(s), 10.0 * std::sqrt(2.0 * 9.81 * 0.6), 1e-9);
  EXPECT_NEAR(o.fluid.stiffness, 1000.0 * 100.0 * 2.0 * 9.81 * 0.6, 1e-6);
  // SPH's default step bounds: CFL 0.25 of the sound speed, no floor that would override it.
  EXPECT_DOUBLE_EQ(s.time.cfl, 0.25);
  EXPECT_LE(s.time.dt_min, 1e-9);
  EXPECT_EQ(s.output.fields, scene::SceneOutput::sph_fields());

  const scene::Scene<2> toy = scene::load_scene<2>(scene::find_scene("sph-desk-toy-2d"));
  const sph::SphOptions<2> t = scene::sph_options<2>(toy);
  EXPECT_NEAR(t.rotation.angle, 3.141592653589793, 1e-12);
  EXPECT_DOUBLE_EQ(t.rotation.duration, 0.6);
  EXPECT_EQ(t.rotation.pivot, Vec<2>(0.3, 0.5));  // the domain's centre
  EXPECT_EQ(t.obstacles.size(), 1u);              // the solids, united
  const scene::Scene<2> pour = scene::load_scene<2>(scene::find_scene("sph-pour-2d"));
  const sph::SphOptions<2> p = scene::sph_options<2>(pour);
  ASSERT_EQ(p.sources.size(), 1u);
  EXPECT_DOUBLE_EQ(p.sources[0].stop, 1.0);
  EXPECT_DOUBLE_EQ(p.sources[0].bounds.lo[0], 0.05);
}

TEST(SphScene, APicSceneRunsBySphAtHalfItsFinestCell) {
  scene::Scene<2> s = scene::load_scene<2>(scene::find_scene("dam-break-2d"));
  scene::SceneOverrides o;
  o.method = "sph";
  o.finest = 5;
  scene::apply_overrides<2>(o, s);
  ASSERT_TRUE(s.sph);
  EXPECT_DOUBLE_EQ(scene::sph_options<2>(s).spacing, 0.5 / 32.0);
  EXPECT_EQ(s.output.fields, scene::SceneOutput::sph_fields());
  EXPECT_DOUBLE_EQ(s.time.cfl, 0.25);
  // An SPH scene's given spacing is not moved by --finest, and --spacing is an SPH option only.
  scene::Scene<2> d = scene::load_scene<2>(scene::find_scene("sph-dam-break-2d"));
  scene::SceneOverrides finest;
  finest.finest = 6;
  EXPECT_THROW(scene::apply_overrides<2>(finest, d), Error);
  scene::SceneOverrides spacing;
  spacing.spacing = 0.02;
  scene::Scene<2> pic = scene::load_scene<2>(scene::find_scene("pool-2d"));
  EXPECT_THROW(scene::apply_overrides<2>(spacing, pic), Error);
  scene::apply_overrides<2>(spacing, d);
  EXPECT_DOUBLE_EQ(scene::sph_options<2>(d).spacing, 0.02);
  // An SPH scene without [grid] cannot run a PIC method.
  scene::SceneOverrides rbf;
  rbf.method = "rbf";
  scene::Scene<2> d2 = scene::load_scene<2>(scene::find_scene("sph-dam-break-2d"));
  EXPECT_THROW(scene::apply_overrides<2>(rbf, d2), Error);
}

TEST(SphScene, ResumedRunEndsBitForBitLikeTheUninterruptedOne) {
  // The pour: sources add particles, resampling splits and merges (random directions).
  const std::string path = scene::find_scene("sph-pour-2d");
  scene::SceneOverrides o;
  o.spacing = 0.02;
  o.steps = 40;
  scene::RunSettings settings;
  settings.out = temp_folder("sph-pour-a");
  settings.checkpoint_every = 20;
  settings.overrides = o;
  settings.scene_path = path;
  scene::Scene<2> scene = scene::load_scene<2>(path);
  scene::apply_overrides<2>(o, scene);
  scene::SphSceneRunner<2> full(scene, settings);
  while (!full.done()) full.step();
  const scene::SphRunSummary fs = full.summary();
  EXPECT_GT(fs.emitted, 0);
  EXPECT_GT(fs.split + fs.merged, 0);
  const std::string half =
      (std::filesystem::path(settings.out) / "sph-pour-2d_checkpoint_000020.h5").string();
  ASSERT_TRUE(std::filesystem::exists(half));
  EXPECT_TRUE(scene::checkpoint_is_sph(half));

  scene::RunSettings again;
  again.out = temp_folder("sph-pour-b");
  scene::SphSceneRunner<2> resumed = scene::SphSceneRunner<2>::resume(half, again);
  EXPECT_EQ(resumed.solver().steps(), 20);
  while (!resumed.done()) resumed.step();
  const auto& a = full.solver().particles();
  const auto& b = resumed.solver().particles();
  ASSERT_EQ(a.size(), b.size());
  for (int i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a.x[i], b.x[i]) << "particle " << i;
    ASSERT_EQ(a.v[i], b.v[i]) << "particle " << i;
    ASSERT_EQ(a.density[i], b.density[i]) << "particle " << i;
    ASSERT_EQ(a.level[i], b.level[i]) << "particle " << i;
  }
  EXPECT_EQ(full.solver().time(), resumed.solver().time());
  const scene::SphRunSummary rs = resumed.summary();
  EXPECT_EQ(fs.steps, rs.steps);
  EXPECT_EQ(fs.particles, rs.particles);
  EXPECT_EQ(fs.split, rs.split);
  EXPECT_EQ(fs.churn_merged, rs.churn_merged);  // the particles' births travel in the checkpoint
  EXPECT_EQ(fs.churn_split, rs.churn_split);
  const auto& born = full.solver().particles().born;
  EXPECT_TRUE(std::any_of(born.begin(), born.end(), [](std::int64_t step) { return step >= 0; }));
  EXPECT_EQ(born, resumed.solver().particles().born);
  EXPECT_EQ(full.solver().particles().birth, resumed.solver().particles().birth);
  EXPECT_EQ(fs.max_density_error, rs.max_density_error);
  EXPECT_EQ(fs.max_compression, rs.max_compression);
  EXPECT_EQ(fs.rested, rs.rested);
  EXPECT_GT(fs.max_compression, 0.0);
  EXPECT_EQ(full.n_frames(), resumed.n_frames());
  // A PIC runner refuses the SPH checkpoint and the SPH runner a PIC scene.
  EXPECT_THROW(scene::SceneRunner<2>::resume(half, again), Error);
  EXPECT_THROW(
      scene::SphSceneRunner<2>(scene::load_scene<2>(scene::find_scene("pool-2d")), scene::RunSettings{}),
      Error);
}

TEST(SphScene, EveryKeyRefusesABadValueByName) {
  // Each entry: the [sph] lines (replacing the spacing line) and what the message must name.
  const std::vector<std::pair<std::string, std::string>> bad{
      {"spacing = -0.01", "key 'sph.spacing': must be positive"},
      {"spacing = nan", "key 'sph.spacing': expected a finite number"},
      {"spacing = \"small\"", "key 'sph.spacing': expected a number, found a string"},
      {"spacing = 1e-7", "over the budget"},
      {"spacing = 5.0", "is not below the domain's shortest side"},
      {"spacing = 0.02\nlevels = -1", "key 'sph.levels': -1 is outside"},
      {"spacing = 0.02\nlevels = 99", "key 'sph.levels': 99 is outside"},
      {"spacing = 0.02\nresample_every = 0", "key 'sph.resample_every': 0 is outside"},
      {"spacing = 0.02\nalpha = 0.0", "key 'sph.alpha': must be positive"},
      {"spacing = 0.02\nkernel = \"\"", "key 'sph.kernel': '' is not one of"},
      {"spacing = 0.02\ndensity = \"sum\"", "key 'sph.density': 'sum' is not one of"},
      {"spacing = 0.02\npressure = 3", "key 'sph.pressure': expected a string"},
      {"spacing = 0.02\ndensity_diffusion = 2.0", "key 'sph.density_diffusion': 2 is outside"},
      {"spacing = 0.02\nrest_density = 0.0", "key 'sph.rest_density': must be positive"},
      {"spacing = 0.02\nsound_speed = -5.0", "key 'sph.sound_speed': must be positive"},
      {"spacing = 0.02\nviscosity = -1.0", "key 'sph.viscosity': must not be negative"},
      {"spacing = 0.02\nviscosity = inf", "key 'sph.viscosity': expected a finite number"},
      {"spacing = 0.02\nsearch = \"octree\"", "key 'sph.search': 'octree' is not one of"},
      {"spacing = 0.02\nsurface = \"marching\"", "key 'sph.surface': 'marching' is not one of"},
      {"spacing = 0.02\nsettle = -0.1", "key 'sph.settle': must not be negative"},
      {"spacing = 0.02\nsettle = 0.1\ngate_lo = [0.0, 0.0]", "give both gate_lo and gate_hi"},
      {"spacing = 0.02\nsettle = 0.1\ngate_lo = [0.0, 0.0]\ngate_hi = [2.0, 0.6]",
       "reaches outside the domain"},
      {"spacing = 0.02\nsettle = 0.1\ngate_lo = [0.5, 0.0]\ngate_hi = [0.4, 0.6]", "hi must exceed lo"},
      {"spacing = 0.02\nrestitution = 1.5", "key 'sph.restitution': 1.5 is outside"},
      {"spacing = 0.02\nneighbour_skin = -0.1", "key 'sph.neighbour_skin': -0.1 is outside"},
      {"spacing = 0.02\nneighbour_skin = nan", "key 'sph.neighbour_skin': expected a finite number"},
      {"spacing = 0.02\nwall_footpoints = 1", "key 'sph.wall_footpoints': expected true or false"},
      {"spacing = 0.02\nmirror_walls = 0", "key 'sph.mirror_walls': expected true or false"},
      {"spacing = 0.02\nkicked_density_rate = \"no\"",
       "key 'sph.kicked_density_rate': expected true or false"},
      {"spacing = 0.02\nmean_radius_gradient = 2", "key 'sph.mean_radius_gradient': expected true or false"},
      {"spacing = 0.02\nfree_particles_at_rest = 1",
       "key 'sph.free_particles_at_rest': expected true or false"},
      {"spacing = 0.02\nshifting = 0.5", "key 'sph.shifting': 0.5 is outside"},
      {"spacing = 0.02\nmirror_walls = \"\"", "key 'sph.mirror_walls': expected true or false"},
      {"spacing = 0.02\nseed = -1", "key 'sph.seed': -1 is outside"},
      {"spacing = 0.02\nturn_angle = 1e9", "more than ten turns"},
      {"spacing = 0.02\nturn_angle = 90.0\nturn_duration = 0.0", "key 'sph.turn_duration': must be positive"},
      {"spacing = 0.02\nturn_duration = 1.0", "does not turn without sph.turn_angle"},
      {"spacing = 0.02\nturn_angle = 90.0\nturn_pivot = [0.5]", "key 'sph.turn_pivot': expected 2 numbers"},
      {"spacing = 0.02\nview_eye = [0.5, 2.0]\nview_target = [0.5, 2.0]\nview_angle = 20.0",
       "the target is the eye"},
      {"spacing = 0.02\nview_eye = [0.5, 2.0]\nview_target = [0.5, 0.0]\nview_angle = nan",
       "key 'sph.view_angle': expected a finite number"},
      {"spacing = 0.02\n[output]\nsurface = 1", "key 'output.surface': expected true or false"},
  };
  const std::string dir = temp_folder("sph-bad-keys");
  int k = 0;
  for (const auto& [lines, expected] : bad) {
    const std::string path = fmt::format("{}/bad-{}.toml", dir, k++);
    {
      std::ofstream out(path);
      out << "[domain]\nlo = [0.0, 0.0]\nhi = [1.0, 1.0]\n[solver]\nmethod = \"sph\"\n[time]\nend = 1.0\n"
             "[[fluid]]\nshape = \"box\"\nlo = [0.0, 0.0]\nhi = [0.4, 0.6]\n[sph]\n"
          << lines << "\n";
    }
    try {
      scene::load_scene<2>(path);
      ADD_FAILURE() << "accepted: " << lines;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << lines << "\n" << e.what();
    }
  }
  // 3D: a turn about no axis.
  const std::string path3 = dir + "/axis.toml";
  {
    std::ofstream out(path3);
    out << "[domain]\nlo = [0.0, 0.0, 0.0]\nhi = [1.0, 1.0, 1.0]\n[solver]\nmethod = \"sph\"\n[time]\nend = "
           "1.0\n"
           "[[fluid]]\nshape = \"box\"\nlo = [0.0, 0.0, 0.0]\nhi = [0.4, 0.6, 1.0]\n[sph]\nspacing = 0.05\n"
           "turn_angle = 90.0\nturn_axis = [0.0, 0.0, 0.0]\n";
  }
  EXPECT_THROW(scene::load_scene<3>(path3), Error);
}

}  // namespace
}  // namespace liquid
