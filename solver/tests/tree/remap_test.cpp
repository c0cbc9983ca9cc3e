// Field remap across changes: a linear cell field stays exact where parents average their
// children; a face field that depends only on the coordinate along each face's normal stays exact
// through splits (parts inherit, inner faces take the mean of both sides) and merges (unions
// average), over random adapt sequences in 2D and 3D.
#include <gtest/gtest.h>

#include <random>

#include "liquid/tree/builders.hpp"
#include "liquid/tree/remap.hpp"

namespace liquid {
namespace {

template <typename T>
class RemapTest : public ::testing::Test {};
using Dims = ::testing::Types<std::integral_constant<int, 2>, std::integral_constant<int, 3>>;
TYPED_TEST_SUITE(RemapTest, Dims);

template <int Dim>
double linear(const Vec<Dim>& x) {
  double v = 0.25;
  for (int d = 0; d < Dim; ++d) v += (d + 1.5) * x[d];
  return v;
}

TYPED_TEST(RemapTest, ChildrenInheritAndParentsAverage) {
  constexpr int Dim = TypeParam::value;
  auto g = tree::uniform<Dim>(Box<Dim>{}, 2);
  std::vector<double> q(g.cell_capacity());
  std::vector<Vec<Dim>> v(g.cell_capacity());
  g.for_each_cell([&](tree::CellId c) {
    q[c] = linear<Dim>(g.centre(c));
    v[c] = g.centre(c);
  });
  const auto group = *g.siblings(0);
  tree::AdaptReport report;
  const tree::CellId p = g.merge(group, &report);
  tree::remap::cell_field(g, report, q);
  tree::remap::cell_field(g, report, v);
  EXPECT_NEAR(q[p], linear<Dim>(g.centre(p)), 1e-14);
  EXPECT_NEAR((v[p] - g.centre(p)).norm(), 0.0, 1e-14);
  const auto children = g.split(p, &report);
  tree::remap::cell_field(g, report, q);
  for (tree::CellId c : children) EXPECT_EQ(q[c], q[p]);
  std::vector<double> too_small(1, 0.0);
  EXPECT_THROW(tree::remap::cell_field(g, report, too_small), Error);
}

TYPED_TEST(RemapTest, NormalCoordinateFaceFieldStaysExact) {
  constexpr int Dim = TypeParam::value;
  for (int jump : {1, 2, tree::unlimited_jump}) {
    tree::CellGraphOptions<Dim> options;
    options.max_jump = jump;
    options.max_level = Dim == 2 ? 7 : 5;
    auto g = tree::random<Dim>(Box<Dim>{}, 9, 1, 3, 0.4, options);
    const auto exact = [&](tree::FaceId f) { return 2.0 * g.face_centre(f)[g.face(f).axis] - 0.5; };
    std::vector<double> u(g.face_capacity());
    g.for_each_face([&](tree::FaceId f) { u[f] = exact(f); });
    std::mt19937_64 rng(jump);
    for (int step = 0; step < 30; ++step) {
      std::vector<tree::Mark> marks(g.cell_capacity(), tree::Mark::keep);
      g.for_each_cell([&](tree::CellId c) {
        const double r = std::uniform_real_distribution<double>(0, 1)(rng);
        marks[c] = r < 0.08 ? tree::Mark::split : (r < 0.7 ? tree::Mark::merge : tree::Mark::keep);
      });
      const tree::AdaptReport report = g.adapt(marks);
      tree::remap::face_field(g, report, u);
      g.for_each_face(
          [&](tree::FaceId f) { ASSERT_NEAR(u[f], exact(f), 1e-13) << "face " << f << " step " << step; });
    }
  }
}

}  // namespace
}  // namespace liquid
