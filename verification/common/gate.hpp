#pragma once
// The accuracy gate: every quick case's gated figures against the accepted ones in
// reference/<case>.toml. An error may not grow past accepted * (1 + error_rel) (plus a round-off
// floor), an order may not drop more than order_drop below the accepted one, an iteration count
// may not grow past accepted * (1 + iterations_rel) + 2, a count (of failures, say) may not grow.

#include <string>
#include <vector>

#include "case.hpp"

namespace liquid::verification {

struct GateTolerance {
  double error_rel = 0.10;
  double error_floor = 1e-13;
  double order_drop = 0.10;
  double iterations_rel = 0.5;
};

/// One accepted figure as read from reference/<case>.toml.
struct AcceptedFigure {
  std::string name, kind;
  GateFigure::Kind parsed;
  double value;
  std::string where;  ///< file:line
};

/// Reads and checks an accepted file: every figure named once, of a known kind, with a finite value;
/// finite non-negative tolerances. Throws liquid::Error naming file:line.
std::vector<AcceptedFigure> read_reference(const std::string& path, GateTolerance& tolerance);
/// read_reference() on reference_dir/<case>.toml when it exists, before the case runs.
void validate_reference(const std::string& case_name, const std::string& reference_dir);

struct GateLine {
  std::string figure;
  std::string kind;
  double accepted = 0.0, now = 0.0, allowed = 0.0;
  bool regression = false;
  bool moved = false;
};

struct GateOutcome {
  std::vector<GateLine> lines;        ///< every accepted figure, in file order
  std::vector<std::string> problems;  ///< missing figures, a missing reference file
  bool passed() const;
};

/// Compares a case's figures with reference/<case>.toml in `reference_dir`. Throws liquid::Error
/// naming the file and line when the reference file is malformed.
GateOutcome compare_with_reference(const std::string& case_name, const std::vector<GateFigure>& figures,
                                   const std::string& reference_dir);

/// Writes reference/<case>.toml with the figures as accepted values and the default tolerances
/// (keeping the tolerances of an existing file).
void bless_reference(const std::string& case_name, const std::vector<GateFigure>& figures,
                     const std::string& reference_dir);

/// The moved figures as an aligned table (all figures when `all`).
Table gate_table(const std::string& case_name, const GateOutcome& outcome, bool all);

const char* to_string(GateFigure::Kind kind);

}  // namespace liquid::verification
