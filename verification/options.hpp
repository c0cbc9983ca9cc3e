#pragma once
// The command line of liquid-verify, parsed once into typed values (CLI11 validators), and echoed
// back in full at start-up. Cases receive CaseOptions; a user's study receives UserPoissonArgs.

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

#include "common/case.hpp"
#include "user_poisson.hpp"

namespace liquid::verification {

/// The study options of `run` as CLI11 fills them; `given(option)` says whether the user set it.
struct StudyFlags {
  CLI::App* app = nullptr;
  std::string levels;
  int max_jump = 2;
  linalg::SolverKind solver = linalg::SolverKind::bicgstab_ilut;
  mac::StencilRule stencil = mac::StencilRule::ring;
  int rbf_exponent = 3, rbf_degree = 3, gradient_degree = 3;
  double stencil_growth = 2.0;
  double ring_cap = 0.0;
  double gradient_cap = 0.0;
  RowProtocol rows = RowProtocol::refine;
  NullspaceChoice nullspace = NullspaceChoice::pin;
  double tolerance = 1e-10;
  AlgebraicControl algebraic = AlgebraicControl::tighten;
  Perturbation perturb = Perturbation::first_order;
  std::string trees_dir;
  std::vector<std::string> methods;
  std::string reference;
  int band = 2;
  std::string seed;
  long particles = 0;
  double radius = 0.0, aspect = 1.0;
  int merge_wait = 0;
  double duration = 0.0;
  std::string sizes;
  double resample_travel = 0.0;
  long max_cells = 0;
  bool full = false;

  bool given(Option option) const;
};

/// Registers --levels ... --trees, --max-cells and --full on `app`.
void add_study_flags(CLI::App& app, StudyFlags& flags);
/// The options given, typed; throws liquid::Error naming the flag on a value no validator could check
/// (--levels A:B), and when `info` does not accept a flag given.
CaseOptions case_options(const StudyFlags& flags, const CaseInfo& info);
/// One line with every option of `run` and its value ("default" where the case decides).
std::string echo(const std::string& case_name, const StudyFlags& flags);

/// Registers the options of `liquid-verify poisson` on `app`.
void add_user_poisson_flags(CLI::App& app, UserPoissonArgs& args);

/// The default budget of cells for one row: half the machine's memory at kCellBytes a cell (a study
/// counts each unknown as kUnknownCells<Dim> cells more).
long default_max_cells();

/// "D:N[,N...]": dimension 2 or 3 and divisions 4 to 1000, increasing; throws liquid::Error naming
/// `flag`.
SizeList parse_size_list(const std::string& text, const std::string& flag);

/// "A:B" with integers 0 <= A <= B <= 64; throws liquid::Error naming `flag`.
LevelRange parse_level_range(const std::string& text, const std::string& flag);

}  // namespace liquid::verification
