// RBF-FD stencil weights next to an interface: the retries of stencil_weights must rescue a
// stencil whose interface crossings cluster around its anchor (an interface a few thousandths of a
// cell away), as a random study of poisson-sweep found, and keep the row exact for quadratics.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "liquid/mac/stencil.hpp"

namespace liquid::mac {
namespace {

double quadratic(const Vec<3>& x) {
  return 1.0 + x[0] - 2.0 * x[1] + x[0] * x[0] + 0.5 * x[0] * x[2] - x[1] * x[1] + 0.7 * x[2] * x[2];
}
constexpr double quadratic_laplacian = 2.0 - 2.0 + 1.4;

// The stencil of the Laplacian row that made poisson-sweep's 3D study 16 throw (cell 114034, an
// ellipsoid on a random jump-2 tree): node positions relative to the cell centre in cell sizes,
// and whether the node is a known interface crossing. Most of its 27 crossings sit within 0.02
// cells of the centre; at degree 3 the condition stayed ~1.2e14 after four farthest-node drops.
struct RecordedNode {
  double x[3];
  bool known;
};
constexpr RecordedNode kStudy16Stencil[] = {
    {{0, 0, 0}, false},
    {{0.99999999999999467, 0, 0}, false},
    {{0, 0.002791004988911501, 0}, true},
    {{0, 0, -0.010342033655805825}, true},
    {{0, 0, 1.0000000000000029}, false},
    {{0, -1.0000000000000109, 0}, false},
    {{0.0096985443161020802, 0.0096985443161020802, 0}, true},
    {{0.99999999999999467, 0, -1.0000000000000029}, false},
    {{0.99999999999999467, 0, 1.0000000000000029}, false},
    {{0, 0.0021981003565769114, -0.002198100356576404}, true},
    {{0, 0.0038213850327700237, 0.0038213850327705307}, true},
    {{0.99999999999999467, -1.0000000000000109, 0}, false},
    {{0, -1.0000000000000109, -1.0000000000000029}, false},
    {{0, -1.0000000000000109, 1.0000000000000029}, false},
    {{0.005007910348673433, 0.005007910348673433, -0.005007910348673433}, true},
    {{0.11133130066432688, 0.11133130066432688, 0.11133130066432841}, true},
    {{0.99999999999999467, -1.0000000000000109, -1.0000000000000029}, false},
    {{0.99999999999999467, -1.0000000000000109, 1.0000000000000029}, false},
    {{1.9999999999999976, 0, 0}, false},
    {{0, -2.0000000000000058, 0}, false},
    {{0.0021678345737743973, 0.0043356691475528505, 0}, true},
    {{0, 0.0024593397131567434, -0.0012296698565788789}, true},
    {{0, 0.0032259834306476317, 0.0016129917153238158}, true},
    {{0.99999999999999467, 0, -1.9999999999999976}, false},
    {{0, 0.0018129090640975737, -0.0036258181281936261}, true},
    {{1.9999999999999976, 0.99999999999999467, 0}, false},
    {{1.9999999999999976, 0, -1.0000000000000029}, false},
    {{1.9999999999999976, 0, 1.0000000000000029}, false},
    {{0, -1.0000000000000109, -1.9999999999999976}, false},
    {{0.99999999999999467, -2.0000000000000058, 0}, false},
    {{1.9999999999999976, -1.0000000000000109, 0}, false},
    {{0, -2.0000000000000058, -1.0000000000000029}, false},
    {{0, -2.0000000000000058, 1.0000000000000029}, false},
    {{0.99999999999999467, -1.0000000000000109, -1.9999999999999976}, false},
    {{0.99999999999999467, -2.0000000000000058, -1.0000000000000029}, false},
    {{0.99999999999999467, -2.0000000000000058, 1.0000000000000029}, false},
    {{1.9999999999999976, -1.0000000000000109, 1.0000000000000029}, false},
    {{0, -2.0000000000000058, -1.9999999999999976}, false},
    {{-0.016682385933707553, -0.010009431560225343, -0.0033364771867416118}, true},
    {{0.99999999999999467, -2.0000000000000058, -1.9999999999999976}, false},
    {{0, -3.0000000000000004, 0}, false},
    {{3.0000000000000004, 0, 0}, false},
    {{1.9999999999999976, -2.0000000000000058, 1.0000000000000029}, false},
    {{0.99999999999999467, -3.0000000000000004, 0}, false},
    {{0, -3.0000000000000004, -1.0000000000000029}, false},
    {{0, -3.0000000000000004, 1.0000000000000029}, false},
    {{3.0000000000000004, 0, 1.0000000000000029}, false},
    {{0, -1.0000000000000109, -3.0000000000000004}, false},
    {{0.99999999999999467, -3.0000000000000004, -1.0000000000000029}, false},
    {{0.99999999999999467, -3.0000000000000004, 1.0000000000000029}, false},
    {{3.0000000000000004, -1.0000000000000109, 1.0000000000000029}, false},
    {{-0.0015798403479703055, 0.0015798403479703055, -0.00031596806959375683}, true},
    {{0, -3.0000000000000004, -1.9999999999999976}, false},
    {{0, -2.0000000000000058, -3.0000000000000004}, false},
    {{0.99999999999999467, -3.0000000000000004, -1.9999999999999976}, false},
    {{1.9999999999999976, -3.0000000000000004, 1.0000000000000029}, false},
    {{3.0000000000000004, -2.0000000000000058, 1.0000000000000029}, false},
    {{1.5000000000000002, -1.5000000000000002, 3.4999999999999978}, false},
    {{0, -0.031974682424142351, -0.12789872969656993}, true},
    {{0, -3.0000000000000004, -3.0000000000000004}, false},
    {{3.0000000000000004, -3.0000000000000004, 1.0000000000000029}, false},
    {{0, -2.0000000000000058, -4.0000000000000027}, false},
    {{0.008560295832390364, 0.014267159720653313, 0.019974023608912202}, true},
    {{0.49999999999999734, -4.5, 0.49999999999999734}, false},
    {{-2.5000000000000031, -1.5000000000000002, 3.4999999999999978}, false},
    {{0.49999999999999734, -4.5, -1.5000000000000002}, false},
    {{-0.0020903584296468997, 0.0020903584296468997, 0.0029265018015047469}, true},
    {{0, -3.0000000000000004, -4.0000000000000027}, false},
    {{0, -0.0079338958142885618, -0.039669479071437738}, true},
    {{-0.0046625396638659789, -0.0027975237983179648, -0.0083925713949589646}, true},
    {{0, -2.0000000000000058, -4.9999999999999973}, false},
    {{-0.0012696623691935886, 0.0012696623691935886, -0.0022853922645466344}, true},
    {{0, -3.0000000000000004, -4.9999999999999973}, false},
    {{-2.5000000000000031, -5.5000000000000115, -0.49999999999999734}, false},
    {{0, -0.0044952771880092321, -0.026971663128054886}, true},
    {{0, -1.2307226931579773, -3.6921680794739191}, true},
    {{0.49999999999999734, -6.5000000000000062, 0.49999999999999734}, false},
    {{5.4999999999999947, -1.5000000000000002, 3.4999999999999978}, false},
    {{-0.0055504798993694735, -0.0012808799767763228, -0.00042695999225911231}, true},
    {{0.49999999999999734, -6.5000000000000062, -1.5000000000000002}, false},
    {{1.5000000000000002, -5.5000000000000115, 3.4999999999999978}, false},
    {{0, -3.0000000000000004, -6.0000000000000009}, false},
    {{-0.0024962136740159179, 0.00096008218231443863, -0.00019201643646268491}, true},
    {{-2.5000000000000031, -5.5000000000000115, 3.4999999999999978}, false},
    {{-0.0082823240753997062, -0.0019113055558599105, 0.0044597129636773499}, true},
    {{-2.5000000000000031, -5.5000000000000115, -4.5}, false},
    {{1.5000000000000002, -1.5000000000000002, 7.5000000000000009}, false},
    {{-0.0041731227379902995, -0.00096302832415223164, -0.0028890849724536524}, true},
    {{-2.5000000000000031, -1.5000000000000002, 7.5000000000000009}, false},
    {{-2.4552955751820957, -2.077557794384858, -0.1888688903986219}, true},
    {{-0.0027088880143733441, -0.0016253328086215726, -0.0092102192488626774}, true},
    {{-2.5000000000000031, -9.5000000000000053, -0.49999999999999734}, false},
};

// Cell centres of a unit lattice within `rings` of the anchor (the origin); those outside a sphere
// of radius `radius` whose surface passes `gap` from the anchor (along (1, 1, 1)) become their
// crossing on the segment from the anchor (one per ray), carrying the exact value.
std::vector<StencilNode<3>> stencil_by_a_sphere(double gap, double radius, int rings) {
  const Vec<3> n = Vec<3>(1.0, 1.0, 1.0).normalized();
  const Vec<3> centre = -(radius - gap) * n;
  const auto phi = [&](const Vec<3>& x) { return (x - centre).norm() - radius; };
  std::vector<StencilNode<3>> nodes;
  int dof = 0;
  for (int i = -rings; i <= rings; ++i)
    for (int j = -rings; j <= rings; ++j)
      for (int k = -rings; k <= rings; ++k) {
        const Vec<3> x(i, j, k);
        if (phi(x) <= 0.0) {
          nodes.push_back({x, dof++, 0.0});
          continue;
        }
        double a = 0.0, b = 1.0;  // phi(0) < 0 < phi(x): bisect the segment
        for (int it = 0; it < 60; ++it) (phi(x * (0.5 * (a + b))) > 0.0 ? b : a) = 0.5 * (a + b);
        const Vec<3> cut = x * (0.5 * (a + b));
        bool seen = false;  // lattice points on one ray share their crossing
        for (const auto& nd : nodes) seen = seen || (nd.x - cut).norm() < 1e-9;
        if (!seen) nodes.push_back({cut, -1, quadratic(cut)});
      }
  return nodes;
}

/// The Laplacian row at the origin (unit cell size) on `nodes` (which the retries may thin), and
/// what it gives for the quadratic.
struct LaplacianRow {
  rbf::Status status;
  long n_retried = 0;
  double laplacian = 0.0;
};
LaplacianRow laplacian_row(std::vector<StencilNode<3>>& nodes, int degree) {
  rbf::Config config;
  config.degree = degree;
  std::vector<double> w;
  LaplacianRow row;
  row.status = stencil_weights<3>(nodes, Vec<3>::Zero(), rbf::Operator<3>::lap(), config, w, row.n_retried,
                                  nullptr, 1.0);
  if (row.status.usable())
    for (std::size_t j = 0; j < nodes.size(); ++j) row.laplacian += w[j] * quadratic(nodes[j].x);
  return row;
}

TEST(StencilWeights, ClusteredCrossingsAreThinnedUntilTheRowIsUsable) {
  std::vector<StencilNode<3>> nodes;
  int dof = 0;
  for (const auto& r : kStudy16Stencil) {
    const Vec<3> x(r.x[0], r.x[1], r.x[2]);
    nodes.push_back(r.known ? StencilNode<3>{x, -1, quadratic(x)} : StencilNode<3>{x, dof++, 0.0});
  }
  ASSERT_EQ(static_cast<int>(nodes.size()) - dof, 27);
  const LaplacianRow row = laplacian_row(nodes, 3);
  ASSERT_TRUE(row.status.usable()) << row.status.describe();
  EXPECT_GT(row.n_retried, 0);
  int kept_known = 0;
  for (const auto& nd : nodes) kept_known += nd.dof < 0;
  EXPECT_GE(kept_known, 1);  // the interface is still in the row
  EXPECT_LT(kept_known, 27);
  EXPECT_NEAR(row.laplacian, quadratic_laplacian, 1e-6);
}

TEST(StencilWeights, WellSeparatedCrossingsAreKept) {
  auto nodes = stencil_by_a_sphere(0.45, 20.0, 2);
  const std::size_t before = nodes.size();
  const LaplacianRow row = laplacian_row(nodes, 2);
  ASSERT_TRUE(row.status.usable()) << row.status.describe();
  EXPECT_EQ(row.n_retried, 0);
  EXPECT_EQ(nodes.size(), before);
  EXPECT_NEAR(row.laplacian, quadratic_laplacian, 1e-8);
}

}  // namespace
}  // namespace liquid::mac
