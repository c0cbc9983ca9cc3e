// Uniform patches: which cells and faces are in them, and that their transfers are the regular
// baselines' APIC, walls included, on uniform and on non-graded trees.

#include <gtest/gtest.h>

#include <omp.h>

#include <random>

#include "liquid/core/error.hpp"
#include "liquid/particles/seeding.hpp"
#include "liquid/transfer/patches.hpp"
#include "liquid/transfer/regular.hpp"
#include "liquid/transfer/scattered.hpp"
#include "liquid/transfer/velocity_field.hpp"
#include "liquid/tree/builders.hpp"

namespace liquid {
namespace {

template <typename T>
class PatchesTest : public ::testing::Test {};
using Dims = ::testing::Types<std::integral_constant<int, 2>, std::integral_constant<int, 3>>;
TYPED_TEST_SUITE(PatchesTest, Dims);

/// An affine field: row k of `grad` is the gradient of component k.
template <int Dim>
struct Affine {
  Vec<Dim> at0;
  Eigen::Matrix<double, Dim, Dim> grad;
  Vec<Dim> operator()(const Vec<Dim>& x) const { return at0 + grad * x; }
};

template <int Dim>
Affine<Dim> some_affine() {
  Affine<Dim> a;
  for (int k = 0; k < Dim; ++k) {
    a.at0[k] = 0.3 - 0.7 * k;
    for (int j = 0; j < Dim; ++j) a.grad(k, j) = 1.0 + k - 0.5 * j;
  }
  return a;
}

template <int Dim>
std::vector<double> sampled(const tree::CellGraph<Dim>& g, const Affine<Dim>& field) {
  std::vector<double> u(g.face_capacity(), 0.0);
  g.for_each_face([&](tree::FaceId f) { u[f] = field(g.face_centre(f))[g.face(f).axis]; });
  return u;
}

template <int Dim>
particles::Particles<Dim> seeded_with_affine(const tree::CellGraph<Dim>& g, std::uint64_t seed) {
  particles::Particles<Dim> p;
  particles::SeedOptions o;
  o.jitter = 0.9;
  o.seed = seed;
  particles::seed_region<Dim>(
      g, [](const Vec<Dim>&) { return -1.0; }, o, p);
  p.add_field("apic", Dim * Dim);
  return p;
}

/// The brute-force definition: level >= 1 and every in-domain cell of the 3^Dim block a leaf of c's level.
template <int Dim>
bool in_patch(const tree::CellGraph<Dim>& g, tree::CellId c) {
  const int level = g.level(c);
  if (level < 1) return false;
  const long n = 1L << level;
  for (int i = 0; i < (Dim == 2 ? 9 : 27); ++i) {
    IVec<Dim> b = g.address(c);
    bool inside = true;
    for (int j = 0, r = i; j < Dim; ++j, r /= 3) {
      b[j] += r % 3 - 1;
      inside = inside && b[j] >= 0 && b[j] < n;
    }
    if (inside && g.find(level, b) == tree::no_cell) return false;
  }
  return true;
}

TYPED_TEST(PatchesTest, OnAUniformTreeTheyAreTheRegularBaselinesApic) {
  constexpr int Dim = TypeParam::value;
  const auto g = tree::uniform<Dim>(Box<Dim>{}, Dim == 2 ? 4 : 3);
  const transfer::RegularLattice<Dim> lattice(g);
  const std::vector<tree::CellId> cells = g.cell_ids();
  const transfer::UniformPatches<Dim> patches(g, cells);
  EXPECT_EQ(patches.n_cells(), g.n_cells());
  EXPECT_EQ(patches.n_faces(), g.n_faces());
  // Random particles everywhere, walls included, with random velocities and affine matrices.
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> pos(0.0, 1.0), val(-1.0, 1.0);
  particles::Particles<Dim> p;
  const int apic = p.add_field("apic", Dim * Dim);
  for (int i = 0; i < 400; ++i) {
    Vec<Dim> x, v;
    for (int k = 0; k < Dim; ++k) x[k] = pos(rng), v[k] = val(rng);
    p.push_back(x, v);
  }
  for (double& c : p.field(apic)) c = val(rng);
  particles::CellBins bins;
  particles::bin_particles<Dim>(g, p.x, bins);
  transfer::FaceValues regular, patched;
  transfer::linear_to_faces<Dim>(g, lattice, p, bins, transfer::RegularScheme::apic, {}, regular);
  patched.reset(g.face_capacity());
  const transfer::TransferReport r = patches.to_faces(p, bins, p.field(apic), patched);
  EXPECT_EQ(r.targets, g.n_faces());
  g.for_each_face([&](tree::FaceId f) {
    ASSERT_EQ(patched.known[f], regular.known[f]) << "face " << f;
    EXPECT_NEAR(patched.value[f], regular.value[f], 1e-12) << "face " << f;
    EXPECT_NEAR(patched.weight[f], regular.weight[f], 1e-12) << "face " << f;
  });
  // Face -> particle, with the affine matrix.
  std::vector<double> u(g.face_capacity());
  for (double& x : u) x = val(rng);
  std::vector<Vec<Dim>> v(p.size());
  std::vector<double> c(p.size() * Dim * Dim);
  transfer::linear_to_points<Dim>(lattice, u, p.x, v, c);
  for (int i = 0; i < p.size(); ++i) {
    double mine[Dim * Dim];
    const Vec<Dim> w = patches.value(bins.cell[i], p.x[i], u, mine);
    EXPECT_LT((w - v[i]).cwiseAbs().maxCoeff(), 1e-12) << "particle " << i;
    for (int j = 0; j < Dim * Dim; ++j) EXPECT_NEAR(mine[j], c[i * Dim * Dim + j], 1e-10) << "particle " << i;
  }
}

TYPED_TEST(PatchesTest, OnNonGradedTreesTheyAreExactlyTheUniformBlocksAndReproduceAffineFields) {
  constexpr int Dim = TypeParam::value;
  tree::CellGraphOptions<Dim> options;
  options.max_jump = 2;
  const Box<Dim> domain{Vec<Dim>::Constant(-1.0), Vec<Dim>::Constant(1.0)};
  const auto g = tree::random<Dim>(domain, 33, 2, Dim == 2 ? 6 : 4, 0.3, options);
  const std::vector<tree::CellId> cells = g.cell_ids();
  const transfer::UniformPatches<Dim> patches(g, cells);
  long inside = 0, outside = 0;
  g.for_each_cell([&](tree::CellId c) {
    EXPECT_EQ(patches.cell(c), in_patch(g, c)) << "cell " << c;
    (patches.cell(c) ? inside : outside) += 1;
  });
  EXPECT_GT(inside, 0);
  EXPECT_GT(outside, 0);
  long faces = 0;
  g.for_each_face([&](tree::FaceId f) {
    bool all = true;
    for (tree::CellId s : g.face(f).cell) all = all && (s == tree::no_cell || patches.cell(s));
    EXPECT_EQ(patches.face(f), all) << "face " << f;
    faces += all;
  });
  EXPECT_EQ(patches.n_faces(), faces);
  // An affine field: particles carrying its value and gradient give it exactly at patch faces,
  // and patch cells give it (and its gradient) exactly back at any point.
  const Affine<Dim> field = some_affine<Dim>();
  auto p = seeded_with_affine<Dim>(g, 5);
  const int apic = p.find_field("apic");
  for (int i = 0; i < p.size(); ++i) {
    p.v[i] = field(p.x[i]);
    for (int k = 0; k < Dim; ++k)
      for (int j = 0; j < Dim; ++j) p.field(apic)[(i * Dim + k) * Dim + j] = field.grad(k, j);
  }
  particles::CellBins bins;
  particles::bin_particles<Dim>(g, p.x, bins);
  transfer::FaceValues out;
  out.reset(g.face_capacity());
  const transfer::TransferReport r = patches.to_faces(p, bins, p.field(apic), out);
  EXPECT_EQ(r.empty, 0);
  double worst = 0.0;
  g.for_each_face([&](tree::FaceId f) {
    if (!patches.face(f)) {
      EXPECT_FALSE(out.known[f]) << "a face outside the patches was written: " << f;
      return;
    }
    worst = std::max(worst, std::abs(out.value[f] - field(g.face_centre(f))[g.face(f).axis]));
  });
  EXPECT_LT(worst, 1e-12);
  const std::vector<double> u = sampled(g, field);
  double worst_back = 0.0, worst_grad = 0.0;
  long checked = 0;
  for (int i = 0; i < p.size(); ++i) {
    if (!patches.cell(bins.cell[i])) continue;
    // Within half a cell of a wall the coordinate is held on the last lattice line (constant
    // extrapolation, derivative 0), as the regular baselines do; elsewhere exact.
    const Vec<Dim> x = p.x[i];
    bool near_wall = false;
    for (int j = 0; j < Dim; ++j)
      near_wall = near_wall || x[j] < domain.lo[j] + 0.5 * g.cell_size(bins.cell[i])[j] ||
                  x[j] > domain.hi[j] - 0.5 * g.cell_size(bins.cell[i])[j];
    if (near_wall) continue;
    double c[Dim * Dim];
    worst_back = std::max(worst_back, (patches.value(bins.cell[i], p.x[i], u, c) - field(p.x[i])).norm());
    ++checked;
    for (int k = 0; k < Dim; ++k)
      for (int j = 0; j < Dim; ++j)
        worst_grad = std::max(worst_grad, std::abs(c[k * Dim + j] - field.grad(k, j)));
  }
  EXPECT_GT(checked, 0);
  EXPECT_LT(worst_back, 1e-12);
  EXPECT_LT(worst_grad, 1e-11);
}

/// The scatter (to_faces) is the gather's definition up to the order of each face's sums, on one
/// thread and on two, with particles anywhere in their cells, random velocities and affine matrices,
/// on a non-graded tree that has both scattered faces and faces on the patches' rims.
TYPED_TEST(PatchesTest, TheScatterIsTheGatherOnAnyThreadCount) {
  constexpr int Dim = TypeParam::value;
  tree::CellGraphOptions<Dim> options;
  options.max_jump = 2;
  const Box<Dim> domain{Vec<Dim>::Constant(-1.0), Vec<Dim>::Constant(1.0)};
  const auto g = tree::random<Dim>(domain, 34, 2, Dim == 2 ? 6 : 4, 0.3, options);
  const transfer::UniformPatches<Dim> patches(g, g.cell_ids());
  ASSERT_GT(patches.n_rim_faces(), 0);
  ASSERT_GT(patches.n_faces() - patches.n_rim_faces(), 0);
  auto p = seeded_with_affine<Dim>(g, 9);
  const int apic = p.find_field("apic");
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> val(-1.0, 1.0);
  for (int i = 0; i < p.size(); ++i)
    for (int k = 0; k < Dim; ++k) p.v[i][k] = val(rng);
  for (double& c : p.field(apic)) c = val(rng);
  particles::CellBins bins;
  particles::bin_particles<Dim>(g, p.x, bins);
  transfer::FaceValues gathered;
  gathered.reset(g.face_capacity());
  const transfer::TransferReport rg = patches.to_faces_gather(p, bins, p.field(apic), gathered);
  const int threads = omp_get_max_threads();
  std::vector<double> on_one;
  for (int t : {1, 2}) {
    omp_set_num_threads(t);
    transfer::FaceValues scattered;
    scattered.reset(g.face_capacity());
    const transfer::TransferReport rs = patches.to_faces(p, bins, p.field(apic), scattered);
    EXPECT_EQ(rs.targets, rg.targets);
    EXPECT_EQ(rs.empty, rg.empty);
    long compared = 0;
    g.for_each_face([&](tree::FaceId f) {
      ASSERT_EQ(scattered.known[f], gathered.known[f]) << "face " << f;
      if (!patches.face(f)) return;
      EXPECT_NEAR(scattered.value[f], gathered.value[f], 1e-13 * (1.0 + std::abs(gathered.value[f])))
          << "face " << f;
      EXPECT_NEAR(scattered.weight[f], gathered.weight[f], 1e-13 * gathered.weight[f]) << "face " << f;
      compared += gathered.known[f];
    });
    EXPECT_GT(compared, patches.n_rim_faces());
    if (t == 1)
      on_one = scattered.value;
    else
      EXPECT_EQ(scattered.value, on_one) << "the scatter's bits depend on the thread count";
  }
  omp_set_num_threads(threads);
}

TYPED_TEST(PatchesTest, TheRbfTransferSkipsPatchFacesAndTheVelocityFieldUsesThePatches) {
  constexpr int Dim = TypeParam::value;
  tree::CellGraphOptions<Dim> options;
  options.max_jump = 3;
  const Box<Dim> domain{Vec<Dim>::Constant(-1.0), Vec<Dim>::Constant(1.0)};
  const auto g = tree::random<Dim>(domain, 7, 2, Dim == 2 ? 6 : 4, 0.3, options);
  const std::vector<tree::CellId> cells = g.cell_ids();
  const transfer::UniformPatches<Dim> patches(g, cells);
  auto p = seeded_with_affine<Dim>(g, 9);
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> val(-1.0, 1.0);
  for (auto& v : p.v)
    for (int k = 0; k < Dim; ++k) v[k] = val(rng);
  particles::CellBins bins;
  particles::bin_particles<Dim>(g, p.x, bins);
  transfer::TransferOptions o;
  o.exponent = 3, o.degree = 1;
  transfer::FaceValues all, skipped;
  transfer::particles_to_faces<Dim>(g, p, bins, o, all);
  const transfer::TransferReport r =
      transfer::particles_to_faces<Dim>(g, p, bins, o, skipped, patches.face_mask());
  EXPECT_EQ(r.targets, g.n_faces() - patches.n_faces());
  g.for_each_face([&](tree::FaceId f) {
    if (patches.face(f))
      EXPECT_FALSE(skipped.known[f]);
    else
      EXPECT_EQ(skipped.value[f], all.value[f]);
  });
  std::vector<double> u(g.face_capacity());
  for (double& x : u) x = val(rng);
  const transfer::FaceVelocityField<Dim> plain(g, u, {}, o);
  const transfer::FaceVelocityField<Dim> hybrid(g, u, {}, o, cells, &patches);
  long patched = 0, other = 0;
  for (int i = 0; i < p.size(); ++i) {
    const tree::CellId c = bins.cell[i];
    if (patches.cell(c)) {
      EXPECT_LT((hybrid(p.x[i]) - patches.value(c, p.x[i], u)).norm(), 1e-14);
      ++patched;
    } else {
      EXPECT_LT((hybrid(p.x[i]) - plain(p.x[i])).norm(), 1e-14);
      ++other;
    }
  }
  EXPECT_GT(patched, 0);
  EXPECT_GT(other, 0);
}

/// A random non-graded tree (level jumps up to 3), its patches, and particles seeded in it with
/// random velocities in [-1, 1] (C = 0), binned: the tent tests' set-up.
template <int Dim>
struct RandomTents {
  tree::CellGraph<Dim> g;
  transfer::UniformPatches<Dim> patches;
  particles::Particles<Dim> p;
  particles::CellBins bins;

