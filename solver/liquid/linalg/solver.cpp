#include "liquid/linalg/solver.hpp"

#include <cstdint>
#include <cstring>

#include <fmt/format.h>
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseLU>

#include "liquid/core/error.hpp"
#include "liquid/core/timer.hpp"
#include "liquid/linalg/amg.hpp"

namespace liquid::linalg {

namespace {
struct Named {
  const char* name;
  SolverKind kind;
};
constexpr Named kNames[] = {{"bicgstab-jacobi", SolverKind::bicgstab_jacobi},
                            {"bicgstab-ilut", SolverKind::bicgstab_ilut},
                            {"cg-ic", SolverKind::cg_ic},
                            {"cg-jacobi", SolverKind::cg_jacobi},
                            {"direct", SolverKind::direct},
                            {"bicgstab-amg", SolverKind::bicgstab_amg},
                            {"gmres-amg", SolverKind::gmres_amg},
                            {"cg-amg", SolverKind::cg_amg}};
}  // namespace

std::vector<std::string> solver_names() {
  std::vector<std::string> out;
  for (const auto& n : kNames) out.emplace_back(n.name);
  return out;
}

SolverKind parse_solver(const std::string& name) {
  for (const auto& n : kNames)
    if (name == n.name) return n.kind;
  throw Error(fmt::format("unknown solver '{}'; choose one of: {}", name, fmt::join(solver_names(), ", ")));
}

bool needs_symmetric(SolverKind kind) {
  return kind == SolverKind::cg_jacobi || kind == SolverKind::cg_ic || kind == SolverKind::cg_amg;
}

bool uses_amg(SolverKind kind) {
  return kind == SolverKind::bicgstab_amg || kind == SolverKind::gmres_amg || kind == SolverKind::cg_amg;
}

SolverKind nonsymmetric_counterpart(SolverKind kind) {
  switch (kind) {
    case SolverKind::cg_jacobi:
      return SolverKind::bicgstab_jacobi;
    case SolverKind::cg_ic:
      return SolverKind::bicgstab_ilut;
    case SolverKind::cg_amg:
      return SolverKind::bicgstab_amg;
    default:
      return kind;
  }
}

std::string to_string(SolverKind kind) {
  for (const auto& n : kNames)
    if (n.kind == kind) return n.name;
  return "unknown";
}

const char* to_string(SolveInfo info) {
  switch (info) {
    case SolveInfo::converged:
      return "converged";
    case SolveInfo::not_converged:
      return "not_converged";
    case SolveInfo::setup_failed:
      return "setup_failed";
    case SolveInfo::non_finite:
      return "non_finite";
  }
  return "unknown";
}

std::string SolveStats::describe() const {
  return fmt::format(
      "{} {}: {} unknowns, {} iterations, relative residual {:.3e}, setup {:.3f} s, solve {:.3f} s{}", solver,
      to_string(info), n_unknowns, iterations, relative_residual, setup_seconds, solve_seconds,
      note.empty() ? "" : " (" + note + ")");
}

namespace {

double true_residual(const SparseMatrix& A, const Vector& b, const Vector& x) {
  const double nb = b.norm();
  const double nr = (b - A * x).norm();
  return nb > 0.0 ? nr / nb : nr;
}

/// A fingerprint of a matrix object and its entries (the address, the pattern and the values'
/// bits, mixed a 64-bit word at a time): a solver keeps its factorisation for the next solve only
/// when it matches.
std::uint64_t matrix_key(const SparseMatrix& A) {
  std::uint64_t h = 0x9E3779B97F4A7C15ull;
  const auto mix = [&h](std::uint64_t w) {
    h ^= w + 0x9E3779B97F4A7C15ull + (h << 6) + (h >> 2);
    h *= 0xFF51AFD7ED558CCDull;
  };
  mix(reinterpret_cast<std::uintptr_t>(&A));
  mix(static_cast<std::uint64_t>(A.rows())), mix(static_cast<std::uint64_t>(A.cols()));
  mix(static_cast<std::uint64_t>(A.nonZeros()));
  for (Eigen::Index k = 0; k < A.outerSize(); ++k)
    for (SparseMatrix::InnerIterator it(A, k); it; ++it) {
      std::uint64_t bits = 0;
      const double v = it.value();
      std::memcpy(&bits, &v, sizeof bits);
      mix((static_cast<std::uint64_t>(k) << 32) ^ static_cast<std::uint64_t>(it.index()));
      mix(bits);
    }
  return h;
}

// Iterative solvers share everything but the Eigen type; CG variants read the lower triangle.
template <class EigenSolver>
class Iterative final : public LinearSolver {
 public:
  explicit Iterative(SolveOptions options) : options_(options) {}
  static constexpr int max_restarts = 8;
  static constexpr int max_breakdowns = 2;

  /// The diagonal, infinite where it is zero (the Jacobi step of a breakdown leaves those entries).
  static Vector diagonal(const SparseMatrix& A) {
    Vector d = A.diagonal();
    for (Eigen::Index i = 0; i < d.size(); ++i)
      if (d[i] == 0.0) d[i] = std::numeric_limits<double>::infinity();
    return d;
  }

