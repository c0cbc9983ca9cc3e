#pragma once
// `liquid-verify poisson`: a user's own manufactured-solution convergence study.

#include <string>

#include "common/case.hpp"

namespace liquid::verification {

struct UserPoissonArgs {
  int dim = 2;
  std::string exact;     ///< p(x, y[, z])
  std::string levelset;  ///< optional: unknowns where it is negative, p = exact on its zero set
  std::string domain;    ///< "x0,x1,y0,y1[,z0,z1]"
  std::string bc = "neumann";
  std::string tree = "band";  ///< uniform | band | random:SEED
  int max_jump = 2;
  std::string levels = "4:6";
  RowProtocol rows = RowProtocol::refine;
  linalg::SolverKind solver = linalg::SolverKind::bicgstab_ilut;
  NullspaceChoice nullspace = NullspaceChoice::pin;
  bool nullspace_given = false;  ///< --nullspace was given (refused on problems that are not singular)
  double tolerance = 0.0;        ///< the solver's relative residual; 0: the default 1e-10
  AlgebraicControl algebraic = AlgebraicControl::tighten;  ///< --algebraic
  std::string expect_order;   ///< "P" or "P,G": floors of the fitted orders of p and dp/dn
  double expect_error = 0.0;  ///< > 0: ceiling of the finest row's L-inf error of p
  long max_cells = 0;         ///< refuse rows estimated above this many cells (0: no limit)
};

/// Runs the study (tables printed by the caller). Throws liquid::Error naming the argument on bad
/// input.
CaseResult run_user_poisson(const UserPoissonArgs& args);

/// The command line echoed back (for the record and the report).
std::string describe(const UserPoissonArgs& args);

}  // namespace liquid::verification
