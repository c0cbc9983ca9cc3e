// Unit tests of solver/liquid/surface: the extracted zero sets of a circle and a sphere are closed,
// consistently oriented outwards, on the surface and of the right length / area.

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include <Eigen/Geometry>
#include <numbers>

#include "liquid/core/error.hpp"
#include "liquid/levelset/levelset.hpp"
#include "liquid/surface/surface.hpp"

namespace liquid::surface {
namespace {

TEST(Surface, CircleIsClosedOutwardAndOfTheRightLength) {
  const Vec<2> c(0.41, 0.52);
  const double R = 0.3, cell = 0.01;
  const Mesh<2> m = extract<2>(levelset::sphere<2>(c, R), Box<2>{Vec<2>(0, 0), Vec<2>(1, 1)}, cell);
  ASSERT_GT(m.elements.size(), 100u);
  EXPECT_NEAR(m.measure(), 2 * std::numbers::pi * R, 1e-3 * 2 * std::numbers::pi * R);
  std::map<int, int> starts, ends;
  for (const auto& e : m.elements) {
    ++starts[e[0]], ++ends[e[1]];
    const Vec<2> d = m.vertices[e[1]] - m.vertices[e[0]];
    if (d.norm() < 1e-12) continue;  // a node on the circle: a segment of zero length at that node
    const Vec<2> right(d[1], -d[0]);
    EXPECT_GT(right.dot(0.5 * (m.vertices[e[0]] + m.vertices[e[1]]) - c), 0.0) << "a segment faces inwards";
  }
  for (int v = 0; v < static_cast<int>(m.vertices.size()); ++v) {
    EXPECT_EQ(starts[v], 1) << "vertex " << v;
    EXPECT_EQ(ends[v], 1) << "vertex " << v;
    EXPECT_LT(std::abs((m.vertices[v] - c).norm() - R), 0.5 * cell * cell / R);
  }
}

TEST(Surface, SphereIsClosedOutwardAndOfTheRightArea) {
  const Vec<3> c(0.48, 0.5, 0.53);
  const double R = 0.3, cell = 0.02;
  const Mesh<3> m = extract<3>(levelset::sphere<3>(c, R), Box<3>{Vec<3>::Zero(), Vec<3>::Ones()}, cell);
  ASSERT_GT(m.elements.size(), 1000u);
  EXPECT_NEAR(m.measure(), 4 * std::numbers::pi * R * R, 0.01 * 4 * std::numbers::pi * R * R);
  std::map<std::pair<int, int>, int> directed;
  for (const auto& t : m.elements) {
    const Vec<3> n = (m.vertices[t[1]] - m.vertices[t[0]]).cross(m.vertices[t[2]] - m.vertices[t[0]]);
    EXPECT_GT(n.dot((m.vertices[t[0]] + m.vertices[t[1]] + m.vertices[t[2]]) / 3 - c), 0.0)
        << "inward triangle";
    for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
  }
  // Closed and consistently oriented: every directed edge once, and its reverse once.
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1);
    const auto reverse = directed.find({edge.second, edge.first});
    ASSERT_NE(reverse, directed.end()) << "an open edge";
    EXPECT_EQ(reverse->second, 1);
  }
  for (const auto& v : m.vertices) EXPECT_LT(std::abs((v - c).norm() - R), 0.5 * 3 * cell * cell / R);
}

TEST(Surface, RefusesALevelSetThatIsNotFinite) {
  const Function<2> bad = [](const Vec<2>& x) { return x[0] > 0.5 ? std::nan("") : -1.0; };
  EXPECT_THROW(extract<2>(bad, Box<2>{Vec<2>(0, 0), Vec<2>(1, 1)}, 0.1), Error);
}

}  // namespace
}  // namespace liquid::surface
