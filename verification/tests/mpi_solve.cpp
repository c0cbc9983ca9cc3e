// liquid-mpi-solve: the distributed path of the AMG solvers. Every rank assembles the same PPE
// (2D, an adaptive tree refined around a circle, Dirichlet p on the circle: RBF-FD rows at its
// T-junctions make the matrix non-symmetric), keeps its contiguous range of rows, and solves it
// with BiCGSTAB+BoomerAMG over MPI_COMM_WORLD; rank 0 compares the gathered solution with the
// one-process direct solve. Exit 0 when they agree to the tolerance, 1 otherwise.
//
//   mpirun -np 2 liquid-mpi-solve [LEVEL]
#include <fmt/format.h>
#include <mpi.h>

#include <cmath>
#include <cstdlib>
#include <vector>

#include "liquid/core/error.hpp"
#include "liquid/linalg/amg.hpp"
#include "liquid/mac/poisson.hpp"
#include "liquid/tree/builders.hpp"

int main(int argc, char** argv) {
  using namespace liquid;
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  int status = 0;
  try {
    const int level = argc > 1 ? std::atoi(argv[1]) : 7;
    LIQUID_VERIFY(level >= 3 && level <= 10, "level {} is outside [3, 10]", level);
    const Box<2> domain{Vec<2>(-1.0, -1.0), Vec<2>(1.0, 1.0)};
    const auto circle = levelset::sphere<2>(Vec<2>::Zero(), 0.8);
    const tree::CellGraph<2> graph = tree::narrow_band<2>(domain, circle, level - 3, level, 2.0);
    mac::PoissonProblem<2> problem;
    const auto exact = [](const Vec<2>& x) { return std::exp(x[0]) * std::sin(2.0 * x[1]); };
    problem.f = [&](const Vec<2>& x) { return -3.0 * exact(x); };
    problem.boundary.levelset = circle;
    problem.boundary.dirichlet = exact;
    const mac::PoissonSystem<2> system = mac::assemble_poisson<2>(graph, problem, mac::PoissonOptions{});
    const long n = system.A.rows();
    // Contiguous ranges in rank order.
    const long first = n * rank / size, last = n * (rank + 1) / size;
    const linalg::SparseMatrix rows = system.A.middleRows(first, last - first);
    const linalg::Vector b = system.b.segment(first, last - first);
    linalg::Vector x;
    const linalg::SolveOptions options{linalg::SolverKind::bicgstab_amg, 1e-10, 500};
    const linalg::SolveStats st = linalg::amg_solve_rows(rows, b, x, first, n, options);
    linalg::Vector mine = linalg::Vector::Zero(n), all(n);
    mine.segment(first, last - first) = x;
    MPI_Reduce(mine.data(), all.data(), static_cast<int>(n), MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
    if (rank == 0) {
      linalg::Vector reference;
      const linalg::SolveStats direct =
          linalg::solve(system.A, system.b, reference, {linalg::SolverKind::direct, 1e-10, 1});
      const double difference =
          (all - reference).lpNorm<Eigen::Infinity>() / reference.lpNorm<Eigen::Infinity>();
      fmt::print("liquid-mpi-solve: {} ranks, {} unknowns ({} RBF-FD rows); {}\n", size, n,
                 system.stats.n_rbf_rows, st.describe());
      std::vector<long> per_rank;
      for (int r = 0; r < size; ++r) per_rank.push_back(n * (r + 1) / size - n * r / size);
      fmt::print("  rows per rank: {}; max |x - x_direct| / max |x_direct| = {:.3e} (direct: {})\n",
                 fmt::join(per_rank, ", "), difference, direct.describe());
      if (!st.converged() || !(difference < 1e-8)) {
        fmt::print(
            "liquid-mpi-solve: FAILED (the distributed solve must converge and match the direct one)\n");
        status = 1;
      }
    }
  } catch (const Error& e) {
    fmt::print(stderr, "liquid-mpi-solve (rank {}): error: {}\n", rank, e.what());
    status = 2;
  }
  MPI_Bcast(&status, 1, MPI_INT, 0, MPI_COMM_WORLD);
  MPI_Finalize();
  return status;
}
