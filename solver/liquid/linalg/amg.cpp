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

namespace {

/// The layout of this rank's rows: the same layout means the same hypre matrix structure.
bool same_layout(const SparseMatrix& rows, long first_row, long n_global, long kept_first, long kept_global,
                 const std::vector<SparseMatrix::StorageIndex>& outer,
                 const std::vector<SparseMatrix::StorageIndex>& inner) {
  if (first_row != kept_first || n_global != kept_global || rows.rows() + 1 != long(outer.size()) ||
      rows.nonZeros() != long(inner.size()) || !rows.isCompressed())
    return false;
  return std::equal(outer.begin(), outer.end(), rows.outerIndexPtr()) &&
         std::equal(inner.begin(), inner.end(), rows.innerIndexPtr());
}

}  // namespace

/// The hypre objects of the kept hierarchy and the layout they were built for.
struct AmgHierarchy::State {
  HypreObjects h;
  HYPRE_ParCSRMatrix A = nullptr;
  HYPRE_ParVector b = nullptr, x = nullptr;
  // One Krylov solver behind two calls: solve (from the current x) and its iteration count.
  std::function<HYPRE_Int()> solve, count;
  // The layout: this rank's first row, the global size, the compressed row structure.
  long first_row = -1, n_global = -1;
  std::vector<SparseMatrix::StorageIndex> outer, inner;
  std::vector<HYPRE_BigInt> row_ids, cols;
  std::vector<HYPRE_Int> ncols;
  std::vector<double> values;
  int fresh_iterations = 0;  ///< iterations of the solve that built the hierarchy
  int solves = 0;            ///< solves with this hierarchy
  bool stale = false;        ///< rebuild before the next solve (the policy)

  /// The matrix values of `rows` in hypre's row order.
  void copy_values(const SparseMatrix& rows) {
    values.assign(rows.valuePtr(), rows.valuePtr() + rows.nonZeros());
  }
  /// Sets a kept vector to `in` (this rank's rows).
  void set_vector(HYPRE_IJVector v, const Vector& in) {
    LIQUID_HYPRE(HYPRE_IJVectorInitialize(v));
    LIQUID_HYPRE(
        HYPRE_IJVectorSetValues(v, static_cast<HYPRE_Int>(row_ids.size()), row_ids.data(), in.data()));
    LIQUID_HYPRE(HYPRE_IJVectorAssemble(v));
  }
};

AmgHierarchy::AmgHierarchy(SolveOptions options) : options_(std::move(options)) {}
AmgHierarchy::~AmgHierarchy() = default;
int AmgHierarchy::solves_on_hierarchy() const {
  return state_ ? state_->solves : 0;
}
int AmgHierarchy::n_setups() const {
  return n_setups_;
}

namespace {

/// Builds the hypre matrix, vectors, BoomerAMG and the Krylov solver for `rows`, and sets them up.
void build(AmgHierarchy::State& s, const SparseMatrix& rows, const Vector& b, const Vector& x, long first_row,
           long n_global, const SolveOptions& options);

}  // namespace

