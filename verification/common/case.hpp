#pragma once
// The verification case interface. A case is one literate .cpp file in verification/cases/ that
// states its problem at the top, runs its study, fills tables, checks its own expectations and
// registers itself with LIQUID_VERIFICATION_CASE.

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "json.hpp"
#include "table.hpp"

namespace liquid::verification {

/// Options a user may pass to `liquid-verify run`; a case reads those that apply to it.
struct CaseOptions {
  std::optional<int> level_min, level_max;  ///< --levels A:B
  std::optional<int> max_jump;              ///< --max-jump K
  std::optional<std::string> solver;        ///< --solver NAME
  std::optional<std::string> stencil;       ///< --stencil RULE (nearest, face-grown, ring)
  std::optional<std::string> perturb;       ///< --perturb first-order: a deliberately degraded scheme
  std::optional<int> rbf_exponent;          ///< --rbf-exponent S: PHS r^S of the RBF-FD Laplacian rows
  std::optional<int> rbf_degree;            ///< --rbf-degree M: their polynomial degree
  std::optional<int> gradient_degree;       ///< --gradient-degree M: degree of RBF-FD face gradients
  std::optional<double> stencil_growth;     ///< --stencil-growth G: RBF-FD stencils of G x terms + 1 nodes
  std::optional<std::string> rows;          ///< --rows rebuild|refine: how later rows' trees are made
  std::optional<std::string> nullspace;     ///< --nullspace pin|zero-mean: a pure Neumann system's fix
  std::optional<double> tolerance;          ///< --tolerance T: the solver's relative residual
  std::optional<std::string> trees_dir;     ///< --trees DIR: write the trees checked (HDF5 + XDMF)
  bool full = false;                        ///< the full suite's extent rather than the quick one
};

/// A figure the accuracy gate compares with its accepted value in reference/<case>.toml.
struct GateFigure {
  enum class Kind { error, order, iterations, count };
  std::string name;  ///< unique within the case, e.g. "level 6 err p"
  Kind kind;
  double value;
};

struct CaseResult {
  bool passed = true;
  std::vector<Table> tables;
  std::vector<std::string> failures;  ///< every missed expectation, one sentence each
  std::vector<std::string> notes;     ///< what a reader should know about the numbers
  Json fields = Json::object();       ///< extra top-level JSON fields ("order", "order_grad", ...)
  std::vector<GateFigure> gate;       ///< figures the accuracy gate checks against reference/

  /// Records an expectation; a false one fails the case with `what`.
  void expect(bool ok, const std::string& what) {
    if (!ok) {
      passed = false;
      failures.push_back(what);
    }
  }
};

struct CaseInfo {
  std::string name;
  std::string summary;  ///< one line for `liquid-verify list`
  bool quick = true;    ///< part of the quick suite (CI) as well as the full one
  std::function<CaseResult(const CaseOptions&)> run;
  bool writes_trees = false;  ///< honours CaseOptions::trees_dir
};

/// For a case that fixes its own scheme: throws, naming the first study option given (--perturb,
/// --solver, --max-jump, --stencil, --rows, --rbf-exponent, --rbf-degree, --gradient-degree,
/// --stencil-growth, --nullspace, --tolerance, and --levels when `levels_too`), as
/// "<case> does not take <flag>: <why>".
void refuse_study_options(const CaseOptions& options, const std::string& case_name, const std::string& why,
                          bool levels_too = false);

/// All registered cases, in name order.
std::vector<CaseInfo>& case_registry();
const CaseInfo* find_case(const std::string& name);

struct CaseRegistrar {
  explicit CaseRegistrar(CaseInfo info);
};

}  // namespace liquid::verification

#define LIQUID_VERIFICATION_CASE_CAT2(a, b) a##b
#define LIQUID_VERIFICATION_CASE_CAT(a, b) LIQUID_VERIFICATION_CASE_CAT2(a, b)
/// Registers a case: LIQUID_VERIFICATION_CASE({"name", "summary", true, run_function});
#define LIQUID_VERIFICATION_CASE(...)                                                         \
  static const ::liquid::verification::CaseRegistrar LIQUID_VERIFICATION_CASE_CAT(registrar_, \
                                                                                  __LINE__)(__VA_ARGS__)
