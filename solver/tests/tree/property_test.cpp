// Property tests: thousands of random splits, merges and adapts under each level-jump limit, in 2D
// and 3D, with every invariant checked after every step, plus the change reports: new and removed
// ids disjoint, origins that are convex combinations, a cell field's integral conserved by the
// remap and a per-axis constant face field kept exactly.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <random>
#include <set>

#include "liquid/core/error.hpp"
#include "liquid/tree/builders.hpp"
#include "liquid/tree/cell_graph.hpp"
#include "liquid/tree/remap.hpp"

namespace liquid {
namespace {

template <int Dim>
class Property {
 public:
  Property(int jump, std::uint64_t seed) : rng_(seed), graph_(make(jump, seed)) {
    cell_.resize(graph_.cell_capacity());
    for (tree::CellId c = 0; c < graph_.cell_capacity(); ++c)
      cell_[c] = std::uniform_real_distribution<double>(-1, 1)(rng_);
    face_.resize(graph_.face_capacity());
    graph_.for_each_face([&](tree::FaceId f) { face_[f] = 1.0 + graph_.face(f).axis; });
    integral_ = integral();
  }

  static constexpr int max_level = Dim == 2 ? 7 : 5;
  static constexpr int max_cells = Dim == 2 ? 1500 : 1200;

  void step() {
    const auto ids = graph_.cell_ids();
    const double u = std::uniform_real_distribution<double>(0, 1)(rng_);
    const bool crowded = graph_.n_cells() > max_cells;
    tree::AdaptReport report;
    if (u < 0.1) {
      // Dense marks, or the same kind of marks as sparse lists in random order with repeats.
      std::vector<tree::Mark> marks(graph_.cell_capacity(), tree::Mark::keep);
      tree::MarkList list;
      for (tree::CellId x : ids) {
        const double v = std::uniform_real_distribution<double>(0, 1)(rng_);
        marks[x] = v < (crowded ? 0.01 : 0.05) ? tree::Mark::split
                                               : (v < 0.6 ? tree::Mark::merge : tree::Mark::keep);
        if (marks[x] != tree::Mark::keep) {
          auto& l = marks[x] == tree::Mark::split ? list.split : list.merge;
          l.push_back(x);
          if (v < 0.02 || (v > 0.3 && v < 0.32)) l.push_back(x);
        }
      }
      if (n_adapts_ % 2 == 0) {
        report = graph_.adapt(marks);
      } else {
        std::shuffle(list.split.begin(), list.split.end(), rng_);
        std::shuffle(list.merge.begin(), list.merge.end(), rng_);
        report = graph_.adapt(list);
      }
      ++n_adapts_;
    } else if (u < 0.6 && !crowded) {
      // A few draws for a cell that can still split: uniform picks favour the finest cells.
      tree::CellId c = ids[std::uniform_int_distribution<std::size_t>(0, ids.size() - 1)(rng_)];
      for (int k = 0; k < 8 && graph_.level(c) >= max_level; ++k)
        c = ids[std::uniform_int_distribution<std::size_t>(0, ids.size() - 1)(rng_)];
      if (graph_.level(c) >= max_level) return;
      const int before = graph_.n_cells();
      const auto children = graph_.split(c, &report);
      for (tree::CellId k : children) ASSERT_TRUE(graph_.alive(k));
      ASSERT_GE(graph_.n_cells(), before + (1 << Dim) - 1);
      n_splits_ += report.n_split;  // balancing splits included
    } else {
      const tree::CellId c = ids[std::uniform_int_distribution<std::size_t>(0, ids.size() - 1)(rng_)];
      const auto group = graph_.siblings(c);
      if (!group) return;
      if (!graph_.can_merge(c)) {
        const int before = graph_.n_cells();
        EXPECT_THROW(graph_.merge(*group), Error);
        ASSERT_EQ(graph_.n_cells(), before);
        ++n_refused_;
        return;
      }
      const tree::CellId p = graph_.merge(*group, &report);
      ASSERT_TRUE(graph_.alive(p));
      ++n_merges_;
    }
    check(report);
  }

  void check(const tree::AdaptReport& report) {
    const tree::InvariantReport inv = graph_.check_invariants();
    ASSERT_TRUE(inv.ok()) << inv.text();
    std::set<tree::CellId> fresh(report.new_cells.begin(), report.new_cells.end());
    for (tree::CellId c : report.new_cells) ASSERT_TRUE(graph_.alive(c));
    for (tree::CellId c : report.removed_cells) {
      ASSERT_FALSE(graph_.alive(c));
      ASSERT_EQ(fresh.count(c), 0u);
    }
    std::set<tree::FaceId> fresh_faces(report.new_faces.begin(), report.new_faces.end());
    for (tree::FaceId f : report.new_faces) ASSERT_TRUE(graph_.face_alive(f));
    for (tree::FaceId f : report.removed_faces) {
      ASSERT_FALSE(graph_.face_alive(f));
      ASSERT_EQ(fresh_faces.count(f), 0u);
    }
    for (const tree::Origins* o : {&report.cell_origins, &report.face_origins}) {
      for (std::size_t i = 0; i + 1 < o->begin.size(); ++i) {
        double sum = 0.0;
        for (int k = o->begin[i]; k < o->begin[i + 1]; ++k) sum += o->weight[k];
        ASSERT_NEAR(sum, 1.0, 1e-12);
      }
    }
    tree::remap::cell_field(graph_, report, cell_);
    tree::remap::face_field(graph_, report, face_);
    ASSERT_NEAR(integral(), integral_, 1e-12 * (1.0 + std::abs(integral_)));
    graph_.for_each_face(
        [&](tree::FaceId f) { ASSERT_EQ(face_[f], 1.0 + graph_.face(f).axis) << "face " << f; });
    graph_.for_each_face([&](tree::FaceId f) {
      const tree::GraphFace& g = graph_.face(f);
      if (!g.is_boundary()) worst_jump_ = std::max(worst_jump_, std::abs(g.side_level[0] - g.side_level[1]));
    });
  }

