#pragma once
// Uniform patches of an adaptive tree: where the regular baselines' multilinear (APIC) transfers
// apply, so the RBF transfer is needed only where a stencil meets a level change.
//
// A cell is a patch cell when it is at level >= 1 and every cell of its 3^Dim block (the cell and
// the cells it touches, those inside the domain) is a leaf of its own level. For a point in a
// patch cell, component k is the multilinear interpolation of the axis-k faces of that level's
// lattice, and APIC's affine matrix C (row k: the gradient of component k) comes with it; at walls
// the coordinate is clamped onto the last lattice line, as the regular baselines do. A patch face
// (every cell beside it is a patch cell) takes the hat-weighted mean of v_p + C (x_f - x_p) over the
// particles around it, APIC's particle -> face. Everything else is the RBF transfer's. Why:
// docs/findings/transfer-stability.md.

#include <array>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "liquid/particles/bins.hpp"
#include "liquid/particles/particles.hpp"
#include "liquid/transfer/face_values.hpp"
#include "liquid/tree/cell_graph.hpp"

namespace liquid::transfer {

template <int Dim>
class UniformPatches {
 public:
  static constexpr int block = Dim == 2 ? 9 : 27;       ///< cells of a 3^Dim block
  static constexpr int axis_faces = Dim == 2 ? 6 : 18;  ///< 2 x 3^(Dim-1) axis-k faces of a block
  /// The patch cells among `cells` (alive cells, any order; typically those near the particles) and
  /// the patch faces around them. Uses OpenMP.
  UniformPatches(const tree::CellGraph<Dim>& graph, std::span<const tree::CellId> cells);

  bool cell(tree::CellId c) const {
    return c >= 0 && c < static_cast<tree::CellId>(slot_.size()) && slot_[c] >= 0;
  }
  bool face(tree::FaceId f) const { return face_[f] != 0; }
  /// Per face id: 1 for a patch face.
  std::span<const std::uint8_t> face_mask() const { return face_; }
  long n_cells() const { return static_cast<long>(cells_.size()); }
  long n_faces() const { return static_cast<long>(faces_.size()); }

  /// The velocity at x (inside patch cell c, or on its boundary) from the face values u; with
  /// `affine` non-null, APIC's C (Dim x Dim, row-major) is written there.
  Vec<Dim> value(tree::CellId c, const Vec<Dim>& x, std::span<const double> u,
                 double* affine = nullptr) const;

  /// Particle -> face at every patch face: the hat-weighted mean of v_p (+ C (x_f - x_p) with
  /// `affine` non-empty: Dim*Dim doubles per particle). Writes out.value, out.known and out.weight
  /// at patch faces only (`out` must be sized for the graph); other faces are left as they are.
  /// A scatter: each patch cell's particles add to the faces of their stencils, in slabs two cells
  /// thick along the last axis (per level) that run in parallel when two apart, so a face's sum has
  /// a fixed order on any thread count. The faces whose hat also reaches cells that are not patch
  /// cells (the patches' rims) then gather those cells' particles, as to_faces_gather does.
  TransferReport to_faces(const particles::Particles<Dim>& particles, const particles::CellBins& bins,
                          std::span<const double> affine, FaceValues& out) const;
  /// The same by the definition: every patch face gathers the particles of the 2 x 3^(Dim-1) cells
  /// its hat reaches. Equal to to_faces up to the order of each face's sum.
  TransferReport to_faces_gather(const particles::Particles<Dim>& particles, const particles::CellBins& bins,
                                 std::span<const double> affine, FaceValues& out) const;
  /// Patch faces on the patches' rims (to_faces gathers their hats' particles outside the patches).
  long n_rim_faces() const { return n_rim_; }

 private:
  const tree::CellGraph<Dim>* graph_ = nullptr;
  std::vector<std::int32_t> slot_;  // per cell id: index into cells_, or -1
  std::vector<tree::CellId> cells_;
  std::vector<tree::CellId> blocks_;       // per patch cell: its 3^Dim block (no_cell outside the domain)
  std::vector<tree::FaceId> faces_table_;  // per patch cell: Dim x axis_faces faces (no_face outside)
  std::vector<std::uint8_t> face_;         // per face id: 0 not a patch face, 1 scattered, 2 on a rim (both)
  std::vector<tree::FaceId> faces_;
  long n_rim_ = 0;
  // The scatter's groups: patch cells (slots) of one level and one slab two cells thick along the
  // last axis, sorted; colours_[c] lists the groups of colour c (slab parity) as ranges of group_slots_.
  std::vector<std::int32_t> group_slots_;
  std::array<std::vector<std::pair<long, long>>, 2> colours_;
  void check_inputs(const particles::Particles<Dim>& particles, const particles::CellBins& bins,
                    std::span<const double> affine, const FaceValues& out) const;
  /// Gathers face faces_[i] into out (the definition), starting from the sums (sum, mass); with
  /// `outside_only`, from the hat's cells that are not patch cells only. Counts into r.
  void gather_face(long i, const particles::Particles<Dim>& particles, const particles::CellBins& bins,
                   std::span<const double> affine, FaceValues& out, TransferReport& r, double sum,
                   double mass, bool outside_only) const;
};

/// APIC's D_k at x in cell c: sum over x's multilinear axis-k stencil in the lattice of c's level of
/// w_f (x_f - x)(x_f - x)^T (walls clamped as above). The metric of a particle's affine kinetic
/// energy, sum_k c_k . D_k c_k / 2 (c_k row k of its C); any cell, patch or not.
template <int Dim>
Eigen::Matrix<double, Dim, Dim> patch_inertia(const tree::CellGraph<Dim>& graph, tree::CellId c, int k,
                                              const Vec<Dim>& x);

/// Particle -> face at every alive face with skip[f] == 0: the mean of v_p (+ C (x_f - x_p) with
/// `affine` non-empty) over the particles of the face's cells and their neighbours, weighed by the
/// tent prod_j max(0, 1 - |x_p,j - x_f,j| / h_j) of the face's level (its finer side's cell size h).
/// Positive weights: a face's value stays within the range of its particles' (C = 0). `out` must be
/// sized for the graph; faces skipped are left as they are.
template <int Dim>
TransferReport tent_to_faces(const tree::CellGraph<Dim>& graph, const particles::Particles<Dim>& particles,
                             const particles::CellBins& bins, std::span<const double> affine,
                             std::span<const std::uint8_t> skip, FaceValues& out);

/// Blends `share` of the tents' mean (tent_to_faces with C = 0) into every face `out` already knows
/// and `skip` leaves: v_f <- (1 - share) v_f + share v_tent wherever a tent reaches a particle (the
/// other faces keep v_f). The average damps the smooth modes that the RBF interpolant, which is not
/// an average, lets grow (docs/findings/transfer-stability.md). share = 0 leaves `out` as it is.
/// Returns the faces blended.
template <int Dim>
long blend_tent_mean(const tree::CellGraph<Dim>& graph, const particles::Particles<Dim>& particles,
                     const particles::CellBins& bins, std::span<const std::uint8_t> skip, double share,
                     FaceValues& out);

extern template class UniformPatches<2>;
extern template class UniformPatches<3>;

}  // namespace liquid::transfer
