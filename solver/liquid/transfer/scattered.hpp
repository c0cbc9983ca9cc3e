#pragma once
// Particle <-> face transfers on any Cellgraph (non-graded trees included), by RBF (the paper's,
// Sec. 4.5) or by moving least squares (HOPIC's, for comparison).
//
// Particle -> face: a face's normal component is interpolated to its centre from the same component
// of the particles in the face's adjacent cells (rings = 1; rings = r adds the cells within r - 1
// face hops of them). A gather: each face reads its particles, so no atomics and the same sums on
// any thread count.
// Face -> particle: component k at a particle is interpolated from the axis-k faces of the cells
// within `rings` face hops of the particle's cell (rings = 1: the cell and the cells incident to it).
// The RBF interpolant is factorised once per (cell, axis) and evaluated at every particle of the
// cell; MLS solves one small least-squares problem per particle.
//
// Walls: a face on the domain boundary has particles on one side only, and its centre lies outside
// them. Such faces reach `wall_rings` more rings (default 1, which cuts the round trip's error at
// walls; wall_rings = 0 is the paper's stencil exactly). Why: docs/findings/transfers.md.
//
// Hard stencils are normal input. Too few or degenerate nodes lower the polynomial degree (counted).
// Coincident nodes make the RBF system singular: the inverse-distance mean is used instead
// (counted). No source in reach leaves the target unknown (faces) or at 0 (particles), counted,
// never NaN. Clamping keeps each value within the range of its sources, against the overshoot of
// scattered interpolants near walls, and is counted. It is on by default for face -> particle (as
// in the paper, Sec. 7) and off for particle -> face: there a hanging face's centre often lies
// outside its particles (the coarse side's particles are far), and clamping lowers the
// extrapolation's order (docs/findings/transfers.md).

#include <cstdint>
#include <span>
#include <string>

#include "liquid/particles/bins.hpp"
#include "liquid/particles/particles.hpp"
#include "liquid/rbf/weights.hpp"
#include "liquid/transfer/face_values.hpp"
#include "liquid/tree/cell_graph.hpp"

namespace liquid::transfer {

enum class Scheme { rbf, mls };
const char* to_string(Scheme scheme);

struct TransferOptions {
  Scheme scheme = Scheme::rbf;
  int exponent = 5;          ///< PHS exponent r^s (RBF only; odd, 1..9)
  int degree = 2;            ///< polynomial degree: appended to the RBF, or fitted by MLS (0..4)
  int rings = 1;             ///< stencil reach in face hops (see above)
  bool clamp = true;         ///< face -> particle: clamp each value to the range of its faces
  bool clamp_faces = false;  ///< particle -> face: clamp each value to the range of its particles
  int wall_rings = 1;        ///< extra rings for particle -> face at domain-boundary faces
  /// Particle -> face: at most this many particles per stencil, the nearest to the face centre; 0
  /// means 4 times the polynomial terms, -1 no limit. A wall face's extra ring in 3D reaches a
  /// hundred particles or more, and the saddle system's LU grows with their cube. Face -> particle
  /// keeps every face of its rings (limiting them costs accuracy). Why: docs/findings/transfers.md.
  int max_nodes = 0;
  /// Face -> particle (RBF): factorise each stencil shape once and share it between the cells with
  /// that layout of faces (rbf::InterpolantCache); false factorises every cell's own. The two agree
  /// to round-off.
  bool share_factors = true;
  /// RBF: how each saddle system's condition is estimated before it is accepted (past 1e14 a
  /// stencil falls back to inverse-distance weights). The two fixed probes cost one solve where the
  /// full Hager-Higham ascent takes up to ten, and accept the same stencils in the runs compared
  /// (docs/findings/table1.md).
  rbf::ConditionEstimate condition_estimate = rbf::ConditionEstimate::probes;
  int node_cap(int dim) const;     ///< the limit max_nodes stands for (0: none)
  rbf::Config rbf_config() const;  ///< the RBF kernel settings above

  /// The paper's transfer: PHS r^5 with polynomials of degree 2, the adjacent/incident cells (plus
  /// wall_rings at walls).
  static TransferOptions paper_rbf() { return {}; }
  /// HOPIC's cubic MLS; it needs more nodes than the RBF (10 terms in 2D, 20 in 3D), so 2 rings.
  static TransferOptions cubic_mls() {
    TransferOptions o;
    o.scheme = Scheme::mls, o.degree = 3, o.rings = 2;
    return o;
  }
  /// A linear least-squares fit on the RBF's stencil: the "linear interpolation" of scattered data.
  static TransferOptions linear_fit() {
    TransferOptions o;
    o.scheme = Scheme::mls, o.degree = 1;
    return o;
  }
  std::string describe() const;
};

/// Particle -> face for every alive face; `out` is reset to graph.face_capacity() first. Uses
/// OpenMP. `bins` must be current for `particles`. Faces with skip[f] != 0 are left unknown and not
/// counted (another transfer fills them: UniformPatches); an empty `skip` skips none.
template <int Dim>
TransferReport particles_to_faces(const tree::CellGraph<Dim>& graph,
                                  const particles::Particles<Dim>& particles, const particles::CellBins& bins,
                                  const TransferOptions& options, FaceValues& out,
                                  std::span<const std::uint8_t> skip = {});

/// Face -> point: the velocity at every point x[i] (points binned in `bins`; particles or any
/// sample points) from the face values `u` (indexed by face id). Faces with known[f] == 0 are not
/// used (pass an empty span when every face is known). `v` (out) has one entry per point. OpenMP.
template <int Dim>
TransferReport faces_to_points(const tree::CellGraph<Dim>& graph, std::span<const double> u,
                               std::span<const std::uint8_t> known, std::span<const Vec<Dim>> x,
                               const particles::CellBins& bins, const TransferOptions& options,
                               std::span<Vec<Dim>> v);

/// FLIP's update blended with PIC: v = alpha (v_old + delta) + (1 - alpha) pic, where pic is the
/// new grid velocity at the particle and delta the change of the grid velocity there (the same
/// transfer applied to u_new - u_old). alpha = 0 is PIC, 1 is pure FLIP.
template <int Dim>
void flip_blend(std::span<const Vec<Dim>> pic, std::span<const Vec<Dim>> delta, double alpha,
                std::span<Vec<Dim>> v);

}  // namespace liquid::transfer
