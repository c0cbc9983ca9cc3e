#pragma once
// Sparse linear solvers for the pressure Poisson equation, behind one interface so that a
// distributed engine can sit behind it later. Every solve returns its statistics; not converging
// is a reported result (info, iterations, residual reached), never a silent one.

#include <memory>
#include <string>
#include <vector>

#include <Eigen/SparseCore>

namespace liquid::linalg {

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor>;
using Vector = Eigen::VectorXd;

enum class SolverKind {
  bicgstab_jacobi,  ///< the paper's: BiCGSTAB with a diagonal preconditioner
  bicgstab_ilut,    ///< BiCGSTAB with incomplete LU (threshold)
  cg_ic,            ///< conjugate gradients with incomplete Cholesky (symmetric matrices only)
  cg_jacobi,        ///< conjugate gradients with a diagonal preconditioner (symmetric only)
  direct,           ///< sparse LU, for checks
  bicgstab_amg,     ///< BiCGSTAB preconditioned by hypre's BoomerAMG (any matrix)
  gmres_amg,        ///< restarted GMRES preconditioned by BoomerAMG (any matrix)
  cg_amg,           ///< conjugate gradients preconditioned by BoomerAMG (symmetric only)
};

/// BoomerAMG's settings as a preconditioner (one V-cycle per application), hypre's codes. Without
/// aggressive coarsening the iteration count stays flat as the grid grows, at no extra time.
/// Why these defaults: docs/findings/amg.md.
struct AmgOptions {
  int coarsening = 10;                ///< 10 HMIS (hypre's default 6 is Falgout)
  int interpolation = 6;              ///< 6 extended+i
  int max_interpolation_entries = 4;  ///< per row of the interpolation
  int smoother = 8;                   ///< 8 l1-scaled symmetric hybrid Gauss-Seidel (CG needs symmetric)
  int sweeps = 1;
  double strength = 0.25;     ///< strong-connection threshold
  int aggressive_levels = 0;  ///< levels of aggressive coarsening at the top
  int gmres_restart = 30;
  /// At most this many Krylov iterations (or SolveOptions::max_iterations if fewer): AMG either
  /// converges in tens or stagnates, and a stagnating solve should fail fast (docs/findings/amg.md).
  int max_iterations = 500;
  /// A kept hierarchy (AmgHierarchy, the solvers of make_solver()) is rebuilt once a solve with it
  /// needs more than this many times the iterations of the solve that built it; 0: never kept.
  /// Why this default: docs/findings/amg.md.
  double reuse_factor = 1.5;
};

/// "bicgstab-jacobi", "bicgstab-ilut", "cg-ic", "cg-jacobi", "direct", "bicgstab-amg", "gmres-amg",
/// "cg-amg". Throws naming the choices.
SolverKind parse_solver(const std::string& name);
std::string to_string(SolverKind kind);
/// Whether `kind` is a conjugate-gradient solver, which needs a symmetric positive (semi)definite
/// matrix.
bool needs_symmetric(SolverKind kind);
/// Whether `kind` is preconditioned by algebraic multigrid.
bool uses_amg(SolverKind kind);
/// The BiCGSTAB solver with the preconditioner of a conjugate-gradient `kind` (`kind` itself for any
/// other): for a symmetric indefinite or nonsymmetric system.
SolverKind nonsymmetric_counterpart(SolverKind kind);
std::vector<std::string> solver_names();

struct SolveOptions {
  SolverKind kind = SolverKind::bicgstab_jacobi;
  double tolerance = 1e-10;  ///< relative residual |b - A x| / |b| to reach
  int max_iterations = 20000;
  // ILUT (bicgstab-ilut): entries below droptol * |row| are dropped, and at most fill * (row's
  // entries) are kept per factor row. Eigen's defaults (1e-12, 10) keep nearly everything, and the
  // factorisation then costs far more than the iterations it saves in 3D. Why: docs/findings/amg.md.
  double ilut_droptol = 1e-3;
  int ilut_fill = 10;
  AmgOptions amg{};
};

enum class SolveInfo { converged, not_converged, setup_failed, non_finite };
const char* to_string(SolveInfo info);

struct SolveStats {
  SolveInfo info = SolveInfo::converged;
  std::string solver;
  int iterations = 0;
  double relative_residual = 0.0;  ///< true |b - A x| / |b| after the solve
  double setup_seconds = 0.0;
  double solve_seconds = 0.0;
  long n_unknowns = 0;
  std::string note;  ///< what failed, when a setup failed (e.g. the hypre call and its error)
  /// The preconditioner was built for an earlier matrix of the same layout (AMG's kept hierarchy:
  /// setup_seconds is then only the copy of the new values).
  bool hierarchy_reused = false;

  bool converged() const { return info == SolveInfo::converged; }
  std::string describe() const;
};

class LinearSolver {
 public:
  virtual ~LinearSolver() = default;
  /// Solves A x = b; x holds the initial guess on entry (resized to zero if its size differs).
  /// The AMG solvers keep their hierarchy for the next call while A keeps its layout (see
  /// AmgOptions::reuse_factor): keep one solver for a sequence of related systems.
  virtual SolveStats solve(const SparseMatrix& A, const Vector& b, Vector& x) = 0;
  /// The relative residual later solves must reach. The Krylov solvers with ILUT, IC or Jacobi and
  /// the direct solver keep their factorisation for the next solve of the same matrix object with
  /// the same entries (setup_seconds is then the check alone), so a solve continued to a tighter
  /// tolerance, or a second right-hand side, costs its iterations only. Returns false where the
  /// solver cannot change it (a new solver is then needed).
  virtual bool set_tolerance(double tolerance) {
    (void)tolerance;
    return false;
  }
};

std::unique_ptr<LinearSolver> make_solver(const SolveOptions& options);

/// Convenience: make_solver(options)->solve(A, b, x).
SolveStats solve(const SparseMatrix& A, const Vector& b, Vector& x, const SolveOptions& options);

}  // namespace liquid::linalg
