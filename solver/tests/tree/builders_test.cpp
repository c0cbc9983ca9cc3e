// Tree builders: uniform counts, bands around a level set at the right levels, one-level shifts
// for convergence rows, seeded random trees under each jump limit, and narrow-band re-adaptation
// by mark + adapt reaching the tree a fresh build gives, and the band tracker marking exactly what
// a visit of every cell marks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <set>

#include "liquid/core/error.hpp"
#include "liquid/tree/band_tracker.hpp"
#include "liquid/tree/builders.hpp"

namespace liquid {
namespace {

template <int Dim>
levelset::Function<Dim> sphere(const Vec<Dim>& centre, double radius) {
  return [centre, radius](const Vec<Dim>& x) { return (x - centre).norm() - radius; };
}

/// True when phi changes sign over the corners of c's box (so the zero set crosses the cell).
template <int Dim>
bool crosses(const tree::CellGraph<Dim>& g, tree::CellId c, const levelset::Function<Dim>& phi) {
  const Box<Dim> b = g.box(c);
  bool neg = false, pos = false;
  for (int k = 0; k < (1 << Dim); ++k) {
    Vec<Dim> x;
    for (int d = 0; d < Dim; ++d) x[d] = (k >> d) & 1 ? b.hi[d] : b.lo[d];
    (phi(x) < 0 ? neg : pos) = true;
  }
  return neg && pos;
}

template <int Dim>
std::set<std::uint64_t> leaf_set(const tree::CellGraph<Dim>& g) {
  std::set<std::uint64_t> out;
  g.for_each_cell([&](tree::CellId c) { out.insert(g.key(c)); });
  return out;
}

template <typename T>
class BuildersTest : public ::testing::Test {};
using Dims = ::testing::Types<std::integral_constant<int, 2>, std::integral_constant<int, 3>>;
TYPED_TEST_SUITE(BuildersTest, Dims);

TYPED_TEST(BuildersTest, UniformCounts) {
  constexpr int Dim = TypeParam::value;
  const int level = Dim == 2 ? 4 : 3;
  const auto g = tree::uniform<Dim>(Box<Dim>{}, level);
  const long n = 1L << level;
  long side = 1;
  for (int d = 0; d < Dim - 1; ++d) side *= n;
  EXPECT_EQ(g.n_cells(), side * n);
  EXPECT_EQ(g.n_faces(), Dim * side * (n - 1) + 2 * Dim * side);
  EXPECT_EQ(g.deepest_level(), level);
  EXPECT_TRUE(g.check_invariants().ok());
  // Face geometry: boundary faces cover the domain's surface; interior faces of one axis cover
  // n - 1 cross-sections.
  std::vector<Vec<Dim>> centres;
  std::vector<double> areas;
  g.face_geometry(centres, areas);
  double boundary = 0.0, inner0 = 0.0;
  g.for_each_face([&](tree::FaceId f) {
    const tree::GraphFace& face = g.face(f);
    if (face.is_boundary()) {
      boundary += areas[f];
      EXPECT_TRUE(centres[f][face.axis] == 0.0 || centres[f][face.axis] == 1.0);
    } else if (face.axis == 0) {
      inner0 += areas[f];
    }
  });
  EXPECT_NEAR(boundary, 2.0 * Dim, 1e-12);
  EXPECT_NEAR(inner0, static_cast<double>(n - 1), 1e-12);
}

TYPED_TEST(BuildersTest, BandedRefinesAroundTheZeroSet) {
  constexpr int Dim = TypeParam::value;
  const auto phi = sphere<Dim>(Vec<Dim>::Constant(0.45), 0.3);
  long previous_fine = 0;
  for (int row = 0; row < 2; ++row) {
    const int level = (Dim == 2 ? 3 : 2) + row;
    const auto g = tree::banded<Dim>(Box<Dim>{}, phi, level, 2.0);
    const tree::InvariantReport r = g.check_invariants();
    ASSERT_TRUE(r.ok()) << r.text();
    g.for_each_cell([&](tree::CellId c) {
      EXPECT_GE(g.level(c), level);
      EXPECT_LE(g.level(c), level + 2);
      if (crosses(g, c, phi)) {
        EXPECT_EQ(g.level(c), level + 2);
      }
    });
    const long fine = g.n_cells_at_level(level + 2);
    EXPECT_GT(fine, 0);
    EXPECT_GT(g.n_cells_at_level(level + 1), 0);
    if (previous_fine > 0) {
      // One level deeper: the band's cell count grows like 2^(Dim-1).
      const double ratio = static_cast<double>(fine) / previous_fine;
      EXPECT_GT(ratio, 0.6 * (1 << (Dim - 1)));
      EXPECT_LT(ratio, 1.6 * (1 << (Dim - 1)));
    }
    previous_fine = fine;
  }
}

TYPED_TEST(BuildersTest, NarrowBandUnderEachJump) {
  constexpr int Dim = TypeParam::value;
  const auto phi = sphere<Dim>(Vec<Dim>::Constant(0.5), 0.31);
  const int fine = Dim == 2 ? 7 : 5;
  for (int jump : {1, 2, tree::unlimited_jump}) {
    tree::CellGraphOptions<Dim> options;
    options.max_jump = jump;
    const auto g = tree::narrow_band<Dim>(Box<Dim>{}, phi, 1, fine, 2.0, options);
    const tree::InvariantReport r = g.check_invariants();
    ASSERT_TRUE(r.ok()) << r.text();
    int coarsest = fine;
    g.for_each_cell([&](tree::CellId c) {
      coarsest = std::min(coarsest, g.level(c));
      if (crosses(g, c, phi)) {
        EXPECT_EQ(g.level(c), fine);
      }
    });
    // The sphere crosses every level-1 cell; away from it the tree is as coarse as the jump allows.
    if (jump == tree::unlimited_jump) {
      EXPECT_EQ(coarsest, 2);
    } else {
      EXPECT_LE(coarsest, fine - 2);
    }
  }
}

// refined(base, k) splits every leaf of base k times: 2^(Dim k) children per leaf, each inside its
// parent leaf and k levels finer, the same largest jump, and every invariant.
TYPED_TEST(BuildersTest, RefinedSplitsEveryLeafUniformly) {
  constexpr int Dim = TypeParam::value;
  tree::CellGraphOptions<Dim> options;
  options.max_jump = 2;
  const auto base = tree::narrow_band<Dim>(Box<Dim>{}, sphere<Dim>(Vec<Dim>::Constant(0.5), 0.3), 2,
                                           Dim == 2 ? 5 : 4, 1.5, options);
  for (int k : {0, 1, 2}) {
    const auto fine = tree::refined<Dim>(base, k, options);
    ASSERT_TRUE(fine.check_invariants().ok()) << "k = " << k;
    EXPECT_EQ(fine.n_cells(), base.n_cells() << (Dim * k)) << "k = " << k;
    int jump_base = 0, jump_fine = 0;
    base.for_each_face([&](tree::FaceId f) {
      const auto& g = base.face(f);
      if (!g.is_boundary()) jump_base = std::max(jump_base, std::abs(g.side_level[0] - g.side_level[1]));
    });
    fine.for_each_face([&](tree::FaceId f) {
      const auto& g = fine.face(f);
      if (!g.is_boundary()) jump_fine = std::max(jump_fine, std::abs(g.side_level[0] - g.side_level[1]));
    });
    EXPECT_EQ(jump_fine, jump_base);
    fine.for_each_cell([&](tree::CellId c) {
      const tree::CellId parent = base.locate(fine.centre(c));
      ASSERT_EQ(fine.level(c), base.level(parent) + k) << "cell " << c;
    });
  }
  EXPECT_THROW(tree::refined<Dim>(base, -1), Error);
}

TYPED_TEST(BuildersTest, RandomTreesAreSeededAndRespectTheJump) {
  constexpr int Dim = TypeParam::value;
  const int deep = Dim == 2 ? 9 : 6;
  for (int jump : {1, 2, 3, 4, tree::unlimited_jump}) {
    tree::CellGraphOptions<Dim> options;
    options.max_jump = jump;
    const auto a = tree::random<Dim>(Box<Dim>{}, 42, 1, deep, 0.35, options);
    const auto b = tree::random<Dim>(Box<Dim>{}, 42, 1, deep, 0.35, options);
    const auto c = tree::random<Dim>(Box<Dim>{}, 43, 1, deep, 0.35, options);
    EXPECT_EQ(leaf_set(a), leaf_set(b));
    EXPECT_NE(leaf_set(a), leaf_set(c));
    const tree::InvariantReport r = a.check_invariants();
    ASSERT_TRUE(r.ok()) << r.text();
    int worst = 0;
    a.for_each_face([&](tree::FaceId f) {
      const tree::GraphFace& face = a.face(f);
      if (!face.is_boundary()) worst = std::max(worst, std::abs(face.side_level[0] - face.side_level[1]));
    });
    EXPECT_LE(worst, jump);
    EXPECT_GE(worst, std::min(jump, 2)) << "jump limit " << jump << ": no non-graded configuration";
  }
}

TYPED_TEST(BuildersTest, NarrowBandReadaptationReachesAFreshBuild) {
  constexpr int Dim = TypeParam::value;
  const int fine = Dim == 2 ? 7 : 5;
  const double h = std::ldexp(1.0, -fine);
  for (int jump : {2, tree::unlimited_jump}) {
    tree::CellGraphOptions<Dim> options;
    options.max_jump = jump;
    Vec<Dim> centre = Vec<Dim>::Constant(0.5);
    auto g = tree::narrow_band<Dim>(Box<Dim>{}, sphere<Dim>(centre, 0.3), 1, fine, 2.0, options);
    centre[0] += h;  // the interface moves by one fine cell
    const auto phi = sphere<Dim>(centre, 0.3);
    std::vector<tree::Mark> marks;
    int rounds = 0;
    for (; rounds < 10; ++rounds) {
      tree::mark_narrow_band<Dim>(g, phi, 1, fine, 2.0, marks);
      const tree::AdaptReport report = g.adapt(marks);
      const tree::InvariantReport r = g.check_invariants();
      ASSERT_TRUE(r.ok()) << r.text();
      if (report.empty()) break;
    }
    EXPECT_LT(rounds, 10);
    g.for_each_cell([&](tree::CellId c) {
      if (crosses(g, c, phi)) {
        EXPECT_EQ(g.level(c), fine);
      }
    });
    const auto fresh = tree::narrow_band<Dim>(Box<Dim>{}, phi, 1, fine, 2.0, options);
    if (jump == tree::unlimited_jump) {
      EXPECT_EQ(leaf_set(g), leaf_set(fresh));
    } else {
      // Balancing may keep a few extra cells that a fresh build never split.
      EXPECT_NEAR(static_cast<double>(g.n_cells()), fresh.n_cells(), 0.05 * fresh.n_cells());
    }
  }
}

/// The dense marks as sorted sparse lists.
tree::MarkList as_list(const std::vector<tree::Mark>& marks, int capacity) {
  tree::MarkList out;
  for (tree::CellId c = 0; c < capacity; ++c) {
    if (marks[c] == tree::Mark::split) out.split.push_back(c);
    if (marks[c] == tree::Mark::merge) out.merge.push_back(c);
  }
  return out;
}

TYPED_TEST(BuildersTest, BandTrackerMarksWhatAFullVisitMarks) {
  constexpr int Dim = TypeParam::value;
  const int fine = Dim == 2 ? 8 : 6;
  const double h = std::ldexp(1.0, -fine);
  // Coarse levels far below the band (most of the tree refined) and close to it (most cells
  // coarse, where the tracker's coarse frontier matters); bands narrow and wide.
  for (int coarse : {1, fine - 3}) {
    for (double band : {1.0, 3.0}) {
      for (int jump : {1, 2, tree::unlimited_jump}) {
        SCOPED_TRACE(::testing::Message() << "coarse " << coarse << " band " << band << " jump " << jump);
        tree::CellGraphOptions<Dim> options;
        options.max_jump = jump;
        Vec<Dim> centre = Vec<Dim>::Constant(0.45);
        const double radius = 0.23;
        auto dense =
            tree::narrow_band<Dim>(Box<Dim>{}, sphere<Dim>(centre, radius), coarse, fine, band, options);
        auto sparse = dense;
        tree::NarrowBandTracker<Dim> tracker(sparse, coarse, fine, band);
        std::vector<tree::Mark> marks;
        tree::MarkList list;
        // The first call visits every cell. A fresh tree can already carry marks: merges of the
        // cells the level-jump balancing split, which adapt() refuses.
        tree::mark_narrow_band<Dim>(dense, sphere<Dim>(centre, radius), coarse, fine, band, marks);
        tracker.mark(sparse, sphere<Dim>(centre, radius), list);
        EXPECT_EQ(list.split.size(), as_list(marks, dense.cell_capacity()).split.size());
        EXPECT_EQ(list.merge.size(), as_list(marks, dense.cell_capacity()).merge.size());
        // The sphere moves one fine cell per step along a diagonal-ish path.
        for (int step = 0; step < 12; ++step) {
          centre[step % Dim] += (step % 5 == 4 ? -1.0 : 1.0) * h;
          const auto phi = sphere<Dim>(centre, radius);
          tree::mark_narrow_band<Dim>(dense, phi, coarse, fine, band, marks);
          tracker.mark(sparse, phi, list);
          if (coarse > 1) {  // with a level-1 background nearly every cell is refined
            EXPECT_LT(static_cast<long>(tracker.candidates().size()), sparse.n_cells());
          }
          tree::MarkList got = list;
          std::sort(got.split.begin(), got.split.end());
          std::sort(got.merge.begin(), got.merge.end());
          const tree::MarkList want = as_list(marks, dense.cell_capacity());
          ASSERT_EQ(got.split, want.split) << "step " << step;
          ASSERT_EQ(got.merge, want.merge) << "step " << step;
          const tree::AdaptReport a = dense.adapt(marks);
          const tree::AdaptReport b = sparse.adapt(list);
          tracker.update(sparse, b);
          EXPECT_EQ(a.new_cells, b.new_cells);
          EXPECT_EQ(a.removed_cells, b.removed_cells);
          EXPECT_EQ(a.n_refused_merge, b.n_refused_merge);
          ASSERT_EQ(leaf_set(dense), leaf_set(sparse)) << "step " << step;
          const tree::InvariantReport r = sparse.check_invariants();
          ASSERT_TRUE(r.ok()) << r.text();
        }
      }
    }
  }
}

TYPED_TEST(BuildersTest, BandTrackerConvergesToAFreshBuild) {
  constexpr int Dim = TypeParam::value;
  const int fine = Dim == 2 ? 8 : 6, coarse = 2;
  const double h = std::ldexp(1.0, -fine);
  tree::CellGraphOptions<Dim> options;
  options.max_jump = tree::unlimited_jump;
  // Start from a uniform tree at the coarse level, one level coarser (the first round makes every
  // cell at the coarse level, which later rounds must still visit), or the root alone.
  for (int start : {coarse, coarse - 1, 0}) {
    SCOPED_TRACE(::testing::Message() << "start level " << start);
    Vec<Dim> centre = Vec<Dim>::Constant(0.5);
    auto g = tree::uniform<Dim>(Box<Dim>{}, start, options);
    tree::NarrowBandTracker<Dim> tracker(g, coarse, fine, 2.0);
    tree::MarkList marks;
    for (int step = 0; step < 40; ++step) {
      if (step % 4 == 3 && step < 30) centre[0] += h;  // every fourth round, by one fine cell
      const auto phi = sphere<Dim>(centre, 0.3);
      tracker.mark(g, phi, marks);
      tracker.update(g, g.adapt(marks));
    }
    ASSERT_TRUE(g.check_invariants().ok());
    const auto fresh =
        tree::narrow_band<Dim>(Box<Dim>{}, sphere<Dim>(centre, 0.3), coarse, fine, 2.0, options);
    // Each round refines one level, so (fine - start) rounds after the last move the tree is fresh.
    EXPECT_EQ(leaf_set(g), leaf_set(fresh));
    EXPECT_GT(tracker.n_refined(), 0);
  }
}

TYPED_TEST(BuildersTest, BandTrackerOnAnisotropicCells) {
  constexpr int Dim = TypeParam::value;
  const int fine = Dim == 2 ? 8 : 6, coarse = fine - 3;
  // A box three times longer than high: cells are flat, and the fine size follows the long side.
  Box<Dim> domain;
  domain.hi[0] = 3.0;
  const double h = 3.0 * std::ldexp(1.0, -fine);
  for (double band : {1.0, 4.0}) {
    SCOPED_TRACE(::testing::Message() << "band " << band);
    Vec<Dim> centre = Vec<Dim>::Constant(0.5);
    centre[0] = 1.5;
    auto dense = tree::narrow_band<Dim>(domain, sphere<Dim>(centre, 0.3), coarse, fine, band);
    auto sparse = dense;
    tree::NarrowBandTracker<Dim> tracker(sparse, coarse, fine, band);
    std::vector<tree::Mark> marks;
    tree::MarkList list;
    tracker.mark(sparse, sphere<Dim>(centre, 0.3), list);
    for (int step = 0; step < 8; ++step) {
      centre[Dim - 1] += h;  // across the short side
      const auto phi = sphere<Dim>(centre, 0.3);
      tree::mark_narrow_band<Dim>(dense, phi, coarse, fine, band, marks);
      tracker.mark(sparse, phi, list);
      const tree::MarkList want = as_list(marks, dense.cell_capacity());
      std::sort(list.split.begin(), list.split.end());
      std::sort(list.merge.begin(), list.merge.end());
      ASSERT_EQ(list.split, want.split) << "step " << step;
      ASSERT_EQ(list.merge, want.merge) << "step " << step;
      dense.adapt(marks);
      tracker.update(sparse, sparse.adapt(list));
      ASSERT_EQ(leaf_set(dense), leaf_set(sparse)) << "step " << step;
    }
  }
}

TEST(MarkList, ADeadIdReusedDuringTheChangeIsNotSplit) {
  // Id 3 dies (split) and goes to the free list; splitting 0 hands it to a new child; the stale
  // mark on 3 must not split that child, as the dense form of the same marks would not.
  auto g = tree::uniform<2>(Box<2>{}, 2);
  g.split(3);
  tree::MarkList marks;
  marks.split = {0, 3};
  const tree::AdaptReport r = g.adapt(marks);
  EXPECT_EQ(r.n_split, 1);
  EXPECT_EQ(g.deepest_level(), 3);
  EXPECT_TRUE(g.check_invariants().ok());
}

TEST(MarkList, AdaptIgnoresRepeatsAndDeadIdsAndNeedsWholeGroups) {
  auto g = tree::uniform<2>(Box<2>{}, 2);
  tree::MarkList marks;
  marks.split = {3, 3, 3};
  tree::AdaptReport r = g.adapt(marks);
  EXPECT_EQ(r.n_split, 1);
  EXPECT_EQ(g.n_cells(), 16 + 3);
  EXPECT_FALSE(g.alive(3));
  // Three of four siblings listed: no merge, three refusals; a dead id is skipped.
  const auto group = *g.siblings(r.new_cells[0]);
  marks.clear();
  marks.merge = {group[0], group[1], group[2], 3};
  r = g.adapt(marks);
  EXPECT_EQ(r.n_merged, 0);
  EXPECT_EQ(r.n_refused_merge, 3);
  marks.merge = {group[3], group[2], group[1], group[0]};
  r = g.adapt(marks);
  EXPECT_EQ(r.n_merged, 1);
  EXPECT_EQ(g.n_cells(), 16);
  EXPECT_TRUE(g.check_invariants().ok());
}

}  // namespace
}  // namespace liquid