SolveStats AmgHierarchy::solve_rows(const SparseMatrix& rows, const Vector& b, Vector& x, long first_row,
                                    long n_global) {
  ensure_mpi();
  const SolveOptions& options = options_;
  SolveStats stats;
  stats.solver = to_string(options.kind);
  stats.n_unknowns = n_global;
  const long n = rows.rows();
  LIQUID_VERIFY(uses_amg(options.kind), "amg_solve_rows: solver {} is not an AMG solver", stats.solver);
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

  // Keep the hierarchy when every rank's layout is the one it was built for (and the policy allows).
  int local_same = state_ && !state_->stale && options.amg.reuse_factor > 0.0 &&
                   same_layout(rows, first_row, n_global, state_->first_row, state_->n_global, state_->outer,
                               state_->inner);
  int same = 0;
  MPI_Allreduce(&local_same, &same, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);

  const Vector x0 = x;
  Stopwatch watch;
  for (int round = 0; round < 2; ++round) {
    const bool reuse = same && round == 0;
    try {
      if (reuse) {
        // The new values into the kept structure: hypre re-initialises an assembled matrix for this.
        State& s = *state_;
        s.copy_values(rows);
        LIQUID_HYPRE(HYPRE_IJMatrixInitialize(s.h.A));
        LIQUID_HYPRE(HYPRE_IJMatrixSetValues(s.h.A, static_cast<HYPRE_Int>(n), s.ncols.data(),
                                             s.row_ids.data(), s.cols.data(), s.values.data()));
        LIQUID_HYPRE(HYPRE_IJMatrixAssemble(s.h.A));
        s.set_vector(s.h.b, b);
        s.set_vector(s.h.x, x);
      } else {
        state_ = std::make_unique<State>();
        build(*state_, rows, b, x, first_row, n_global, options);
        ++n_setups_;
      }
    } catch (const HypreFailure& f) {
      state_.reset();
      stats.info = SolveInfo::setup_failed;
      stats.setup_seconds += watch.seconds();
      stats.note = fmt::format("{} returned hypre error {}", f.call, f.code);
      return stats;
    }
    stats.setup_seconds += watch.seconds();
    watch.restart();
    State& s = *state_;
    // The stopping test is the recurrence's; the result is judged by the true residual over every
    // rank's rows. Short of it, start again from the current iterate (as the Eigen solvers do).
    int iterations = 0;
    try {
      for (int attempt = 0; attempt < 4; ++attempt) {
        s.solve();  // not converging is reported by an error code: judged below instead
        HYPRE_ClearAllErrors();
        iterations += static_cast<int>(s.count());
        LIQUID_HYPRE(HYPRE_IJVectorGetValues(s.h.x, static_cast<HYPRE_Int>(n), s.row_ids.data(), x.data()));
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
        if (stats.relative_residual <= options.tolerance || iterations >= max_iterations || s.count() == 0)
          break;
      }
    } catch (const HypreFailure& f) {
      state_.reset();
      stats.info = SolveInfo::setup_failed;
      stats.solve_seconds += watch.seconds();
      stats.note = fmt::format("{} returned hypre error {}", f.call, f.code);
      return stats;
    }
    stats.iterations += iterations;
    stats.solve_seconds += watch.seconds();
    watch.restart();
    ++s.solves;
    const bool converged = x.allFinite() && stats.relative_residual <= options.tolerance;
    if (!reuse) {
      s.fresh_iterations = std::max(1, iterations);
      break;
    }
    stats.hierarchy_reused = true;
    // The policy: a kept hierarchy that costs more than reuse_factor times its first solve's
    // iterations is rebuilt for the next solve; one that did not converge is rebuilt now.
    if (iterations > options.amg.reuse_factor * s.fresh_iterations) s.stale = true;
    if (converged) break;
    stats.hierarchy_reused = false;
    stats.note = fmt::format("the kept hierarchy did not converge ({} iterations); rebuilt", iterations);
    x = x.allFinite() ? Vector(x) : x0;
  }
  if (!x.allFinite()) {
    stats.info = SolveInfo::non_finite;
    stats.relative_residual = std::numeric_limits<double>::quiet_NaN();
    return stats;
  }
  stats.info = stats.relative_residual <= options.tolerance ? SolveInfo::converged : SolveInfo::not_converged;
  return stats;
}

