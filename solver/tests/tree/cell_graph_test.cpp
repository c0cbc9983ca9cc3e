// CellGraph: split and merge in 2D and 3D, side faces, level-jump enforcement, the sibling test,
// the bulk build against incremental splits, point location and k-ring against brute force, and
// the topology number with the adjacency derived from it.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <tuple>

#include "liquid/core/error.hpp"
#include "liquid/tree/builders.hpp"
#include "liquid/tree/cell_adjacency.hpp"
#include "liquid/tree/cell_graph.hpp"

namespace liquid {
namespace {

template <int Dim>
Box<Dim> test_domain() {
  Box<Dim> b;
  b.lo = Vec<Dim>::Constant(-1.0);
  b.hi = Vec<Dim>::Constant(1.0);
  b.hi[0] = 3.0;  // anisotropic cells
  return b;
}

template <int Dim>
void expect_ok(const tree::CellGraph<Dim>& g) {
  const tree::InvariantReport r = g.check_invariants();
  ASSERT_TRUE(r.ok()) << r.text();
}

/// Faces as a set of (smaller key, larger key, axis, boundary) for comparing graphs.
template <int Dim>
std::set<std::tuple<std::uint64_t, std::uint64_t, int, int>> face_set(const tree::CellGraph<Dim>& g) {
  std::set<std::tuple<std::uint64_t, std::uint64_t, int, int>> out;
  g.for_each_face([&](tree::FaceId f) {
    const tree::GraphFace& face = g.face(f);
    const std::uint64_t a = face.cell[0] == tree::no_cell ? 0 : g.key(face.cell[0]);
    const std::uint64_t b = face.cell[1] == tree::no_cell ? 0 : g.key(face.cell[1]);
    out.emplace(a, b, face.axis, face.boundary);
  });
  return out;
}

template <int Dim>
std::set<std::uint64_t> leaf_set(const tree::CellGraph<Dim>& g) {
  std::set<std::uint64_t> out;
  g.for_each_cell([&](tree::CellId c) { out.insert(g.key(c)); });
  return out;
}

template <typename T>
class CellGraphTest : public ::testing::Test {};
using Dims = ::testing::Types<std::integral_constant<int, 2>, std::integral_constant<int, 3>>;
TYPED_TEST_SUITE(CellGraphTest, Dims);

TYPED_TEST(CellGraphTest, SplitAndMergeRoot) {
  constexpr int Dim = TypeParam::value;
  tree::CellGraph<Dim> g(test_domain<Dim>());
  EXPECT_EQ(g.n_cells(), 1);
  EXPECT_EQ(g.n_faces(), 2 * Dim);
  expect_ok(g);
  tree::AdaptReport report;
  const auto children = g.split(0, &report);
  expect_ok(g);
  EXPECT_EQ(g.n_cells(), 1 << Dim);
  // Interior faces Dim * 2^(Dim-1), boundary faces 2 * Dim * 2^(Dim-1).
  EXPECT_EQ(g.n_faces(), 3 * Dim * (1 << (Dim - 1)));
  EXPECT_EQ(report.removed_cells, std::vector<tree::CellId>{0});
  EXPECT_EQ(report.new_cells.size(), std::size_t(1 << Dim));
  EXPECT_EQ(report.removed_faces.size(), std::size_t(2 * Dim));
  for (int i = 0; i < (1 << Dim); ++i) {
    EXPECT_EQ(g.level(children[i]), 1);
    for (int d = 0; d < Dim; ++d) EXPECT_EQ(g.address(children[i])[d], (i >> d) & 1);
  }
  EXPECT_TRUE(g.are_siblings(children));
  EXPECT_TRUE(g.can_merge(children[1]));
  const tree::CellId root = g.merge(children, &report);
  expect_ok(g);
  EXPECT_EQ(g.n_cells(), 1);
  EXPECT_EQ(g.n_faces(), 2 * Dim);
  EXPECT_EQ(g.level(root), 0);
  EXPECT_EQ(report.new_cells, std::vector<tree::CellId>{root});
  EXPECT_EQ(report.cell_origins.source.size(), std::size_t(1 << Dim));
}

TYPED_TEST(CellGraphTest, SideFacesReportHangingNeighbours) {
  constexpr int Dim = TypeParam::value;
  tree::CellGraphOptions<Dim> options;
  options.max_jump = tree::unlimited_jump;
  tree::CellGraph<Dim> g(test_domain<Dim>(), options);
  const auto c1 = g.split(0);
  const auto c2 = g.split(c1[0]);  // the lower corner child, split again
  expect_ok(g);
  // c1[1] (upper along axis 0) sees 2^(Dim-1) finer neighbours on its lower side along axis 0.
  std::vector<tree::SideFace> side;
  g.side_faces(c1[1], 0, -1, side);
  ASSERT_EQ(side.size(), std::size_t(1 << (Dim - 1)));
  for (const tree::SideFace& s : side) {
    EXPECT_EQ(s.adjacency, tree::Adjacency::finer);
    EXPECT_EQ(s.neighbour_level, 2);
    EXPECT_TRUE(g.face(s.face).hanging(1));
    EXPECT_FALSE(g.face(s.face).hanging(0));
    EXPECT_NEAR(g.face_area(s.face) * (1 << (Dim - 1)), g.volume(c1[1]) / g.cell_size(c1[1])[0], 1e-12);
  }
  // c2[1] sees the coarser c1[1] across its upper side, and the boundary on none of its sides.
  g.side_faces(c2[1], 0, +1, side);
  ASSERT_EQ(side.size(), 1u);
  EXPECT_EQ(side[0].adjacency, tree::Adjacency::coarser);
  EXPECT_EQ(side[0].neighbour, c1[1]);
  g.side_faces(c2[0], 0, -1, side);
  ASSERT_EQ(side.size(), 1u);
  EXPECT_EQ(side[0].adjacency, tree::Adjacency::boundary);
  EXPECT_EQ(g.face(side[0].face).boundary, 0);
  g.side_faces(c2[0], 0, +1, side);
  ASSERT_EQ(side.size(), 1u);
  EXPECT_EQ(side[0].adjacency, tree::Adjacency::same);
  EXPECT_EQ(side[0].neighbour, c2[1]);
  const Vec<Dim> fc = g.face_centre(side[0].face);
  EXPECT_NEAR(fc[0], g.box(c2[0]).hi[0], 1e-15);
}

TYPED_TEST(CellGraphTest, SplittingEnforcesTheLevelJump) {
  constexpr int Dim = TypeParam::value;
  for (int jump : {1, 2, 3}) {
    tree::CellGraphOptions<Dim> options;
    options.max_jump = jump;
    tree::CellGraph<Dim> g(test_domain<Dim>(), options);
    g.split(0);
    // Refine 6 times at a point just below the root's mid-plane along axis 0: the level-1 cells
    // across that plane would end up 6 levels coarser without balancing.
    Vec<Dim> corner = test_domain<Dim>().centre();
    corner[0] -= 1e-9;
    long forced = 0;
    for (int k = 0; k < 6; ++k) {
      tree::AdaptReport r;
      g.split(g.locate(corner), &r);
      forced += r.n_balance_splits;
      expect_ok(g);
    }
    EXPECT_EQ(g.level(g.locate(corner)), 7);
    EXPECT_GT(forced, 0) << "jump " << jump;
    int worst = 0;
    g.for_each_face([&](tree::FaceId f) {
      const tree::GraphFace& face = g.face(f);
      if (!face.is_boundary()) worst = std::max(worst, std::abs(face.side_level[0] - face.side_level[1]));
    });
    EXPECT_EQ(worst, jump);
  }
}

TYPED_TEST(CellGraphTest, MergeRefusedWhereItBreaksTheJump) {
  constexpr int Dim = TypeParam::value;
  tree::CellGraphOptions<Dim> options;
  options.max_jump = 1;
  tree::CellGraph<Dim> g(test_domain<Dim>(), options);
  const auto c1 = g.split(0);
  const auto c2 = g.split(c1[0]);
  g.split(c2[(1 << Dim) - 1]);  // level 3 next to c1's other children: they must split
  expect_ok(g);
  // A group of leaf siblings at level 2 next to a level-3 cell cannot merge under jump 1.
  int n_refused = 0;
  for (tree::CellId c : g.cell_ids()) {
    if (g.level(c) != 2 || !g.siblings(c) || morton::child_index<Dim>(g.key(c)) != 0) continue;
    const auto group = *g.siblings(c);
    bool next_to_finer = false;
    for (tree::CellId s : group)
      for (tree::FaceId f : g.faces(s)) next_to_finer = next_to_finer || g.face(f).level() == 3;
    EXPECT_EQ(g.can_merge(c), !next_to_finer);
    if (next_to_finer) {
      ++n_refused;
      EXPECT_THROW(g.merge(group), Error);
    }
  }
  EXPECT_GT(n_refused, 0);
  expect_ok(g);
  EXPECT_FALSE(g.can_merge(c2[0]));  // c2's group is not all leaves
  // Not siblings: cells of different parents.
  std::array<tree::CellId, (1 << Dim)> mixed = c2;
  mixed[0] = c1[1];
  EXPECT_FALSE(g.are_siblings(mixed));
  EXPECT_THROW(g.merge(mixed), Error);
  // min_level is respected by adapt.
  tree::CellGraphOptions<Dim> floor_options;
  floor_options.min_level = 1;
  tree::CellGraph<Dim> h = tree::uniform<Dim>(test_domain<Dim>(), 1, floor_options);
  std::vector<tree::Mark> marks(h.cell_capacity(), tree::Mark::merge);
  const tree::AdaptReport r = h.adapt(marks);
  EXPECT_EQ(r.n_merged, 0);
  EXPECT_EQ(r.n_refused_merge, 1 << Dim);
  EXPECT_EQ(h.n_cells(), 1 << Dim);
}

TYPED_TEST(CellGraphTest, BulkBuildEqualsIncrementalSplits) {
  constexpr int Dim = TypeParam::value;
  const Box<Dim> domain = test_domain<Dim>();
  for (int jump : {1, 2, tree::unlimited_jump}) {
    tree::CellGraphOptions<Dim> options;
    options.max_jump = jump;
    const tree::CellGraph<Dim> bulk = tree::random<Dim>(domain, 7 + jump, 1, Dim == 2 ? 6 : 4, 0.3, options);
    expect_ok(bulk);
    // The random predicate's own tree (no balancing), split top-down; balancing forces the rest.
    const tree::CellGraph<Dim> raw =
        tree::random<Dim>(domain, 7 + jump, 1, Dim == 2 ? 6 : 4, 0.3,
                          tree::CellGraphOptions<Dim>{tree::unlimited_jump, 0, morton::max_level<Dim>});
    std::vector<std::uint64_t> interior;
    for (std::uint64_t k : leaf_set(raw))
      for (std::uint64_t a = k >> Dim; a >= 1; a >>= Dim) interior.push_back(a);
    std::sort(interior.begin(), interior.end());
    interior.erase(std::unique(interior.begin(), interior.end()), interior.end());
    tree::CellGraph<Dim> inc(domain, options);
    for (std::uint64_t k : interior) {  // ascending keys: parents before children
      const tree::CellId c = inc.find(morton::key_level<Dim>(k), morton::key_address<Dim>(k));
      if (c != tree::no_cell) inc.split(c);
    }
    expect_ok(inc);
    EXPECT_EQ(leaf_set(inc), leaf_set(bulk)) << "jump " << jump;
    EXPECT_EQ(face_set(inc), face_set(bulk)) << "jump " << jump;
  }
}

TYPED_TEST(CellGraphTest, PointLocationMatchesBruteForce) {
  constexpr int Dim = TypeParam::value;
  const Box<Dim> domain = test_domain<Dim>();
  const tree::CellGraph<Dim> g = tree::random<Dim>(domain, 3, 1, Dim == 2 ? 8 : 5, 0.4, {});
  const auto ids = g.cell_ids();
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec<Dim>> points;
  for (int i = 0; i < 3000; ++i) {
    Vec<Dim> x;
    for (int d = 0; d < Dim; ++d) x[d] = domain.lo[d] + u(rng) * (domain.hi[d] - domain.lo[d]);
    points.push_back(x);
  }
  // Cell centres and corners of random cells land exactly on boundaries between cells.
  for (int i = 0; i < 500; ++i) {
    const Box<Dim> b = g.box(ids[rng() % ids.size()]);
    points.push_back(b.centre());
    points.push_back(b.lo);
    points.push_back(b.hi);
  }
  std::vector<tree::CellId> found(points.size());
  g.locate(points, found);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec<Dim>& x = points[i];
    tree::CellId brute = tree::no_cell;
    int n_holding = 0;
    for (tree::CellId c : ids) {
      if (g.box(c).contains(x)) {
        ++n_holding;
        brute = c;
      }
    }
    ASSERT_GE(n_holding, 1);
    if (n_holding == 1)
      ASSERT_EQ(found[i], brute) << "point " << i;
    else
      ASSERT_TRUE(g.box(found[i]).contains(x)) << "point " << i << " on a boundary";
    EXPECT_EQ(g.locate(x, found[i]), found[i]);
  }
  // Outside points clamp onto the domain.
  Vec<Dim> far = domain.hi + Vec<Dim>::Constant(5.0);
  EXPECT_TRUE(g.box(g.locate(far)).contains(domain.hi));
  far = domain.lo - Vec<Dim>::Constant(5.0);
  EXPECT_TRUE(g.box(g.locate(far)).contains(domain.lo));
  Vec<Dim> bad = domain.centre();
  bad[0] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(g.locate(bad), Error);
}

/// Every alive cell's adjacency against its face list: per axis, the same faces in the same order,
/// each with the cell across it.
template <int Dim>
void expect_adjacency_of(const tree::CellGraph<Dim>& g, const tree::CellAdjacency<Dim>& adj) {
  long checked = 0;
  g.for_each_cell([&](tree::CellId c) {
    std::size_t all = 0;
    for (int axis = 0; axis < Dim; ++axis) {
      std::vector<std::pair<tree::FaceId, tree::CellId>> want, got;
      for (tree::FaceId f : g.faces(c)) {
        const tree::GraphFace& face = g.face(f);
        if (face.axis == axis) want.emplace_back(f, face.cell[0] == c ? face.cell[1] : face.cell[0]);
      }
      for (const auto& side : adj.of(c, axis)) got.emplace_back(side.face, side.other);
      ASSERT_EQ(got, want) << "cell " << c << ", axis " << axis;
      all += got.size();
    }
    ASSERT_EQ(adj.of(c).size(), all) << "cell " << c;
    ++checked;
  });
  EXPECT_EQ(checked, g.n_cells());
}

TYPED_TEST(CellGraphTest, AdjacencyFollowsTheTopology) {
  // The topology number moves with every split and merge and differs between graphs built apart;
  // an adjacency bound to a graph is remade when it moves, and matches the face lists each time.
  constexpr int Dim = TypeParam::value;
  tree::CellGraphOptions<Dim> options;
  options.max_jump = tree::unlimited_jump;
  tree::CellGraph<Dim> g = tree::random<Dim>(test_domain<Dim>(), 9, 1, Dim == 2 ? 6 : 4, 0.45, options);
  const tree::CellGraph<Dim> other =
      tree::random<Dim>(test_domain<Dim>(), 9, 1, Dim == 2 ? 6 : 4, 0.45, options);
  EXPECT_NE(g.topology(), other.topology());
  tree::CellAdjacency<Dim> adj;
  adj.bind(other);
  adj.bind(g);
  expect_adjacency_of(g, adj);
  std::mt19937_64 rng(3);
  for (int round = 0; round < 6; ++round) {
    const std::uint64_t before = g.topology();
    const auto ids = g.cell_ids();
    const tree::CellId c = ids[rng() % ids.size()];
    if (round % 2 == 0 && g.level(c) < g.options().max_level) {
      g.split(c);
    } else if (const auto sib = g.siblings(c); sib && g.can_merge(c)) {
      g.merge(*sib);
    } else {
      g.split(ids[0]);
    }
    ASSERT_NE(g.topology(), before) << "round " << round;
    adj.bind(g);
    expect_adjacency_of(g, adj);
  }
  const tree::CellGraph<Dim> copy = g;  // a copy has the same topology
  EXPECT_EQ(copy.topology(), g.topology());
}

TYPED_TEST(CellGraphTest, KRingMatchesBruteForceAdjacency) {
  constexpr int Dim = TypeParam::value;
  const Box<Dim> domain = test_domain<Dim>();
  for (int jump : {1, 3, tree::unlimited_jump}) {
    tree::CellGraphOptions<Dim> options;
    options.max_jump = jump;
    const tree::CellGraph<Dim> g = tree::random<Dim>(domain, 5, 1, Dim == 2 ? 7 : 4, 0.45, options);
    const auto ids = g.cell_ids();
    // Brute force: two leaves are adjacent when their boxes share a face of positive area.
    std::vector<std::vector<tree::CellId>> adj(g.cell_capacity());
    for (std::size_t i = 0; i < ids.size(); ++i) {
      const Box<Dim> a = g.box(ids[i]);
      for (std::size_t j = i + 1; j < ids.size(); ++j) {
        const Box<Dim> b = g.box(ids[j]);
        int touching = 0, overlapping = 0;
        for (int d = 0; d < Dim; ++d) {
          if (a.hi[d] == b.lo[d] || b.hi[d] == a.lo[d])
            ++touching;
          else if (a.lo[d] < b.hi[d] && b.lo[d] < a.hi[d])
            ++overlapping;
        }
        if (touching == 1 && overlapping == Dim - 1) {
          adj[ids[i]].push_back(ids[j]);
          adj[ids[j]].push_back(ids[i]);
        }
      }
    }
    std::vector<tree::CellId> ring;
    for (std::size_t t = 0; t < ids.size(); t += std::max<std::size_t>(1, ids.size() / 40)) {
      const tree::CellId c = ids[t];
      std::vector<int> dist(g.cell_capacity(), -1);
      std::vector<tree::CellId> queue{c};
      dist[c] = 0;
      for (std::size_t q = 0; q < queue.size(); ++q)
        for (tree::CellId o : adj[queue[q]])
          if (dist[o] < 0) {
            dist[o] = dist[queue[q]] + 1;
            queue.push_back(o);
          }
      for (int k : {0, 1, 2, 3}) {
        g.k_ring(c, k, ring);
        ASSERT_EQ(ring.front(), c);
        std::set<tree::CellId> expect, got(ring.begin(), ring.end());
        for (tree::CellId o : ids)
          if (dist[o] >= 0 && dist[o] <= k) expect.insert(o);
        ASSERT_EQ(got.size(), ring.size()) << "duplicates in the ring";
        ASSERT_EQ(got, expect) << "cell " << c << " k " << k << " jump " << jump;
      }
    }
  }
}

}  // namespace
}  // namespace liquid

