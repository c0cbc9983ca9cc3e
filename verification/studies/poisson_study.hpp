#pragma once
// The convergence-study driver shared by the Poisson cases: for each level of a study, build the
// adaptive tree, assemble, solve, measure the L-inf errors of p (at unknown cells) and of the
// normal derivative (at faces between two unknowns, against the exact one at the face centre),
// then repeat on a uniform grid of the same finest h, so error and time sit side by side.

#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "common/case.hpp"
#include "liquid/linalg/solver.hpp"
#include "liquid/mac/poisson.hpp"
#include "liquid/tree/cell_graph.hpp"
#include "support/manufactured.hpp"

namespace liquid::verification {

/// Errors below this are at the level of the solver's tolerance (1e-10) and of round-off: a study
/// whose errors all sit below it reproduces p exactly and has no order to fit.
inline constexpr double exact_error_level = 1e-9;

/// The scheme is second order in p and in dp/dn. A study without floors of its own is judged by
/// these (a fitted order at or above them "converges"); the paper cases set 1.9 and 1.8.
inline constexpr double kSchemeOrder = 2.0;
inline constexpr double kSchemeOrderFloor = 1.8, kSchemeGradOrderFloor = 1.6;
/// Two step orders closer than this are settled; farther apart, the study is still pre-asymptotic.
inline constexpr double kSettledSpread = 0.3;
/// A finest-row error below this fraction of the solution's scale (max |p|, max |dp/dn|) is at the
/// round-off floor of a double-precision solve.
inline constexpr double kRoundoffFraction = 1e-8;

template <int Dim>
struct PoissonStudy {
  Box<Dim> domain;
  std::function<double(const Vec<Dim>&)> exact;       ///< p
  std::function<Vec<Dim>(const Vec<Dim>&)> gradient;  ///< grad p
  std::function<double(const Vec<Dim>&)> laplacian;   ///< f = Lap p
  levelset::Function<Dim> levelset;                   ///< empty: Neumann walls
  bool dirichlet_walls = false;                       ///< walls carry p (else Neumann)
  /// The adaptive tree of one row, by its base level.
  std::function<tree::CellGraph<Dim>(int level, const tree::CellGraphOptions<Dim>& options)> make_tree;
  /// rebuild: make_tree per row, so band widths counted in finest cells halve with h.
  /// refine: only the first row calls make_tree; every later row is that tree with each leaf split
  /// once more (the paper's recursive subdivision), so the refined regions and the T-junctions stay
  /// where they are and each row is a true refinement of the one before.
  RowProtocol rows = RowProtocol::refine;
  int level_min = 3, level_max = 5;  ///< base levels of the rows (CaseOptions::level_* override)
  int finest_offset = 2;             ///< finest level = base level + this
  int max_jump = 2;
  mac::PoissonOptions discretisation;
  /// With discretisation.nullspace = pin: spread the discrete incompatibility as a uniform source
  /// (a second solve, mac::make_compatible) rather than leave it at the pinned cell as a point source
  /// (why: docs/findings/poisson-trust.md).
  bool spread_pin_source = true;
  linalg::SolveOptions solver{linalg::SolverKind::bicgstab_ilut, 1e-10, 20000};
  /// The solver's error kept below `algebraic_bound` of each row's error (see AlgebraicControl).
  AlgebraicControl algebraic = AlgebraicControl::tighten;
  double algebraic_bound = 0.01;
  double order_floor = 1.9, order_grad_floor = 1.8;
  std::optional<double> error_ceiling;  ///< the finest row's L-inf error of p must not exceed it
  bool asserted = true;                 ///< false: a user's study without expectations
  long max_cells = 0;  ///< refuse rows estimated above this many cells (kCellBytes each, unknowns counted as
                       ///< kUnknownCells more; 0: no limit)
  long uniform_limit = 300000;  ///< skip the uniform comparison rows above this many cells (quick tier)