  double integral() const {
    double sum = 0.0;
    graph_.for_each_cell([&](tree::CellId c) { sum += cell_[c] * graph_.volume(c); });
    return sum;
  }

  const tree::CellGraph<Dim>& graph() const { return graph_; }
  int worst_jump() const { return worst_jump_; }
  long n_splits_ = 0, n_merges_ = 0, n_adapts_ = 0, n_refused_ = 0;

 private:
  static tree::CellGraph<Dim> make(int jump, std::uint64_t seed) {
    tree::CellGraphOptions<Dim> options;
    options.max_jump = jump;
    options.max_level = max_level;
    Box<Dim> domain;
    domain.hi[Dim - 1] = 0.5;
    return tree::random<Dim>(domain, seed, 1, 3, 0.4, options);
  }

  std::mt19937_64 rng_;
  tree::CellGraph<Dim> graph_;
  std::vector<double> cell_, face_;
  double integral_ = 0.0;
  int worst_jump_ = 0;
};

template <int Dim>
void run(int jump, int n_ops) {
  long total_splits = 0, total_merges = 0, total_adapts = 0, total_refused = 0;
  int worst = 0;
  const int n_seeds = 4;
  for (std::uint64_t seed = 1; seed <= n_seeds; ++seed) {
    Property<Dim> p(jump, seed * 1000 + jump);
    p.check(tree::AdaptReport{});
    for (int i = 0; i < n_ops / n_seeds; ++i) {
      p.step();
      if (::testing::Test::HasFatalFailure()) {
        ADD_FAILURE() << "Dim " << Dim << " jump " << jump << " seed " << seed << " step " << i;
        return;
      }
    }
    total_splits += p.n_splits_;
    total_merges += p.n_merges_;
    total_adapts += p.n_adapts_;
    total_refused += p.n_refused_;
    worst = std::max(worst, p.worst_jump());
  }
  std::printf(
      "Dim %d jump %d: %ld cells split (balancing included), %ld merges, %ld refused merges, %ld adapts, "
      "worst jump %d\n",
      Dim, jump, total_splits, total_merges, total_refused, total_adapts, worst);
  EXPECT_GT(total_splits, n_ops / 20);
  EXPECT_GT(total_merges, n_ops / 20);
  EXPECT_LE(worst, jump);
  if (jump <= 2) {
    EXPECT_EQ(worst, jump) << "the random sequence never reached the limit";
  }
  if (jump > 4) {
    EXPECT_GE(worst, 3) << "no strongly non-graded configuration occurred";
  }
}

// Random operations per jump limit (each followed by the full invariant check), over four seeds.
// Under AddressSanitizer (a debug build, about 20 times slower) a quarter of them: the same code
// paths, checked for memory errors, in the time CI has.
#if defined(__SANITIZE_ADDRESS__)
constexpr int n_ops_scale = 4;
#else
constexpr int n_ops_scale = 1;
#endif
constexpr int n_ops_2d = 8000 / n_ops_scale;
constexpr int n_ops_3d = 3000 / n_ops_scale;

TEST(CellGraphProperty, Graded2D) {
  run<2>(1, n_ops_2d);
}
TEST(CellGraphProperty, Jump2In2D) {
  run<2>(2, n_ops_2d);
}
TEST(CellGraphProperty, Jump3In2D) {
  run<2>(3, n_ops_2d);
}
TEST(CellGraphProperty, Jump4In2D) {
  run<2>(4, n_ops_2d);
}
TEST(CellGraphProperty, Unlimited2D) {
  run<2>(tree::unlimited_jump, n_ops_2d);
}
TEST(CellGraphProperty, Graded3D) {
  run<3>(1, n_ops_3d);
}
TEST(CellGraphProperty, Jump2In3D) {
  run<3>(2, n_ops_3d);
}
TEST(CellGraphProperty, Jump3In3D) {
  run<3>(3, n_ops_3d);
}
TEST(CellGraphProperty, Jump4In3D) {
  run<3>(4, n_ops_3d);
}
TEST(CellGraphProperty, Unlimited3D) {
  run<3>(tree::unlimited_jump, n_ops_3d);
}

}  // namespace
}  // namespace liquid
