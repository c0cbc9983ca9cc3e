// Flux rows (IrregularRows::flux): at every unknown the PPE row is the finite-volume divergence of
// the face gradients the projection subtracts, so a projection leaves only the solver's residual as
// divergence; quadratics are solved exactly; a smooth solution converges.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "liquid/levelset/levelset.hpp"
#include "liquid/mac/divergence.hpp"
#include "liquid/mac/poisson.hpp"
#include "liquid/tree/builders.hpp"
#include "poisson_fixtures.hpp"

namespace liquid::mac {
namespace {

enum class Outside { air_cells, levelset };

using testing::non_graded;
using testing::quad;

/// Dirichlet outside a ball: a level set, or the cells whose centres lie outside as air cells.
template <int Dim>
void set_outside(PoissonProblem<Dim>& problem, const tree::CellGraph<Dim>& graph, Outside outside) {
  const auto blob = levelset::sphere<Dim>(Vec<Dim>::Constant(0.05), 0.7);
  if (outside == Outside::levelset) {
    problem.boundary.levelset = blob;
    return;
  }
  problem.boundary.unknown_cells.assign(graph.cell_capacity(), 0);
  graph.for_each_cell(
      [&](tree::CellId c) { problem.boundary.unknown_cells[c] = blob(graph.centre(c)) < 0.0; });
}

template <int Dim>
PoissonProblem<Dim> problem_on(const tree::CellGraph<Dim>& graph, Outside outside) {
  PoissonProblem<Dim> problem;
  problem.f = [](const Vec<Dim>&) { return Dim == 2 ? 0.0 : 1.4; };  // Lap quad
  problem.boundary.dirichlet = quad<Dim>;
  set_outside(problem, graph, outside);
  return problem;
}

PoissonOptions flux_options() {
  PoissonOptions o;
  o.irregular = IrregularRows::flux;
  return o;
}

/// The projection's face gradient of p: face_normal_derivative, and towards a cell outside a level set
/// the ghost-fluid difference to the crossing (theta >= 1e-3); walls carry no flux.
template <int Dim>
std::vector<double> projection_gradient(const tree::CellGraph<Dim>& graph, const PoissonSystem<Dim>& sys,
                                        const PoissonOptions& options, const linalg::Vector& p) {
  std::vector<double> dn = face_normal_derivative<Dim>(graph, sys, options, p);
  graph.for_each_face([&](tree::FaceId f) {
    const tree::GraphFace& g = graph.face(f);
    if (g.is_boundary()) {
      dn[f] = 0.0;
      return;
    }
    if (std::isfinite(dn[f])) return;
    const int i0 = sys.layout.dof_of_cell[g.cell[0]], i1 = sys.layout.dof_of_cell[g.cell[1]];
    if ((i0 >= 0) == (i1 >= 0)) {
      dn[f] = 0.0;
      return;
    }
    const int in = i0 >= 0 ? 0 : 1;
    const Vec<Dim> a = graph.centre(g.cell[in]), b = graph.centre(g.cell[1 - in]);
    const auto& phi = sys.boundary.levelset;
    const auto cut = levelset::crossing<Dim>(phi, a, b, phi(a), phi(b));
    const double theta = std::max(cut->theta, 1e-3), d = std::abs(b[g.axis] - a[g.axis]);
    const double outward = (sys.boundary.dirichlet(cut->point) - p[in == 0 ? i0 : i1]) / (theta * d);
    dn[f] = in == 0 ? outward : -outward;
  });
  return dn;
}

template <int Dim>
void rows_are_the_divergence_of_the_projection_gradient(Outside outside) {
  const tree::CellGraph<Dim> graph = non_graded<Dim>(Dim == 2 ? 4 : 2);
  PoissonProblem<Dim> problem = problem_on<Dim>(graph, outside);
  problem.f = [](const Vec<Dim>&) { return 0.0; };
  const PoissonOptions options = flux_options();
  const PoissonSystem<Dim> sys = assemble_poisson<Dim>(graph, problem, options);
  ASSERT_GT(sys.stats.n_rbf_rows, 0) << "no T-junction row: the test would see only FD rows";
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  linalg::Vector p(sys.n_unknowns());
  for (long i = 0; i < p.size(); ++i) p[i] = u(rng);
  // With f = 0, A p - b is -div(G p) at every unknown, G p including its known values.
  const linalg::Vector row = sys.A * p - sys.b;
  const std::vector<double> div = fv_divergence<Dim>(graph, projection_gradient<Dim>(graph, sys, options, p));
  double worst = 0.0, scale = 0.0;
  for (long i = 0; i < sys.n_unknowns(); ++i) {
    const tree::CellId c = sys.layout.cell_of_dof[i];
    worst = std::max(worst, std::abs(row[i] + div[c]));
    scale = std::max(scale, std::abs(div[c]));
  }
  EXPECT_GT(scale, 1.0);
  EXPECT_LT(worst, 1e-10 * scale);
  // The paper's RBF-FD Laplacian rows are not that divergence: the test can tell them apart.
  const PoissonSystem<Dim> paper = assemble_poisson<Dim>(graph, problem, PoissonOptions{});
  const linalg::Vector paper_row = paper.A * p - paper.b;
  double apart = 0.0;
  for (long i = 0; i < sys.n_unknowns(); ++i)
    apart = std::max(apart, std::abs(paper_row[i] + div[sys.layout.cell_of_dof[i]]));
  EXPECT_GT(apart, 1e-3 * scale);
}

TEST(FluxRows, AreTheDivergenceOfTheProjectionGradient2D) {
  rows_are_the_divergence_of_the_projection_gradient<2>(Outside::air_cells);
  rows_are_the_divergence_of_the_projection_gradient<2>(Outside::levelset);
}
TEST(FluxRows, AreTheDivergenceOfTheProjectionGradient3D) {
  rows_are_the_divergence_of_the_projection_gradient<3>(Outside::air_cells);
  rows_are_the_divergence_of_the_projection_gradient<3>(Outside::levelset);
}

/// Face gradients exact for quadratics (two-point at equal faces, RBF-FD of degree >= 2 at hanging
/// ones), summed by the midpoint rule over each face: the flux rows are exact for quadratics.
template <int Dim>
void air_cells_quadratic_is_exact() {
  const tree::CellGraph<Dim> graph = non_graded<Dim>(Dim == 2 ? 4 : 2);
  const PoissonProblem<Dim> problem = problem_on<Dim>(graph, Outside::air_cells);
  const PoissonSystem<Dim> sys = assemble_poisson<Dim>(graph, problem, flux_options());
  ASSERT_GT(sys.stats.n_rbf_rows, 0);
  EXPECT_LT(testing::direct_error_against_quad<Dim>(graph, sys), 1e-9);
}
TEST(FluxRows, AirCellsQuadraticIsExact2D) {
  air_cells_quadratic_is_exact<2>();
}
TEST(FluxRows, AirCellsQuadraticIsExact3D) {
  air_cells_quadratic_is_exact<3>();
}

/// p = sin(2x) cos(y) (+ z^2 in 3D), Dirichlet outside a ball, on a non-graded tree at `level`: the
/// L-inf error at the unknowns.
template <int Dim>
double smooth_error(int level, IrregularRows rows = IrregularRows::flux,
                    Outside outside = Outside::levelset) {
  const tree::CellGraph<Dim> graph = non_graded<Dim>(level);
  const auto exact = [](const Vec<Dim>& x) {
    double v = std::sin(2 * x[0]) * std::cos(x[1]);
    if constexpr (Dim == 3) v += x[2] * x[2];
    return v;
  };
  PoissonProblem<Dim> problem;
  problem.f = [](const Vec<Dim>& x) {
    double v = -5.0 * std::sin(2 * x[0]) * std::cos(x[1]);
    if constexpr (Dim == 3) v += 2.0;
    return v;
  };
  set_outside(problem, graph, outside);
  problem.boundary.dirichlet = exact;
  PoissonOptions o;
  o.irregular = rows;
  const PoissonSystem<Dim> sys = assemble_poisson<Dim>(graph, problem, o);
  EXPECT_GT(sys.stats.n_rbf_rows, 0);
  linalg::Vector p;
  EXPECT_TRUE(linalg::solve(sys.A, sys.b, p, {linalg::SolverKind::direct}).converged());
  double err = 0.0;
  for (long i = 0; i < sys.n_unknowns(); ++i)
    err = std::max(err, std::abs(p[i] - exact(graph.centre(sys.layout.cell_of_dof[i]))));
  return err;
}
// With air cells (the PIC's free surface) the flux rows converge at second order in 2D and stay within
// 3x of the RBF-FD Laplacian rows' error in 3D (measured: 0.8-1.0x at levels 2-3, 2.5x at 4). With a
// level-set surface they are 10-65x less accurate (the ghost-fluid difference towards a cell of another level
// runs along a slanted segment), which is why scenes refuse that pair.
TEST(FluxRows, SmoothSolutionConverges2D) {
  const double e5 = smooth_error<2>(5, IrregularRows::flux, Outside::air_cells);
  const double e6 = smooth_error<2>(6, IrregularRows::flux, Outside::air_cells);
  const double e7 = smooth_error<2>(7, IrregularRows::flux, Outside::air_cells);
  EXPECT_GT(std::log2(e5 / e6), 1.5) << e5 << " " << e6 << " " << e7;
  EXPECT_GT(std::log2(e6 / e7), 1.5) << e5 << " " << e6 << " " << e7;
}
TEST(FluxRows, SmoothSolutionNearTheLaplacianRows3D) {
  for (int level : {2, 3}) {
    const double flux = smooth_error<3>(level, IrregularRows::flux, Outside::air_cells);
    const double laplacian = smooth_error<3>(level, IrregularRows::laplacian, Outside::air_cells);
    EXPECT_LT(flux, 3.0 * laplacian) << "level " << level;
    EXPECT_GT(flux, 1e-6) << "solved exactly: the comparison would measure round-off";
  }
}

}  // namespace
}  // namespace liquid::mac