  RandomTents(std::uint64_t tree_seed, std::uint64_t particle_seed, std::uint64_t velocity_seed)
      : g(random_tree(tree_seed)), patches(g, g.cell_ids()), p(seeded_with_affine<Dim>(g, particle_seed)) {
    particles::bin_particles<Dim>(g, p.x, bins);
    std::mt19937_64 rng(velocity_seed);
    std::uniform_real_distribution<double> val(-1.0, 1.0);
    for (auto& v : p.v)
      for (int k = 0; k < Dim; ++k) v[k] = val(rng);
  }
  static tree::CellGraph<Dim> random_tree(std::uint64_t seed) {
    tree::CellGraphOptions<Dim> options;
    options.max_jump = 3;
    const Box<Dim> domain{Vec<Dim>::Constant(-1.0), Vec<Dim>::Constant(1.0)};
    return tree::random<Dim>(domain, seed, 2, Dim == 2 ? 6 : 4, 0.3, options);
  }
};

TYPED_TEST(PatchesTest, TentWeightsStayInTheParticlesRangeAndReproduceAffineFieldsWithTheirGradient) {
  constexpr int Dim = TypeParam::value;
  RandomTents<Dim> t(17, 3, 8);
  const auto& g = t.g;
  const auto& patches = t.patches;
  auto& p = t.p;
  const auto& bins = t.bins;
  const int apic = p.find_field("apic");
  // The set-up's random velocities with C = 0: every face within the range of the particles' values.
  transfer::FaceValues out;
  out.reset(g.face_capacity());
  const transfer::TransferReport r =
      transfer::tent_to_faces<Dim>(g, p, bins, p.field(apic), patches.face_mask(), out);
  EXPECT_EQ(r.targets, g.n_faces() - patches.n_faces());
  EXPECT_EQ(r.empty, 0);
  std::array<double, Dim> lo, hi;
  lo.fill(1e300), hi.fill(-1e300);
  for (const auto& v : p.v)
    for (int k = 0; k < Dim; ++k) lo[k] = std::min(lo[k], v[k]), hi[k] = std::max(hi[k], v[k]);
  g.for_each_face([&](tree::FaceId f) {
    if (patches.face(f)) {
      EXPECT_FALSE(out.known[f]);
      return;
    }
    const int k = g.face(f).axis;
    EXPECT_GE(out.value[f], lo[k]);
    EXPECT_LE(out.value[f], hi[k]);
  });
  // An affine field carried with its gradient is reproduced exactly at every face reached.
  const Affine<Dim> field = some_affine<Dim>();
  for (int i = 0; i < p.size(); ++i) {
    p.v[i] = field(p.x[i]);
    for (int k = 0; k < Dim; ++k)
      for (int j = 0; j < Dim; ++j) p.field(apic)[(i * Dim + k) * Dim + j] = field.grad(k, j);
  }
  out.reset(g.face_capacity());
  transfer::tent_to_faces<Dim>(g, p, bins, p.field(apic), patches.face_mask(), out);
  double worst = 0.0;
  g.for_each_face([&](tree::FaceId f) {
    if (out.known[f])
      worst = std::max(worst, std::abs(out.value[f] - field(g.face_centre(f))[g.face(f).axis]));
  });
  EXPECT_LT(worst, 1e-12);
}

TYPED_TEST(PatchesTest, TheTentShareBlendsOnlyTheFacesTheRbfSetAndLeavesTheRest) {
  constexpr int Dim = TypeParam::value;
  RandomTents<Dim> t(23, 5, 3);
  const auto& g = t.g;
  const auto& patches = t.patches;
  const auto& p = t.p;
  const auto& bins = t.bins;
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> val(-1.0, 1.0);
  // The faces as a transfer left them: arbitrary values, every third face unknown.
  transfer::FaceValues before;
  before.reset(g.face_capacity());
  g.for_each_face([&](tree::FaceId f) {
    before.value[f] = val(rng);
    before.known[f] = f % 3 != 0;
  });
  transfer::FaceValues tents;
  tents.reset(g.face_capacity());
  transfer::tent_to_faces<Dim>(g, p, bins, {}, patches.face_mask(), tents);

  transfer::FaceValues out = before;
  EXPECT_EQ(transfer::blend_tent_mean<Dim>(g, p, bins, patches.face_mask(), 0.0, out), 0);
  EXPECT_EQ(out.value, before.value);  // share 0: the same bits

  const double share = 0.3;
  const long blended = transfer::blend_tent_mean<Dim>(g, p, bins, patches.face_mask(), share, out);
  long expected = 0;
  g.for_each_face([&](tree::FaceId f) {
    if (patches.face(f) || !before.known[f] || !tents.known[f]) {
      EXPECT_EQ(out.value[f], before.value[f]) << "face " << f;
      return;
    }
    ++expected;
    EXPECT_NEAR(out.value[f], (1.0 - share) * before.value[f] + share * tents.value[f], 1e-15)
        << "face " << f;
  });
  EXPECT_GT(expected, 0);
  EXPECT_EQ(blended, expected);
  EXPECT_THROW(transfer::blend_tent_mean<Dim>(g, p, bins, patches.face_mask(), 1.5, out), Error);
  EXPECT_THROW(transfer::blend_tent_mean<Dim>(g, p, bins, patches.face_mask(), std::nan(""), out), Error);
}

}  // namespace
}  // namespace liquid
