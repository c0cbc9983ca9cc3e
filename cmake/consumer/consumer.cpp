// Solves a small Poisson problem with the installed library and checks the answer.
#include <cmath>
#include <cstdio>

#include "liquid/linalg/solver.hpp"
#include "liquid/mac/poisson.hpp"
#include "liquid/tree/builders.hpp"

int main() {
  using namespace liquid;
  const Box<2> box{Vec<2>::Zero(), Vec<2>::Ones()};
  const tree::CellGraph<2> graph = tree::uniform<2>(box, 4);
  mac::PoissonProblem<2> problem;
  problem.f = [](const Vec<2>&) { return 2.0; };  // p = x^2 with Dirichlet walls
  problem.boundary.dirichlet_walls = true;
  problem.boundary.dirichlet = [](const Vec<2>& x) { return x[0] * x[0]; };
  const auto sys = mac::assemble_poisson<2>(graph, problem, mac::PoissonOptions{});
  linalg::Vector p;
  if (!linalg::solve(sys.A, sys.b, p, {linalg::SolverKind::direct}).converged()) return 1;
  double err = 0.0;
  for (long i = 0; i < sys.n_unknowns(); ++i) {
    const Vec<2> x = graph.centre(sys.layout.cell_of_dof[i]);
    err = std::max(err, std::abs(p[i] - x[0] * x[0]));
  }
  std::printf("consumer: %ld unknowns, L-inf error %.2e\n", sys.n_unknowns(), err);
  return err < 1e-10 ? 0 : 1;
}
