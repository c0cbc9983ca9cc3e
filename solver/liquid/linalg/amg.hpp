#pragma once
// The AMG solvers (bicgstab-amg, gmres-amg, cg-amg: hypre's BoomerAMG as the preconditioner) and
// the MPI they run on. make_solver() hands them out like the others; amg_solve_rows() is the
// distributed entry: each rank passes its contiguous range of rows.
//
//   // on every rank of MPI_COMM_WORLD, rows [first, first + n) of an N x N system:
//   SolveStats s = amg_solve_rows(A_rows, b_rows, x_rows, first, N, options);

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

}  // namespace liquid::linalg