namespace liquid {
namespace {

template <int Dim>
void expect_same_state(const tree::CellGraphState<Dim>& a, const tree::CellGraphState<Dim>& b) {
  EXPECT_EQ(a.level, b.level);
  EXPECT_EQ(a.address, b.address);
  EXPECT_EQ(a.faces, b.faces);
  EXPECT_EQ(a.face_alive, b.face_alive);
  EXPECT_EQ(a.free_cells, b.free_cells);
  EXPECT_EQ(a.free_faces, b.free_faces);
}

template <class D>
class CellGraphStateTest : public ::testing::Test {};
using StateDims = ::testing::Types<std::integral_constant<int, 2>, std::integral_constant<int, 3>>;
TYPED_TEST_SUITE(CellGraphStateTest, StateDims);

// A graph restored from its state has the same ids, face lists, free lists and tree index: the
// same changes made to both afterwards leave them identical, ids included.
TYPED_TEST(CellGraphStateTest, RestoredGraphEvolvesLikeTheOriginal) {
  constexpr int Dim = TypeParam::value;
  const Box<Dim> domain = test_domain<Dim>();
  tree::CellGraph<Dim> g =
      tree::narrow_band<Dim>(domain, levelset::sphere<Dim>(Vec<Dim>::Zero(), 0.6), 1, Dim == 2 ? 5 : 3, 1.5);
  std::mt19937 rng(7);
  const auto random_marks = [&](const tree::CellGraph<Dim>& graph) {
    tree::MarkList m;
    std::uniform_int_distribution<int> pick(0, 9);
    graph.for_each_cell([&](tree::CellId c) {
      const int r = pick(rng);
      if (r == 0) m.split.push_back(c);
      if (r >= 6) m.merge.push_back(c);
    });
    return m;
  };
  for (int round = 0; round < 3; ++round) {  // ids recycled, free lists non-empty
    tree::MarkList m = random_marks(g);
    g.adapt(m);
  }
  ASSERT_FALSE(g.state().free_cells.empty());
  tree::CellGraph<Dim> h = tree::CellGraph<Dim>::from_state(g.state());
  expect_ok(h);
  expect_same_state(g.state(), h.state());
  EXPECT_EQ(g.n_cells(), h.n_cells());
  EXPECT_EQ(g.deepest_level(), h.deepest_level());
  for (int round = 0; round < 3; ++round) {
    tree::MarkList m = random_marks(g), m2 = m;
    const tree::AdaptReport ra = g.adapt(m), rb = h.adapt(m2);
    EXPECT_EQ(ra.new_cells, rb.new_cells);
    EXPECT_EQ(ra.new_faces, rb.new_faces);
    expect_same_state(g.state(), h.state());
  }
  const Vec<Dim> x = Vec<Dim>::Constant(0.3);
  EXPECT_EQ(g.locate(x), h.locate(x));
}

TYPED_TEST(CellGraphStateTest, BrokenStateIsRefusedWithTheProblemNamed) {
  constexpr int Dim = TypeParam::value;
  const tree::CellGraph<Dim> g = tree::uniform<Dim>(test_domain<Dim>(), 2);
  tree::CellGraphState<Dim> s = g.state();
  s.address.pop_back();
  EXPECT_THROW(
      {
        try {
          tree::CellGraph<Dim>::from_state(s);
        } catch (const Error& e) {
          EXPECT_NE(std::string(e.what()).find("addresses"), std::string::npos) << e.what();
          throw;
        }
      },
      Error);
  s = g.state();
  s.faces[tree::CellGraphState<Dim>::face_record * 5] = 9999;  // a face naming a cell that does not exist
  EXPECT_THROW(tree::CellGraph<Dim>::from_state(s), Error);
  s = g.state();
  s.level[3] = 1;  // a cell at the wrong level: the faces no longer tile
  EXPECT_THROW(tree::CellGraph<Dim>::from_state(s), Error);
}

}  // namespace
}  // namespace liquid
