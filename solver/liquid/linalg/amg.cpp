// Krylov solvers preconditioned by hypre's BoomerAMG (algebraic multigrid): bicgstab-amg,
// gmres-amg, cg-amg. The matrix goes to hypre as a ParCSR matrix over MPI_COMM_WORLD, one
// contiguous row range per rank (one rank: every row). Every HYPRE_* call is checked; hypre's own
// error printing is off, a failure is a reported SolveInfo, never an abort.
#include <HYPRE.h>
#include <HYPRE_parcsr_ls.h>
#include <fmt/format.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <limits>
#include <vector>

#include "liquid/core/error.hpp"
#include "liquid/core/timer.hpp"
#include "liquid/linalg/amg.hpp"

namespace liquid::linalg {

namespace {

void finalize_mpi() {
  int finalized = 0;
  MPI_Finalized(&finalized);
  if (!finalized) MPI_Finalize();
}

/// A failed HYPRE_* call: the call's name and hypre's error code.
struct HypreFailure {
  const char* call;
  HYPRE_Int code;
};

void check(HYPRE_Int code, const char* call) {
  if (code != 0) {
    HYPRE_ClearAllErrors();
    throw HypreFailure{call, code};
  }
}
#define LIQUID_HYPRE(call) check((call), #call)

/// Owns the hypre objects of one solve.
struct HypreObjects {
  HYPRE_IJMatrix A = nullptr;
  HYPRE_IJVector b = nullptr, x = nullptr;
  HYPRE_Solver amg = nullptr, krylov = nullptr;
  SolverKind kind = SolverKind::bicgstab_amg;
  ~HypreObjects() {
    if (krylov) {
      if (kind == SolverKind::bicgstab_amg) HYPRE_ParCSRBiCGSTABDestroy(krylov);
      if (kind == SolverKind::gmres_amg) HYPRE_ParCSRGMRESDestroy(krylov);
      if (kind == SolverKind::cg_amg) HYPRE_ParCSRPCGDestroy(krylov);
    }
    if (amg) HYPRE_BoomerAMGDestroy(amg);
    if (x) HYPRE_IJVectorDestroy(x);
    if (b) HYPRE_IJVectorDestroy(b);
    if (A) HYPRE_IJMatrixDestroy(A);
    HYPRE_ClearAllErrors();
  }
};

}  // namespace

void ensure_mpi() {
  int initialised = 0;
  MPI_Initialized(&initialised);
  if (initialised) return;
  int provided = 0;
  LIQUID_VERIFY(MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided) == MPI_SUCCESS,
                "AMG: MPI could not be initialised (hypre needs it, even on one rank)");
  std::atexit(finalize_mpi);
}

int mpi_rank() {
  ensure_mpi();
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  return rank;
}

int mpi_size() {
  ensure_mpi();
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  return size;
}

