// Divergence at cell centres: the flux sum is exact for linear velocities and conservative for any;
// the RBF-FD divergence is exact for quadratic velocities, T-junctions included.
#include <gtest/gtest.h>

#include <cmath>

#include "liquid/levelset/levelset.hpp"
#include "liquid/mac/divergence.hpp"
#include "liquid/tree/builders.hpp"

namespace liquid::mac {
namespace {

template <int Dim>
tree::CellGraph<Dim> tree_with_jumps() {
  const Box<Dim> domain{Vec<Dim>::Constant(-1.0), Vec<Dim>::Constant(1.0)};
  return tree::narrow_band<Dim>(domain, levelset::sphere<Dim>(Vec<Dim>::Constant(0.1), 0.5), Dim == 2 ? 3 : 2,
                                Dim == 2 ? 5 : 4, 2.0);
}

template <int Dim, class Field>
std::vector<double> sample(const tree::CellGraph<Dim>& g, Field&& field) {
  std::vector<double> u(g.face_capacity(), 0.0);
  g.for_each_face([&](tree::FaceId f) { u[f] = field(g.face_centre(f), g.face(f).axis); });
  return u;
}

template <int Dim>
void check() {
  const tree::CellGraph<Dim> g = tree_with_jumps<Dim>();
  // Linear: u_k = k + 1 + 2 x_k - x_{k+1}; div = 2 Dim.
  auto linear = [](const Vec<Dim>& x, int k) { return k + 1.0 + 2.0 * x[k] - x[(k + 1) % Dim]; };
  // Quadratic: u_k = x_k^2 + x_0 x_1; div = 2 sum x_k + x_1 (k = 0) + x_0 (k = 1).
  auto quadratic = [](const Vec<Dim>& x, int k) { return x[k] * x[k] + x[0] * x[1]; };
  const auto fv = fv_divergence<Dim>(g, sample<Dim>(g, linear));
  const auto rbf_lin = rbf_divergence<Dim>(g, sample<Dim>(g, linear));
  const auto rbf_quad = rbf_divergence<Dim>(g, sample<Dim>(g, quadratic));
  g.for_each_cell([&](tree::CellId c) {
    const Vec<Dim> x = g.centre(c);
    EXPECT_NEAR(fv[c], 2.0 * Dim, 1e-10) << "cell " << c;
    EXPECT_NEAR(rbf_lin[c], 2.0 * Dim, 1e-8) << "cell " << c;
    EXPECT_NEAR(rbf_quad[c], 2.0 * x.sum() + x[1] + x[0], 1e-7) << "cell " << c;
  });
  // Conservation of the flux sum for a field that is not linear.
  auto wavy = [](const Vec<Dim>& x, int k) { return std::sin(3 * x[k] + k) * std::cos(x[(k + 1) % Dim]); };
  const auto u = sample<Dim>(g, wavy);
  const auto div = fv_divergence<Dim>(g, u);
  double total = 0.0, boundary = 0.0;
  g.for_each_cell([&](tree::CellId c) { total += g.volume(c) * div[c]; });
  g.for_each_face([&](tree::FaceId f) {
    const tree::GraphFace& gf = g.face(f);
    if (gf.is_boundary()) boundary += (gf.cell[0] != tree::no_cell ? 1.0 : -1.0) * u[f] * g.face_area(f);
  });
  EXPECT_NEAR(total, boundary, 1e-12);
}

TEST(Divergence, ExactAndConservative2D) {
  check<2>();
}
TEST(Divergence, ExactAndConservative3D) {
  check<3>();
}

}  // namespace
}  // namespace liquid::mac
