// Scenes: every built-in scene file loads; the loader's values and overrides; a run resumed from a
// checkpoint ends bit for bit where the uninterrupted run ends, frames included.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "liquid/core/error.hpp"
#include "liquid/io/archive.hpp"
#include "liquid/scene/runner.hpp"

namespace liquid {
namespace {

std::string temp_folder(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("liquid-scene-test-" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

TEST(Scene, EveryBuiltinSceneLoadsInItsDimension) {
  const auto scenes = builtin_scenes();
  ASSERT_GE(scenes.size(), 14u);  // seven scenes, 2D and 3D
  for (const auto& [name, description] : scenes) {
    const std::string path = find_scene(name);
    EXPECT_FALSE(description.empty()) << name;
    const int dim = scene_dimension(path);
    EXPECT_EQ(name.substr(name.size() - 2), dim == 2 ? "2d" : "3d") << name;
    if (dim == 2) {
      const Scene<2> s = load_scene<2>(path);
      EXPECT_EQ(s.name, name);
      EXPECT_TRUE(static_cast<bool>(s.liquid));
    } else {
      const Scene<3> s = load_scene<3>(path);
      EXPECT_EQ(s.name, name);
    }
  }
}

TEST(Scene, ValuesAndOverridesReachTheSolverOptions) {
  Scene<2> s = load_scene<2>(find_scene("drop-2d"));
  EXPECT_EQ(s.pic.fine_level, 6);
  EXPECT_EQ(s.pic.coarse_level, 3);
  EXPECT_EQ(s.pic.max_jump, 2);
  EXPECT_TRUE(s.pic.adaptive);
  EXPECT_DOUBLE_EQ(s.time.end, 0.8);
  // The drop moves down, the pool is at rest.
  EXPECT_DOUBLE_EQ(s.velocity(Vec<2>(0.5, 0.7))[1], -1.0);
  EXPECT_DOUBLE_EQ(s.velocity(Vec<2>(0.5, 0.1)).norm(), 0.0);
  EXPECT_LT(s.liquid(Vec<2>(0.5, 0.7)), 0.0);
  EXPECT_GT(s.liquid(Vec<2>(0.5, 0.5)), 0.0);
  SceneOverrides o;
  o.method = "apic";
  o.finest = 5;
  o.steps = 3;
  apply_overrides<2>(o, s);
  EXPECT_EQ(s.pic.transfer, PicTransfer::apic);
  EXPECT_FALSE(s.pic.adaptive);
  EXPECT_EQ(s.pic.fine_level, 5);
  EXPECT_EQ(s.pic.coarse_level, 2);
  EXPECT_EQ(s.time.steps, 3);
  SceneOverrides bad;
  bad.method = "pic";
  bad.adaptive = 1;
  EXPECT_THROW(apply_overrides<2>(bad, s), Error);
  const Scene<3> obstacles = load_scene<3>(find_scene("dam-break-obstacles-3d"));
  ASSERT_TRUE(static_cast<bool>(obstacles.pic.solid));
  EXPECT_LT(obstacles.pic.solid(Vec<3>(0.6, 0.9, 0.3)), 0.0);  // inside the pillar (infinite along y)
  EXPECT_GT(obstacles.pic.solid(Vec<3>(0.2, 0.5, 0.5)), 0.0);
  const Scene<2> sources = load_scene<2>(find_scene("two-sources-2d"));
  ASSERT_EQ(sources.pic.sources.size(), 2u);
  EXPECT_DOUBLE_EQ(sources.pic.sources[1].velocity[0], -1.5);
  EXPECT_TRUE(sources.pic.sources[0].active(0.25));
  EXPECT_FALSE(sources.pic.sources[0].active(0.5));
}

TEST(Scene, OutputFieldsAndTheRegularGridsSolverAreRead) {
  const std::string dir = temp_folder("fields");
  const std::string path = dir + "/fields.toml";
  {
    std::ofstream out(path);
    out << "[domain]\nlo = [0.0, 0.0]\nhi = [1.0, 1.0]\n[grid]\nfinest = 4\n[solver]\nmethod = \"apic\"\n"
           "[time]\nsteps = 2\n[output]\nfields = [\"speed\", \"type\"]\n"
           "[[fluid]]\nshape = \"box\"\nlo = [0.0, 0.0]\nhi = [1.0, 0.5]\n";
  }
  const Scene<2> s = load_scene<2>(path);
  EXPECT_TRUE(s.output.writes("speed"));
  EXPECT_TRUE(s.output.writes("type"));
  EXPECT_FALSE(s.output.writes("pressure"));
  EXPECT_FALSE(s.output.writes("velocity"));
  EXPECT_FALSE(s.pic.adaptive);  // apic runs on a regular grid
  // The regular grid's PPE is the symmetric FD matrix: conjugate gradients unless the file says.
  EXPECT_EQ(s.pic.solver.kind, linalg::SolverKind::cg_jacobi);
  const Scene<2> tree = load_scene<2>(find_scene("pool-2d"));
  EXPECT_EQ(tree.pic.solver.kind, linalg::SolverKind::bicgstab_ilut);
}

TEST(Scene, ResumedRunEndsBitForBitLikeTheUninterruptedOne) {
  for (const char* name : {"dam-break-obstacles-2d", "two-sources-2d"}) {
    const std::string path = find_scene(name);
    SceneOverrides o;
    o.finest = 5;
    o.steps = 10;
    RunSettings settings;
    settings.out = temp_folder(std::string(name) + "-a");
    settings.checkpoint_every = 5;
    settings.overrides = o;
    settings.scene_path = path;
    Scene<2> scene = load_scene<2>(path);
    apply_overrides<2>(o, scene);
    SceneRunner<2> full(scene, settings);
    while (!full.done()) full.step();
    const std::string half =
        (std::filesystem::path(settings.out) / (std::string(name) + "_checkpoint_000005.h5")).string();
    ASSERT_TRUE(std::filesystem::exists(half));

    RunSettings again;
    again.out = temp_folder(std::string(name) + "-b");
    SceneRunner<2> resumed = SceneRunner<2>::resume(half, again);
    EXPECT_EQ(resumed.solver().step(), 5);
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
  const std::string path = find_scene("pool-2d");
  RunSettings settings;
  settings.out = temp_folder("refuse");
  settings.scene_path = path;
  settings.frames = false;
  Scene<2> scene = load_scene<2>(path);
  scene.pic.fine_level = 4;
  scene.pic.coarse_level = 2;
  SceneRunner<2> run(scene, settings);
  run.step();
  const std::string saved = run.checkpoint();
  EXPECT_EQ(checkpoint_dimension(saved), 2);
  EXPECT_THROW(SceneRunner<3>::resume(saved, RunSettings{}), Error);
}

}  // namespace
}  // namespace liquid
