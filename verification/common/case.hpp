#pragma once
// The verification case interface. A case is one literate .cpp file in verification/cases/ that
// states its problem at the top, runs its study, fills tables, checks its own expectations and
// registers itself with LIQUID_VERIFICATION_CASE.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "common/json.hpp"
#include "common/table.hpp"
#include "liquid/linalg/solver.hpp"
#include "liquid/mac/laplacian.hpp"
#include "liquid/mac/stencil.hpp"

namespace liquid::verification {

/// A study option of `liquid-verify run`; a case declares those it accepts (CaseInfo::accepts), and
/// `run` refuses any other with exit 2.
enum class Option {
  levels,
  max_jump,
  solver,
  stencil,
  rbf_exponent,
  rbf_degree,
  gradient_degree,
  stencil_growth,
  ring_cap,
  gradient_cap,
  rows,
  nullspace,
  tolerance,
  algebraic,
  perturb,
  trees,
  methods,
  seed,
  particles,
  radius,
  aspect,
  merge_wait,
  duration,
  sizes,
  resample_travel,
  reference,
  band
};
using OptionSet = std::vector<Option>;
/// The command-line flag of an option ("--max-jump").
const char* flag_of(Option option);

/// `--sizes D:N[,N...]`: one dimension and the divisions (spacings a/N) a size study runs.
struct SizeList {
  int dim = 0;
  std::vector<int> divisions;
};

/// How the later rows of a convergence study get their trees.
enum class RowProtocol {
  refine,   ///< split every cell of the first row's tree once more per row (the paper's protocol)
  rebuild,  ///< a fresh tree per row by the study's rule (band widths in finest cells shrink with h)
};
const char* to_string(RowProtocol rows);

/// How a Poisson study keeps the linear solver's (algebraic) error out of the errors it reports.
/// Each row's solve is continued from its solution to a 100x tighter relative residual; the change
/// of p (and of dp/dn) over the row's error is the row's "algebraic share".
enum class AlgebraicControl {
  tighten,  ///< continue until the share is below the bound (or the tolerance reaches 1e-15); report the last
  check,    ///< continue once, report the share, keep the errors of the solve at the given tolerance
  off,      ///< no second solve: the errors are those at the given tolerance, the share unmeasured
};
const char* to_string(AlgebraicControl control);

/// How a study fixes the constant of a pure Neumann problem.
enum class NullspaceChoice {
  pin,        ///< pin one unknown, then spread the discrete incompatibility as a uniform source
              ///< (mac::make_compatible)
  pin_point,  ///< pin one unknown and leave the incompatibility at it, a point source (the paper's way)
  zero_mean,  ///< the bordered zero-mean system
};
const char* to_string(NullspaceChoice choice);

/// A deliberately degraded scheme, to watch the gate fail.
enum class Perturbation { first_order };

/// Base levels A:B of a study's rows.
struct LevelRange {
  int first = 0, last = 0;
};

/// Typed options of `liquid-verify run`, parsed and range-checked once in main; a case reads those it
/// declared.
struct CaseOptions {
  std::optional<LevelRange> levels;           ///< --levels A:B
  std::optional<int> max_jump;                ///< --max-jump K (>= 1)
  std::optional<linalg::SolverKind> solver;   ///< --solver NAME
  std::optional<mac::StencilRule> stencil;    ///< --stencil RULE
  std::optional<int> rbf_exponent;            ///< --rbf-exponent S: PHS r^S of the Laplacian rows
  std::optional<int> rbf_degree;              ///< --rbf-degree M: their polynomial degree
  std::optional<int> gradient_degree;         ///< --gradient-degree M: degree of face gradients
  std::optional<double> stencil_growth;       ///< --stencil-growth G
  std::optional<double> ring_cap;             ///< --ring-cap C: ring stencils keep at most C x that size
  std::optional<double> gradient_cap;         ///< --gradient-cap C: the same for face gradients only
  std::optional<RowProtocol> rows;            ///< --rows refine|rebuild
  std::optional<NullspaceChoice> nullspace;   ///< --nullspace pin|pin-point|zero-mean
  std::optional<double> tolerance;            ///< --tolerance T: the solver's relative residual
  std::optional<AlgebraicControl> algebraic;  ///< --algebraic tighten|check|off
  std::optional<Perturbation> perturb;        ///< --perturb first-order
  std::optional<std::string> trees_dir;       ///< --trees DIR: write the trees checked
  std::vector<std::string> methods;           ///< --methods A,B: run only these rows (empty: all)
  std::optional<std::string> reference;       ///< --reference-method M: a flow study's reference
  std::optional<int> band;                    ///< --band K: a flow study's adaptive rows, finest-level hops
  std::optional<std::uint64_t> seed;          ///< --seed N: the random draws of a sampled problem
  std::optional<long> particles;              ///< --particles N: the size of a sampled problem
  std::optional<double> radius;               ///< --radius R: a sampled sphere's radius (domain units)
  std::optional<double> aspect;               ///< --aspect A: a sampled box's width over its height
  std::optional<int> merge_wait;              ///< --merge-wait N: SPH, passes before a split's children merge
  std::optional<double> duration;             ///< --duration T: simulated seconds of a long run
  std::optional<SizeList> sizes;              ///< --sizes D:N,N: a size study's dimension and divisions
  std::optional<double> resample_travel;      ///< --resample-travel S: SPH, spacings travelled between passes
  long max_cells = 0;                         ///< budget: refuse rows above this many cells (0: no limit)
  bool full = false;                          ///< the full suite's extent rather than the quick one
};

/// The budget's unit. A study's cost is counted in cells of kCellBytes: peak memory measured on
/// the Poisson studies was about 350 B a tree cell, plus 570 B (2D) or 2.4 kB (3D) for each cell
/// that holds an unknown (its matrix row, RBF-FD weights and ILUT factors); the figures used carry
/// a quarter more (kUnknownCells).
inline constexpr double kCellBytes = 512.0;
/// An unknown's extra memory in budget cells: 768 B in 2D, 3 kB in 3D.
template <int Dim>
inline constexpr double kUnknownCells = Dim == 2 ? 1.5 : 6.0;
/// What a row of `cells` cells and `unknowns` unknowns costs, in budget cells.
template <int Dim>
constexpr double budget_cost(double cells, double unknowns) {
  return cells + kUnknownCells<Dim> * unknowns;
}
/// The help text of --max-cells (liquid-verify run and liquid-verify poisson).
inline constexpr const char* kMaxCellsHelp =
    "refuse rows estimated above N cells of 512 B, an unknown counting 1.5 cells more in 2D, 6 in 3D "
    "(default: half the memory)";

/// Every option of a Poisson convergence study (run_poisson_study reads them all).
inline const OptionSet poisson_study_options{
    Option::levels,          Option::max_jump,       Option::solver,
    Option::stencil,         Option::rbf_exponent,   Option::rbf_degree,
    Option::gradient_degree, Option::stencil_growth, Option::ring_cap,
    Option::gradient_cap,    Option::rows,           Option::nullspace,
    Option::tolerance,       Option::algebraic,      Option::perturb};
inline const OptionSet no_options{};

/// A figure the accuracy gate compares with its accepted value in reference/<case>.toml.
struct GateFigure {
  enum class Kind { error, order, iterations, count };
  std::string name;  ///< unique within the case, e.g. "level 6 err p"
  Kind kind;
  double value;
};

/// One curve of a case's "series" (the report plots each group on log-log axes): points (x, y),
/// by default h against an error; x_label / y_label name other axes (seconds against error, say).
Json series_entry(const std::string& group, const std::string& label, const std::vector<double>& x,
                  const std::vector<double>& y, const std::string& x_label = "",
                  const std::string& y_label = "");

struct CaseResult {
  bool passed = true;
  std::vector<Table> tables;
  std::vector<std::string> failures;  ///< every missed expectation, one sentence each
  std::vector<std::string> notes;     ///< what a reader should know about the numbers
  Json fields = Json::object();       ///< extra top-level JSON fields ("order", "order_grad", ...)
  std::vector<GateFigure> gate;       ///< figures the accuracy gate checks against reference/
  std::vector<std::string> warnings;  ///< numbers a reader should doubt (pre-asymptotic rows, ...)
  bool asserted = true;               ///< false: the case checked nothing (a study without expectations)