  SolveStats solve(const SparseMatrix& A, const Vector& b, Vector& x) override {
    SolveStats stats;
    stats.solver = to_string(options_.kind);
    stats.n_unknowns = A.rows();
    LIQUID_VERIFY(A.rows() == A.cols() && A.rows() == b.size(),
                  "{}: matrix {}x{} and right-hand side {} differ", stats.solver, A.rows(), A.cols(),
                  b.size());
    if (!b.allFinite()) {
      stats.info = SolveInfo::non_finite;
      return stats;
    }
    if (x.size() != b.size()) x = Vector::Zero(b.size());
    // A zero right-hand side has the zero solution: no Krylov step (its recurrences divide by the
    // residual's norm and break down).
    if (b.squaredNorm() == 0.0) {
      x.setZero();
      stats.relative_residual = 0.0;
      stats.info = SolveInfo::converged;
      return stats;
    }
    Stopwatch watch;
    const std::uint64_t key = matrix_key(A);
    if (!solver_ || key != key_) {
      solver_ = std::make_unique<EigenSolver>();
      key_ = key;
      if constexpr (requires { solver_->preconditioner().setDroptol(1.0); }) {
        solver_->preconditioner().setDroptol(options_.ilut_droptol);
        solver_->preconditioner().setFillfactor(options_.ilut_fill);
      }
      solver_->compute(A);
      if (solver_->info() != Eigen::Success) {
        solver_.reset();
        stats.setup_seconds = watch.seconds();
        stats.info = SolveInfo::setup_failed;
        return stats;
      }
    } else {
      stats.hierarchy_reused = true;
    }
    EigenSolver& solver = *solver_;
    solver.setTolerance(options_.tolerance);
    solver.setMaxIterations(options_.max_iterations);
    stats.setup_seconds = watch.seconds();
    watch.restart();
    // A guess that already meets the tolerance is the answer (a continued solve started at the
    // solution would only meet a zero residual, where the recurrences break down).
    stats.relative_residual = true_residual(A, b, x);
    if (stats.relative_residual <= options_.tolerance) {
      stats.solve_seconds = watch.seconds();
      stats.info = SolveInfo::converged;
      return stats;
    }
    // Krylov recurrences drift from the true residual; when the solver stops on its own estimate
    // short of the true one, restart from the current iterate (a few times at most).
    int budget = options_.max_iterations;
    int breakdowns = 0;
    for (int restart = 0; restart <= max_restarts && budget > 0; ++restart) {
      solver.setMaxIterations(budget);
      Vector result = solver.solveWithGuess(b, x);
      stats.iterations += static_cast<int>(solver.iterations());
      budget -= static_cast<int>(solver.iterations());
      if (!result.allFinite()) {
        // A breakdown (0/0 in the recurrences: BiCGSTAB's shadow residual orthogonal to A p, met
        // for instance when b is one unit vector). Restart from the last finite iterate moved by
        // one Jacobi step, which changes the Krylov space, a few times at most.
        if (++breakdowns <= max_breakdowns) {
          const Vector r = b - A * x;
          x += r.cwiseQuotient(diagonal(A));
          stats.relative_residual = true_residual(A, b, x);
          if (x.allFinite()) continue;
        }
        stats.solve_seconds = watch.seconds();
        stats.info = SolveInfo::non_finite;
        return stats;
      }
      x = std::move(result);
      stats.relative_residual = true_residual(A, b, x);
      if (stats.relative_residual <= options_.tolerance || solver.iterations() == 0) break;
    }
    stats.solve_seconds = watch.seconds();
    stats.info =
        stats.relative_residual <= options_.tolerance ? SolveInfo::converged : SolveInfo::not_converged;
    return stats;
  }

  bool set_tolerance(double tolerance) override {
    options_.tolerance = tolerance;
    return true;
  }

 private:
  SolveOptions options_;
  std::unique_ptr<EigenSolver> solver_;  ///< holds a reference to the matrix its key names
  std::uint64_t key_ = 0;
};

/// The AMG solvers on one process: every row on this rank (see amg.hpp for the distributed call),
/// the hierarchy kept for the next solve of a matrix with the same layout.
class Amg final : public LinearSolver {
 public:
  // MPI starts here (hypre needs it, even on one rank), not inside the first solve's timing.
  explicit Amg(SolveOptions options) : options_(options), hierarchy_(options) { ensure_mpi(); }
  SolveStats solve(const SparseMatrix& A, const Vector& b, Vector& x) override {
    LIQUID_VERIFY(A.rows() == A.cols() && A.rows() == b.size(),
                  "{}: matrix {}x{} and right-hand side {} differ", to_string(options_.kind), A.rows(),
                  A.cols(), b.size());
    LIQUID_VERIFY(mpi_size() == 1,
                  "{}: {} MPI ranks share this solve; a distributed solve passes each rank's rows to "
                  "amg_solve_rows()",
                  to_string(options_.kind), mpi_size());
    return hierarchy_.solve_rows(A, b, x, 0, A.rows());
  }

