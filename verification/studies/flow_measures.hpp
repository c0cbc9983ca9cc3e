#pragma once
// Measures of a particle flow shared by the flow cases (kinetic-energy, vorticity).

#include <cmath>
#include <span>
#include <string>
#include <vector>

#include "common/table.hpp"
#include "liquid/pic/adaptive_pic.hpp"
#include "liquid/tree/cell_graph.hpp"

namespace liquid::verification {

/// One method of a flow study: the adaptive tree or a uniform one, the transfer, and whether it runs
/// the paper's preset (PicOptions::apply_paper_preset) instead of the defaults.
struct FlowMethod {
  const char* name;
  bool adaptive;
  pic::PicTransfer transfer;
  bool paper = false;
  bool everywhere = false;   ///< adaptive RBF with the RBF everywhere (no uniform patches)
  bool tent = false;         ///< adaptive RBF with tent particle -> face at level changes
  int ppe_degree = 0;        ///< adaptive RBF: the RBF-FD rows' polynomial degree (0: the default)
  bool flux_rows = false;    ///< adaptive RBF: flux rows at T-junctions (PPE = D G, mac::IrregularRows)
  double tent_share = -1.0;  ///< adaptive RBF: PicOptions::level_change_tent_share (< 0: the default)
  /// A comparison row: a setting other than the default adaptive one or the paper's preset.
  bool variant() const { return everywhere || tent || ppe_degree > 0 || flux_rows || tent_share >= 0.0; }
};
/// The methods of `all` that `flag` (--methods, or --reference-method) names, in the order named (every one
/// when none is named); throws naming a method that is not one of them.
std::vector<FlowMethod> chosen_methods(std::span<const FlowMethod> all, const std::vector<std::string>& names,
                                       const char* flag = "--methods");
/// The note a flow study prints when `--band K` set its adaptive runs' band (finest-level face hops
/// around a surface cell; the default and the paper's is 2).
std::string band_note(int band);
/// The flow studies' methods, side by side: adaptive RBF with the default transfer and reseeding,
/// the same with the paper's preset, RBF on the uniform tree, and the regular baselines PIC, FLIP and
/// APIC.
inline const FlowMethod kFlowMethods[] = {{"adaptive-rbf", true, pic::PicTransfer::rbf},
                                          {"adaptive-rbf-paper", true, pic::PicTransfer::rbf, true},
                                          {"regular-rbf", false, pic::PicTransfer::rbf},
                                          {"regular-pic", false, pic::PicTransfer::pic},
                                          {"regular-flip", false, pic::PicTransfer::flip},
                                          {"regular-apic", false, pic::PicTransfer::apic}};

/// How often a run's projections raised the kinetic energy of the face velocities
/// (PicStepReport::grid_energy_before/after), and by how much at most (relative).
struct ProjectionEnergy {
  long raised = 0;       ///< steps whose projection raised it by more than 1e-9
  double largest = 0.0;  ///< the largest relative rise
  void add(const pic::PicStepReport& r) {
    if (r.grid_energy_before <= 0.0) return;
    const double rise = r.grid_energy_after / r.grid_energy_before - 1.0;
    raised += rise > 1e-9;
    largest = rise > largest ? rise : largest;
  }
};

/// The volume each particle at `x` stands for, all scaled to sum to `volume`: its cell's volume
/// over the cell's particles, or over 2^Dim (what a full cell is seeded with) when the cell holds
/// fewer (a surface cell, partly liquid). Seeding and reseeding count particles per cell whatever
/// its level, so on an adaptive tree a particle in a coarse cell stands for more liquid than one in
/// the band: equal shares would weigh the band 2^Dim times too much per level. On a uniform tree
/// with every cell at its seeded count the shares are equal. `filled` (optional) receives the
/// volume the particles fill by the same count, unscaled: each cell holding particles counts its
/// volume times min(its particles, 2^Dim) / 2^Dim. A PIC liquid that spreads (its particles leaving
/// gaps that the cells still count as liquid) grows by this measure.
template <int Dim>
std::vector<double> particle_volumes(const tree::CellGraph<Dim>& graph, std::span<const Vec<Dim>> x,
                                     double volume, double* filled = nullptr);
/// APIC's affine kinetic energy (particle_affine_energy), each particle weighing w_i; with adaptive
/// RBF's uniform patches the same in the lattice of each particle's cell level (patch_inertia); 0 for
/// the other transfers, whose particles carry no affine part.
template <int Dim>
double affine_energy(const pic::AdaptivePic<Dim>& sim, std::span<const double> w);

/// Twice the kinetic energy of a box of volume `volume` full of liquid, from the particles (each
/// weighing its share, particle_volumes), APIC's affine part included.
template <int Dim>
double twice_kinetic_energy(const pic::AdaptivePic<Dim>& sim, double volume);

/// The Taylor-Green cells u = (sin x cos y, -cos x sin y) on [0, pi]^2, an exact steady inviscid
/// flow with free-slip walls; in 3D the same cells with w = 0 (independent of z).
template <int Dim>
Vec<Dim> taylor_green(const Vec<Dim>& x) {
  Vec<Dim> u = Vec<Dim>::Zero();
  u[0] = std::sin(x[0]) * std::cos(x[1]);
  u[1] = -std::cos(x[0]) * std::sin(x[1]);
  return u;
}

/// How a method's seconds at an error were found: its run, log-log between two runs, at most its
/// cheapest run (already more accurate), or at least its most accurate run (not as accurate). Never
/// extrapolated: a power law through two or three runs can put a method anywhere.
enum class Reach { run, interpolated, at_most, at_least };
/// The reading as words for a report's column ("log-log between two runs", ...).
const char* reach_text(Reach how);

/// A method's runs as (error, seconds) pairs, one per row of a study.
struct ErrorCurve {
  std::string name;
  std::vector<double> errors, seconds;
};

/// The seconds a method needs at an error, read from its runs without extrapolating: inside the range
/// of its runs' errors, log-log interpolation between the two runs that bracket it (exact at a run);
/// below it, at least what its most accurate run took (a more accurate run of the same method is taken
/// to cost more); above it, at most its cheapest run (already more accurate).
struct SecondsAt {
  double seconds = 0.0;
  Reach how = Reach::interpolated;  ///< interpolated, at_least or at_most
};
SecondsAt seconds_at(const ErrorCurve& curve, double error);

/// One error at which a method is compared with the fastest of the others.
struct EqualErrorRow {
  double error = 0.0;    ///< a run's error (any method's), inside the method's own range
  double seconds = 0.0;  ///< the method's seconds there (interpolated between its runs)
  std::string fastest;   ///< the other method that sets the fastest time (its bound when not read)
  SecondsAt other;       ///< that method's seconds there
  double low = 0.0;      ///< the speed-up (fastest other / method) is at least this (0: no bound)
  double high = 0.0;     ///< and at most this (infinite: no bound); low == high when read exactly
};

/// At one error: the method's seconds against the fastest of `others`, whose bounds (SecondsAt) carry
/// into the speed-up's.
EqualErrorRow speed_at_error(const ErrorCurve& method, std::span<const ErrorCurve> others, double error);

/// Speed at equal error over the whole range where it can be read: at every run's error (any method's)
/// inside the range of `method`'s errors, the method's seconds against the fastest of `others`. The
/// others' bounds (SecondsAt) carry into the speed-up's, so an error no other method's runs bracket
/// still gives a one-sided figure. Rows from the largest error to the smallest; none when `method` has
/// fewer than two runs with a positive error and time.
std::vector<EqualErrorRow> speed_at_equal_error(const ErrorCurve& method, std::span<const ErrorCurve> others);

/// "3.1x", ">= 1.2x", "<= 0.8x" or "1.2x to 4.0x": a speed-up's bounds as text.
std::string speedup_text(const EqualErrorRow& row);

/// The rows as a report table (`error` names the error's column) and as one line for a note:
/// "1x at 0.015, 3.1x at 0.011, >= 1.2x at 0.007".
Table equal_error_table(const std::vector<EqualErrorRow>& rows, const std::string& title,
                        const std::string& error, const std::string& method);
std::string equal_error_summary(const std::vector<EqualErrorRow>& rows);

}  // namespace liquid::verification