  /// Records an expectation; a false one fails the case with `what`.
  void expect(bool ok, const std::string& what) {
    if (!ok) {
      passed = false;
      failures.push_back(what);
    }
  }

  /// Takes in another part of the same case (its 3D half, say): its tables, failures, notes and
  /// warnings follow this one's, its gate figures are renamed `prefix` + name. `fields` stay this
  /// one's.
  void append(CaseResult&& other, const std::string& prefix = "") {
    passed = passed && other.passed;
    asserted = asserted || other.asserted;
    for (auto& t : other.tables) tables.push_back(std::move(t));
    for (auto& f : other.failures) failures.push_back(std::move(f));
    for (auto& n : other.notes) notes.push_back(std::move(n));
    for (auto& w : other.warnings) warnings.push_back(std::move(w));
    for (auto& g : other.gate) gate.push_back({prefix + g.name, g.kind, g.value});
  }
};

struct CaseInfo {
  std::string name;
  std::string summary;  ///< one line for `liquid-verify list`
  bool quick = true;    ///< part of the quick suite (CI) as well as the full one
  std::function<CaseResult(const CaseOptions&)> run;
  OptionSet accepts = no_options;  ///< the options the case reads; `run` refuses any other
  bool perturbable() const;        ///< accepts Option::perturb (the gate's --perturb)
  bool accepts_option(Option o) const;
};

/// All registered cases, in name order.
std::vector<CaseInfo>& case_registry();
const CaseInfo* find_case(const std::string& name);
/// A registered case's family: the folder under verification/cases/ of the file that registered it.
const std::string& case_family(const std::string& name);

struct CaseRegistrar {
  /// `file` is the registering source file; its folder under cases/ names the case's family.
  CaseRegistrar(const char* file, CaseInfo info);
};

}  // namespace liquid::verification

#define LIQUID_VERIFICATION_CASE_CAT2(a, b) a##b
#define LIQUID_VERIFICATION_CASE_CAT(a, b) LIQUID_VERIFICATION_CASE_CAT2(a, b)
/// Registers a case: LIQUID_VERIFICATION_CASE({"name", "summary", true, run_function});
#define LIQUID_VERIFICATION_CASE(...)                                                                    \
  static const ::liquid::verification::CaseRegistrar LIQUID_VERIFICATION_CASE_CAT(registrar_, __LINE__)( \
      __FILE__, __VA_ARGS__)