namespace {

void build(AmgHierarchy::State& s, const SparseMatrix& rows, const Vector& b, const Vector& x, long first_row,
           long n_global, const SolveOptions& options) {
  HypreObjects& h = s.h;
  h.kind = options.kind;
  const long n = rows.rows();
  const int max_iterations = std::min(options.max_iterations, options.amg.max_iterations);
  s.first_row = first_row;
  s.n_global = n_global;
  s.outer.assign(rows.outerIndexPtr(), rows.outerIndexPtr() + n + 1);
  s.inner.assign(rows.innerIndexPtr(), rows.innerIndexPtr() + rows.nonZeros());
  if (!rows.isCompressed()) s.outer.clear();  // never the same layout: compare() needs compressed rows

  const auto lo = static_cast<HYPRE_BigInt>(first_row), hi = static_cast<HYPRE_BigInt>(first_row + n - 1);
  LIQUID_HYPRE(HYPRE_IJMatrixCreate(MPI_COMM_WORLD, lo, hi, lo, hi, &h.A));
  LIQUID_HYPRE(HYPRE_IJMatrixSetObjectType(h.A, HYPRE_PARCSR));
  // hypre splits a row range into a diagonal block (columns in the rank's range) and the rest.
  std::vector<HYPRE_Int> diag(n, 0), offd(n, 0);
  s.ncols.assign(n, 0);
  s.row_ids.resize(n);
  s.cols.resize(rows.nonZeros());
  s.values.resize(rows.nonZeros());
  long k = 0;
  for (long i = 0; i < n; ++i) {
    s.row_ids[i] = static_cast<HYPRE_BigInt>(first_row + i);
    for (SparseMatrix::InnerIterator it(rows, i); it; ++it, ++k) {
      s.cols[k] = static_cast<HYPRE_BigInt>(it.col());
      s.values[k] = it.value();
      ++s.ncols[i];
      (it.col() >= first_row && it.col() < first_row + n ? diag[i] : offd[i])++;
    }
  }
  LIQUID_HYPRE(HYPRE_IJMatrixSetDiagOffdSizes(h.A, diag.data(), offd.data()));
  LIQUID_HYPRE(HYPRE_IJMatrixInitialize(h.A));
  LIQUID_HYPRE(HYPRE_IJMatrixSetValues(h.A, static_cast<HYPRE_Int>(n), s.ncols.data(), s.row_ids.data(),
                                       s.cols.data(), s.values.data()));
  LIQUID_HYPRE(HYPRE_IJMatrixAssemble(h.A));
  LIQUID_HYPRE(HYPRE_IJMatrixGetObject(h.A, reinterpret_cast<void**>(&s.A)));

  const auto make_vector = [&](HYPRE_IJVector& v, const Vector& values_in) {
    LIQUID_HYPRE(HYPRE_IJVectorCreate(MPI_COMM_WORLD, lo, hi, &v));
    LIQUID_HYPRE(HYPRE_IJVectorSetObjectType(v, HYPRE_PARCSR));
    s.set_vector(v, values_in);
    HYPRE_ParVector out = nullptr;
    LIQUID_HYPRE(HYPRE_IJVectorGetObject(v, reinterpret_cast<void**>(&out)));
    return out;
  };
  s.b = make_vector(h.b, b);
  s.x = make_vector(h.x, x);

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

  HYPRE_Solver krylov = nullptr;
  std::function<HYPRE_Int(HYPRE_ParCSRMatrix, HYPRE_ParVector, HYPRE_ParVector)> setup;
  switch (options.kind) {
    case SolverKind::bicgstab_amg:
      LIQUID_HYPRE(HYPRE_ParCSRBiCGSTABCreate(MPI_COMM_WORLD, &h.krylov));
      krylov = h.krylov;
      LIQUID_HYPRE(HYPRE_ParCSRBiCGSTABSetTol(krylov, options.tolerance));
      LIQUID_HYPRE(HYPRE_ParCSRBiCGSTABSetMaxIter(krylov, max_iterations));
      LIQUID_HYPRE(HYPRE_ParCSRBiCGSTABSetPrecond(krylov, HYPRE_BoomerAMGSolve, HYPRE_BoomerAMGSetup, h.amg));
      setup = [krylov](auto M, auto f, auto u) { return HYPRE_ParCSRBiCGSTABSetup(krylov, M, f, u); };
      s.solve = [&s, krylov] { return HYPRE_ParCSRBiCGSTABSolve(krylov, s.A, s.b, s.x); };
      s.count = [krylov] {
        HYPRE_Int it = 0;
        HYPRE_ParCSRBiCGSTABGetNumIterations(krylov, &it);
        return it;
      };
      break;
    case SolverKind::gmres_amg:
      LIQUID_HYPRE(HYPRE_ParCSRGMRESCreate(MPI_COMM_WORLD, &h.krylov));
      krylov = h.krylov;
      LIQUID_HYPRE(HYPRE_ParCSRGMRESSetKDim(krylov, a.gmres_restart));
      LIQUID_HYPRE(HYPRE_ParCSRGMRESSetTol(krylov, options.tolerance));
      LIQUID_HYPRE(HYPRE_ParCSRGMRESSetMaxIter(krylov, max_iterations));
      LIQUID_HYPRE(HYPRE_ParCSRGMRESSetPrecond(krylov, HYPRE_BoomerAMGSolve, HYPRE_BoomerAMGSetup, h.amg));
      setup = [krylov](auto M, auto f, auto u) { return HYPRE_ParCSRGMRESSetup(krylov, M, f, u); };
      s.solve = [&s, krylov] { return HYPRE_ParCSRGMRESSolve(krylov, s.A, s.b, s.x); };
      s.count = [krylov] {
        HYPRE_Int it = 0;
        HYPRE_ParCSRGMRESGetNumIterations(krylov, &it);
        return it;
      };
      break;
    default:
      LIQUID_HYPRE(HYPRE_ParCSRPCGCreate(MPI_COMM_WORLD, &h.krylov));
      krylov = h.krylov;
      LIQUID_HYPRE(HYPRE_ParCSRPCGSetTwoNorm(krylov, 1));
      LIQUID_HYPRE(HYPRE_ParCSRPCGSetTol(krylov, options.tolerance));
      LIQUID_HYPRE(HYPRE_ParCSRPCGSetMaxIter(krylov, max_iterations));
      LIQUID_HYPRE(HYPRE_ParCSRPCGSetPrecond(krylov, HYPRE_BoomerAMGSolve, HYPRE_BoomerAMGSetup, h.amg));
      setup = [krylov](auto M, auto f, auto u) { return HYPRE_ParCSRPCGSetup(krylov, M, f, u); };
      s.solve = [&s, krylov] { return HYPRE_ParCSRPCGSolve(krylov, s.A, s.b, s.x); };
      s.count = [krylov] {
        HYPRE_Int it = 0;
        HYPRE_ParCSRPCGGetNumIterations(krylov, &it);
        return it;
      };
      break;
  }
  check(setup(s.A, s.b, s.x), "the Krylov solver's setup (BoomerAMG's hierarchy)");
}

}  // namespace

SolveStats amg_solve_rows(const SparseMatrix& rows, const Vector& b, Vector& x, long first_row, long n_global,
                          const SolveOptions& options) {
  SolveOptions once = options;
  once.amg.reuse_factor = 0.0;
  return AmgHierarchy(once).solve_rows(rows, b, x, first_row, n_global);
}

}  // namespace liquid::linalg