SolveStats amg_solve_rows(const SparseMatrix& rows, const Vector& b, Vector& x, long first_row, long n_global,
                          const SolveOptions& options) {
  ensure_mpi();
  SolveStats stats;
  stats.solver = to_string(options.kind);
  stats.n_unknowns = n_global;
  const long n = rows.rows();
  LIQUID_VERIFY(options.kind == SolverKind::bicgstab_amg || options.kind == SolverKind::gmres_amg ||
                    options.kind == SolverKind::cg_amg,
                "amg_solve_rows: solver {} is not an AMG solver", stats.solver);
  LIQUID_VERIFY(rows.cols() == n_global && b.size() == n && first_row >= 0 && first_row + n <= n_global,
                "{}: rows {}..{} ({} x {}) and right-hand side {} do not fit {} unknowns", stats.solver,
                first_row, first_row + n, n, rows.cols(), b.size(), n_global);
  if (x.size() != n) x = Vector::Zero(n);
  const int max_iterations = std::min(options.max_iterations, options.amg.max_iterations);
  // Non-finite input and empty rows would make hypre divide by zero somewhere inside: refuse them.
  bool finite = b.allFinite() && x.allFinite();
  for (long k = 0; k < rows.nonZeros() && finite; ++k) finite = std::isfinite(rows.valuePtr()[k]);
  int local_bad = finite ? 0 : 1, bad = 0;
  MPI_Allreduce(&local_bad, &bad, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  if (bad) {
    stats.info = SolveInfo::non_finite;
    return stats;
  }
  int local_empty = 0, empty = 0;
  for (long i = 0; i < n && !local_empty; ++i) {
    bool nonzero = false;
    for (SparseMatrix::InnerIterator it(rows, i); it; ++it) nonzero = nonzero || it.value() != 0.0;
    local_empty = nonzero ? 0 : 1;
  }
  MPI_Allreduce(&local_empty, &empty, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  if (empty) {
    stats.info = SolveInfo::setup_failed;  // a zero row: the matrix is singular
    return stats;
  }
  double local_b2 = b.squaredNorm(), b2 = 0.0;
  MPI_Allreduce(&local_b2, &b2, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  if (b2 == 0.0) {  // the solution of A x = 0 is 0 (A regular); hypre would divide by |b| = 0
    x.setZero();
    return stats;
  }

  HypreObjects h;
  h.kind = options.kind;
  Stopwatch watch;
  try {
    const auto lo = static_cast<HYPRE_BigInt>(first_row), hi = static_cast<HYPRE_BigInt>(first_row + n - 1);
    LIQUID_HYPRE(HYPRE_IJMatrixCreate(MPI_COMM_WORLD, lo, hi, lo, hi, &h.A));
    LIQUID_HYPRE(HYPRE_IJMatrixSetObjectType(h.A, HYPRE_PARCSR));
    // hypre splits a row range into a diagonal block (columns in the rank's range) and the rest.
    std::vector<HYPRE_Int> diag(n, 0), offd(n, 0), ncols(n);
    std::vector<HYPRE_BigInt> row_ids(n), cols(rows.nonZeros());
    std::vector<double> values(rows.nonZeros());
    long k = 0;
    for (long i = 0; i < n; ++i) {
      row_ids[i] = static_cast<HYPRE_BigInt>(first_row + i);
      ncols[i] = 0;
      for (SparseMatrix::InnerIterator it(rows, i); it; ++it, ++k) {
        cols[k] = static_cast<HYPRE_BigInt>(it.col());
        values[k] = it.value();
        ++ncols[i];
        (it.col() >= first_row && it.col() < first_row + n ? diag[i] : offd[i])++;
      }
    }
    LIQUID_HYPRE(HYPRE_IJMatrixSetDiagOffdSizes(h.A, diag.data(), offd.data()));
    LIQUID_HYPRE(HYPRE_IJMatrixInitialize(h.A));
    LIQUID_HYPRE(HYPRE_IJMatrixSetValues(h.A, static_cast<HYPRE_Int>(n), ncols.data(), row_ids.data(),
                                         cols.data(), values.data()));
    LIQUID_HYPRE(HYPRE_IJMatrixAssemble(h.A));
    HYPRE_ParCSRMatrix A = nullptr;
    LIQUID_HYPRE(HYPRE_IJMatrixGetObject(h.A, reinterpret_cast<void**>(&A)));

    const auto make_vector = [&](HYPRE_IJVector& v, const Vector& values_in) {
      LIQUID_HYPRE(HYPRE_IJVectorCreate(MPI_COMM_WORLD, lo, hi, &v));
      LIQUID_HYPRE(HYPRE_IJVectorSetObjectType(v, HYPRE_PARCSR));
      LIQUID_HYPRE(HYPRE_IJVectorInitialize(v));
      LIQUID_HYPRE(HYPRE_IJVectorSetValues(v, static_cast<HYPRE_Int>(n), row_ids.data(), values_in.data()));
      LIQUID_HYPRE(HYPRE_IJVectorAssemble(v));
      HYPRE_ParVector out = nullptr;
      LIQUID_HYPRE(HYPRE_IJVectorGetObject(v, reinterpret_cast<void**>(&out)));
      return out;
    };
    HYPRE_ParVector pb = make_vector(h.b, b);
    HYPRE_ParVector px = make_vector(h.x, x);

    // BoomerAMG as a preconditioner: one V-cycle per application. See AmgOptions for the choices.
    const AmgOptions& a = options.amg;
    LIQUID_HYPRE(HYPRE_BoomerAMGCreate(&h.amg));
    LIQUID_HYPRE(HYPRE_BoomerAMGSetPrintLevel(h.amg, 0));
    LIQUID_HYPRE(HYPRE_BoomerAMGSetCoarsenType(h.amg, a.coarsening));
    LIQUID_HYPRE(HYPRE_BoomerAMGSetInterpType(h.amg, a.interpolation));
    LIQUID_HYPRE(HYPRE_BoomerAMGSetPMaxElmts(h.amg, a.max_interpolation_entries));
    LIQUID_HYPRE(HYPRE_BoomerAMGSetRelaxType(h.amg, a.smoother));
    LIQUID_HYPRE(HYPRE_BoomerAMGSetNumSweeps(h.amg, a.sweeps));
    LIQUID_HYPRE(HYPRE_BoomerAMGSetStrongThreshold(h.amg, a.strength));
    LIQUID_HYPRE(HYPRE_BoomerAMGSetAggNumLevels(h.amg, a.aggressive_levels));
    LIQUID_HYPRE(HYPRE_BoomerAMGSetMaxIter(h.amg, 1));
    LIQUID_HYPRE(HYPRE_BoomerAMGSetTol(h.amg, 0.0));

    // One Krylov solver behind three calls: setup, solve (from the current x), iterations.
    std::function<HYPRE_Int(HYPRE_ParCSRMatrix, HYPRE_ParVector, HYPRE_ParVector)> setup, solve;
    std::function<HYPRE_Int()> count;
    switch (options.kind) {
      case SolverKind::bicgstab_amg:
        LIQUID_HYPRE(HYPRE_ParCSRBiCGSTABCreate(MPI_COMM_WORLD, &h.krylov));
        LIQUID_HYPRE(HYPRE_ParCSRBiCGSTABSetTol(h.krylov, options.tolerance));
        LIQUID_HYPRE(HYPRE_ParCSRBiCGSTABSetMaxIter(h.krylov, max_iterations));
        LIQUID_HYPRE(
            HYPRE_ParCSRBiCGSTABSetPrecond(h.krylov, HYPRE_BoomerAMGSolve, HYPRE_BoomerAMGSetup, h.amg));
        setup = [&](auto M, auto f, auto u) { return HYPRE_ParCSRBiCGSTABSetup(h.krylov, M, f, u); };
        solve = [&](auto M, auto f, auto u) { return HYPRE_ParCSRBiCGSTABSolve(h.krylov, M, f, u); };
        count = [&] {
          HYPRE_Int it = 0;
          HYPRE_ParCSRBiCGSTABGetNumIterations(h.krylov, &it);
          return it;
        };
        break;
      case SolverKind::gmres_amg:
        LIQUID_HYPRE(HYPRE_ParCSRGMRESCreate(MPI_COMM_WORLD, &h.krylov));
        LIQUID_HYPRE(HYPRE_ParCSRGMRESSetKDim(h.krylov, a.gmres_restart));
        LIQUID_HYPRE(HYPRE_ParCSRGMRESSetTol(h.krylov, options.tolerance));
        LIQUID_HYPRE(HYPRE_ParCSRGMRESSetMaxIter(h.krylov, max_iterations));
        LIQUID_HYPRE(
            HYPRE_ParCSRGMRESSetPrecond(h.krylov, HYPRE_BoomerAMGSolve, HYPRE_BoomerAMGSetup, h.amg));
        setup = [&](auto M, auto f, auto u) { return HYPRE_ParCSRGMRESSetup(h.krylov, M, f, u); };
        solve = [&](auto M, auto f, auto u) { return HYPRE_ParCSRGMRESSolve(h.krylov, M, f, u); };
        count = [&] {
          HYPRE_Int it = 0;
          HYPRE_ParCSRGMRESGetNumIterations(h.krylov, &it);
          return it;
        };
        break;
      default:
        LIQUID_HYPRE(HYPRE_ParCSRPCGCreate(MPI_COMM_WORLD, &h.krylov));
        LIQUID_HYPRE(HYPRE_ParCSRPCGSetTwoNorm(h.krylov, 1));
        LIQUID_HYPRE(HYPRE_ParCSRPCGSetTol(h.krylov, options.tolerance));
        LIQUID_HYPRE(HYPRE_ParCSRPCGSetMaxIter(h.krylov, max_iterations));
        LIQUID_HYPRE(HYPRE_ParCSRPCGSetPrecond(h.krylov, HYPRE_BoomerAMGSolve, HYPRE_BoomerAMGSetup, h.amg));
        setup = [&](auto M, auto f, auto u) { return HYPRE_ParCSRPCGSetup(h.krylov, M, f, u); };
        solve = [&](auto M, auto f, auto u) { return HYPRE_ParCSRPCGSolve(h.krylov, M, f, u); };
        count = [&] {
          HYPRE_Int it = 0;
          HYPRE_ParCSRPCGGetNumIterations(h.krylov, &it);
          return it;
        };
        break;
    }
    check(setup(A, pb, px), "the Krylov solver's setup (BoomerAMG's hierarchy)");
    stats.setup_seconds = watch.seconds();
    watch.restart();
    // The stopping test is the recurrence's; the result is judged by the true residual over every
    // rank's rows. Short of it, start again from the current iterate (as the Eigen solvers do).
    for (int attempt = 0; attempt < 4; ++attempt) {
      solve(A, pb, px);  // not converging is reported by an error code: judged below instead
      HYPRE_ClearAllErrors();
      stats.iterations += static_cast<int>(count());
      LIQUID_HYPRE(HYPRE_IJVectorGetValues(h.x, static_cast<HYPRE_Int>(n), row_ids.data(), x.data()));
      if (!x.allFinite()) break;
      Vector full = Vector::Zero(n_global);
      full.segment(first_row, n) = x;
      Vector gathered(n_global);
      MPI_Allreduce(full.data(), gathered.data(), static_cast<int>(n_global), MPI_DOUBLE, MPI_SUM,
                    MPI_COMM_WORLD);
      const double local_r2 = (b - rows * gathered).squaredNorm();
      double r2 = 0.0;
      MPI_Allreduce(&local_r2, &r2, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
      stats.relative_residual = std::sqrt(r2 / b2);
      if (stats.relative_residual <= options.tolerance || stats.iterations >= max_iterations || count() == 0)
        break;
    }
    stats.solve_seconds = watch.seconds();
  } catch (const HypreFailure& f) {
    stats.info = SolveInfo::setup_failed;
    stats.setup_seconds = watch.seconds();
    stats.note = fmt::format("{} returned hypre error {}", f.call, f.code);
    return stats;
  }
  if (!x.allFinite()) {
    stats.info = SolveInfo::non_finite;
    stats.relative_residual = std::numeric_limits<double>::quiet_NaN();
    return stats;
  }
  stats.info = stats.relative_residual <= options.tolerance ? SolveInfo::converged : SolveInfo::not_converged;
  return stats;
}

}  // namespace liquid::linalg