  /// Takes p, grad p and f = Lap p from a manufactured solution.
  void use(const support::Manufactured<Dim>& m) {
    exact = m.p;
    gradient = m.gradient;
    laplacian = m.laplacian;
  }
};

/// Runs the study, fills the tables, records expectations and the top-level fields
/// ("order", "order_grad", "order_dofs", "series"). Options from the command line override the
/// study's levels, jump limit, solver and scheme; a study refuses rows whose finest tree would
/// exceed options.max_cells before it builds anything that large.
template <int Dim>
CaseResult run_poisson_study(PoissonStudy<Dim> study, const CaseOptions& options);

/// The tree of the row at base level `level`; `first` is make_tree(level_min) (used when the study
/// refines its first row).
template <int Dim>
tree::CellGraph<Dim> row_tree(const PoissonStudy<Dim>& study, const tree::CellGraph<Dim>& first, int level,
                              const tree::CellGraphOptions<Dim>& options);

/// One solve and its errors (also used by the unit tests and the hard cases).
struct PoissonRun {
  long n_cells = 0, n_unknowns = 0;
  double h = 0.0;
  double err_p = 0.0, err_grad = 0.0;
  double assembly_seconds = 0.0, solve_seconds = 0.0;
  linalg::SolveStats solve;  ///< the solve at the study's tolerance
  mac::AssemblyStats assembly;
  /// The algebraic part of the errors reported, as a share: d = the larger of |x - x'|_inf / err p
  /// and |dp/dn(x) - dp/dn(x')|_inf / err dp/dn (each error floored at kRoundoffFraction of the
  /// solution's scale), x' the solve at 100x x's tolerance. check: d, an
  /// upper bound for x. tighten, one round: d (x' is reported, its share is below d); after k > 1
  /// rounds: d_k^2 / d_(k-1), the distances' rate of fall carried one round on. NaN: not measured
  /// (off, the direct solver).
  double algebraic_share = std::numeric_limits<double>::quiet_NaN();
  /// The continued solves stopped improving (a 100x tighter solve moved the solution more than a
  /// tenth as much as the one before, or stalled): what is left of the share is the solve's round-off.
  bool solve_at_roundoff = false;
  double tolerance = 0.0;        ///< the relative residual the reported solution was solved to
  double control_seconds = 0.0;  ///< the continued solves (setup included)
  /// The constant a pinned system's source was shifted by to make it compatible (0: not pinned, or
  /// the point source kept): the discrete incompatibility per unknown.
  double incompatibility = 0.0;
  int control_iterations = 0;
  /// Largest |p| on the unknowns and largest |dp/dn| on the faces measured: the scales a round-off
  /// floor is judged against.
  double p_scale = 0.0, grad_scale = 0.0;
  int max_level_jump = 0;
  /// Where the error lives: per cell level, the unknowns there and the L-inf error of p on them.
  std::vector<std::tuple<int, long, double>> err_by_level;
  std::string worst_p;     ///< where the L-inf of p is reached: centre, level, distance to S in cells
  std::string worst_grad;  ///< where the L-inf of dp/dn is reached: face centre, side levels, FD or RBF-FD
};

/// Why a study's fitted order is what it is, from its rows alone: one line for p and one for dp/dn.
struct OrderDiagnosis {
  /// converges, exact, round-off, algebraic, pre-asymptotic, above-order, too-few-rows, loss-of-order
  std::string p_kind, grad_kind;
  std::string p, grad;  ///< the sentences
  std::string line() const;
};

/// Classifies the orders of a study's adaptive rows: `floor_p` and `floor_grad` are the orders that
/// count as the scheme's (2 nominal), `bound` the algebraic share allowed; `levels` the rows' base levels.
OrderDiagnosis diagnose_orders(const std::vector<int>& levels, const std::vector<PoissonRun>& runs,
                               double floor_p, double floor_grad, double bound);

/// The rows of `study` at base levels level_min..level_max (trees by row_tree, jumps up to
/// study.max_jump), solved in order. A row whose solver does not converge is recorded in `result`
/// under `label` and ends the series. `on_row(level, run)`, when given, sees each converged row as
/// soon as it is solved (run_poisson_study fills its tables and uniform rows there).
template <int Dim>
std::vector<PoissonRun> solve_rows(const PoissonStudy<Dim>& study, CaseResult& result,
                                   const std::string& label,
                                   const std::function<void(int, const PoissonRun&)>& on_row = {});

template <int Dim>
PoissonRun solve_poisson(const tree::CellGraph<Dim>& graph, const PoissonStudy<Dim>& study);

/// The mac problem of a study: f, the interface and its values, the walls, the pin.
template <int Dim>
mac::PoissonProblem<Dim> poisson_problem(const PoissonStudy<Dim>& study);

/// L-inf error of p over the unknowns of `system` for the solution x (the volume-weighted mean
/// difference removed for zero-mean systems).
template <int Dim>
double max_error(const tree::CellGraph<Dim>& graph, const PoissonStudy<Dim>& study,
                 const mac::PoissonSystem<Dim>& system, const linalg::Vector& x);

}  // namespace liquid::verification
