#pragma once
// The AMG solvers (bicgstab-amg, gmres-amg, cg-amg: hypre's BoomerAMG as the preconditioner) and
// the MPI they run on. make_solver() hands them out like the others; amg_solve_rows() is the
// distributed entry: each rank passes its contiguous range of rows. An AmgHierarchy keeps
// BoomerAMG's hierarchy from one solve to the next while the matrix keeps its layout.
//
//   // on every rank of MPI_COMM_WORLD, rows [first, first + n) of an N x N system:
//   SolveStats s = amg_solve_rows(A_rows, b_rows, x_rows, first, N, options);
//
//   AmgHierarchy amg(options);                       // a time loop: one per pressure equation
//   for (...) s = amg.solve_rows(A, b, x, 0, A.rows());  // s.hierarchy_reused tells which

#include <memory>

#include "liquid/linalg/solver.hpp"

namespace liquid::linalg {

/// Initialises MPI (thread level funneled) unless the program did; finalises it at exit then.
void ensure_mpi();
/// This process's rank in MPI_COMM_WORLD and the number of ranks (initialising MPI if needed).
int mpi_rank();
int mpi_size();

/// Solves rows [first_row, first_row + rows.rows()) of an n_global x n_global system, collectively
/// over MPI_COMM_WORLD (every rank calls it with its own range; the ranges tile [0, n_global) in
/// rank order). `rows` has global column indices; `x` holds this rank's initial guess on entry
/// (zero if its size differs) and its part of the solution on return. The statistics (iterations,
/// true relative residual over all rows, setup and solve seconds) are the same on every rank.
/// Non-finite input, a zero row, or a failing hypre call are reported in SolveStats::info (and
/// SolveStats::note), never thrown from inside hypre.
SolveStats amg_solve_rows(const SparseMatrix& rows, const Vector& b, Vector& x, long first_row, long n_global,
                          const SolveOptions& options);

/// An AMG solver that keeps its hypre matrix, Krylov solver and BoomerAMG hierarchy between
/// solves. A solve whose matrix has the same layout as the last one (the same rows on this rank,
/// the same column indices in every row, checked on every rank) copies the new values into the
/// kept matrix and preconditions with the kept hierarchy (coarse levels from the matrix it was
/// built for, the finest level's smoothing on the new values); any other solve builds a new one.
/// Policy (AmgOptions::reuse_factor; docs/findings/amg.md): a kept hierarchy is rebuilt before
/// the next solve once a solve with it needed more than reuse_factor times the iterations of the
/// solve that built it, and at once (the solve repeated) when a solve with it did not converge.
/// reuse_factor = 0 builds a new hierarchy for every solve.
class AmgHierarchy {
 public:
  explicit AmgHierarchy(SolveOptions options);
  ~AmgHierarchy();
  AmgHierarchy(const AmgHierarchy&) = delete;
  AmgHierarchy& operator=(const AmgHierarchy&) = delete;

  /// As amg_solve_rows(), collectively over MPI_COMM_WORLD.
  SolveStats solve_rows(const SparseMatrix& rows, const Vector& b, Vector& x, long first_row, long n_global);

  /// Solves since the hierarchy in use was built (0: none kept), and hierarchies built so far.
  int solves_on_hierarchy() const;
  int n_setups() const;

  struct State;  ///< the kept hypre objects (amg.cpp)

 private:
  SolveOptions options_;
  std::unique_ptr<State> state_;
  int n_setups_ = 0;
};

}  // namespace liquid::linalg