 private:
  SolveOptions options_;
  AmgHierarchy hierarchy_;
};

class Direct final : public LinearSolver {
 public:
  SolveStats solve(const SparseMatrix& A, const Vector& b, Vector& x) override {
    SolveStats stats;
    stats.solver = "direct";
    stats.n_unknowns = A.rows();
    LIQUID_VERIFY(A.rows() == A.cols() && A.rows() == b.size(),
                  "direct: matrix {}x{} and right-hand side {} differ", A.rows(), A.cols(), b.size());
    Stopwatch watch;
    const std::uint64_t key = matrix_key(A);
    if (!lu_ || key != key_) {
      lu_ = std::make_unique<Eigen::SparseLU<Eigen::SparseMatrix<double, Eigen::ColMajor>>>();
      key_ = key;
      Eigen::SparseMatrix<double, Eigen::ColMajor> Ac = A;
      lu_->compute(Ac);
      if (lu_->info() != Eigen::Success) {
        lu_.reset();
        stats.setup_seconds = watch.seconds();
        stats.info = SolveInfo::setup_failed;
        return stats;
      }
    } else {
      stats.hierarchy_reused = true;
    }
    stats.setup_seconds = watch.seconds();
    watch.restart();
    x = lu_->solve(b);
    stats.solve_seconds = watch.seconds();
    stats.iterations = 1;
    if (!x.allFinite()) {
      stats.info = SolveInfo::non_finite;
      return stats;
    }
    stats.relative_residual = true_residual(A, b, x);
    stats.info = stats.relative_residual < 1e-8 ? SolveInfo::converged : SolveInfo::not_converged;
    return stats;
  }
  /// The factorisation is exact: a tolerance changes nothing.
  bool set_tolerance(double) override { return true; }

 private:
  std::unique_ptr<Eigen::SparseLU<Eigen::SparseMatrix<double, Eigen::ColMajor>>> lu_;  ///< owns its copy
  std::uint64_t key_ = 0;
};

}  // namespace

std::unique_ptr<LinearSolver> make_solver(const SolveOptions& options) {
  LIQUID_VERIFY(options.tolerance > 0.0 && options.tolerance < 1.0,
                "solver tolerance must be in (0, 1), got {}", options.tolerance);
  LIQUID_VERIFY(options.ilut_droptol >= 0.0 && options.ilut_fill >= 1,
                "ILUT needs droptol >= 0 and fill >= 1, got {} and {}", options.ilut_droptol,
                options.ilut_fill);
  LIQUID_VERIFY(options.max_iterations > 0, "solver needs a positive iteration limit, got {}",
                options.max_iterations);
  const AmgOptions& a = options.amg;
  LIQUID_VERIFY(
      a.sweeps >= 1 && a.gmres_restart >= 1 && a.max_iterations >= 1 && a.aggressive_levels >= 0 &&
          a.max_interpolation_entries >= 0,
      "AMG needs sweeps, GMRES restart and iteration cap >= 1 and non-negative aggressive levels and "
      "interpolation entries (got {}, {}, {}, {}, {})",
      a.sweeps, a.gmres_restart, a.max_iterations, a.aggressive_levels, a.max_interpolation_entries);
  LIQUID_VERIFY(a.strength >= 0.0 && a.strength < 1.0, "AMG strength threshold {} is outside [0, 1)",
                a.strength);
  LIQUID_VERIFY(a.reuse_factor >= 0.0, "AMG reuse factor {} must be 0 (never keep the hierarchy) or positive",
                a.reuse_factor);
  using Jacobi = Eigen::DiagonalPreconditioner<double>;
  switch (options.kind) {
    case SolverKind::bicgstab_jacobi:
      return std::make_unique<Iterative<Eigen::BiCGSTAB<SparseMatrix, Jacobi>>>(options);
    case SolverKind::bicgstab_ilut:
      return std::make_unique<Iterative<Eigen::BiCGSTAB<SparseMatrix, Eigen::IncompleteLUT<double>>>>(
          options);
    case SolverKind::cg_ic:
      return std::make_unique<Iterative<Eigen::ConjugateGradient<
          SparseMatrix, Eigen::Lower | Eigen::Upper, Eigen::IncompleteCholesky<double, Eigen::Lower>>>>(
          options);
    case SolverKind::cg_jacobi:
      return std::make_unique<
          Iterative<Eigen::ConjugateGradient<SparseMatrix, Eigen::Lower | Eigen::Upper, Jacobi>>>(options);
    case SolverKind::direct:
      return std::make_unique<Direct>();
    case SolverKind::bicgstab_amg:
    case SolverKind::gmres_amg:
    case SolverKind::cg_amg:
      return std::make_unique<Amg>(options);
  }
  throw Error("unknown solver kind");
}

SolveStats solve(const SparseMatrix& A, const Vector& b, Vector& x, const SolveOptions& options) {
  return make_solver(options)->solve(A, b, x);
}

}  // namespace liquid::linalg
