#pragma once
// The regular baselines the paper compares against (its Kim 2016 solvers, and Jet's): PIC, FLIP and
// APIC on a uniform tree (every cell at one level, level jump 0), with multilinear weights on the
// staggered (MAC) faces.
//
// Weights. Component k lives on the axis-k faces, a lattice offset by half a cell along the other
// axes. A point's weights are the tensor product of 1D hat functions over the 2^Dim lattice faces
// around it; near a wall, where the lattice ends, the coordinate is clamped onto the last lattice
// line (constant extrapolation) and the weight's derivative along it is 0.
// APIC (Jiang et al. 2015) with these linear B-spline weights: each particle carries an affine
// matrix C (row k: the gradient of component k), the field "apic" of Dim*Dim doubles. Particle ->
// face adds C_k . (x_f - x_p) to the particle's component; face -> particle sets
// C_k = sum_f u_f grad w_f(x_p), which equals sum_f w_f u_f D_k^-1 (x_f - x_p) for multilinear
// weights (D_k the per-component inertia tensor; Jiang et al., Sec. 5.3). With unit masses (or the
// field "mass"), both transfers conserve linear momentum, and angular momentum counted as
// sum_p m_p (x_p x v_p + sum_k (D_k c_k) x e_k), exactly (up to round-off) wherever the stencils
// are whole (particles at least a cell away from walls).
//
// Particle -> face is a scatter in slabs that never share a face (each particle read once), so no
// atomics and the same sums on any thread count.

#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "liquid/particles/bins.hpp"
#include "liquid/particles/particles.hpp"
#include "liquid/transfer/face_values.hpp"
#include "liquid/tree/cell_graph.hpp"

namespace liquid::transfer {

/// The cells and faces of a uniform tree as lattices.
template <int Dim>
class RegularLattice {
 public:
  /// Throws naming a cell unless every cell of `graph` is at one level >= 1.
  explicit RegularLattice(const tree::CellGraph<Dim>& graph);

  int level() const { return level_; }
  long n() const { return n_; }  ///< cells per axis
  const Vec<Dim>& h() const { return h_; }
  const Vec<Dim>& origin() const { return lo_; }
  /// The cell at lattice address a (0 <= a < n), or no_cell outside.
  tree::CellId cell(const IVec<Dim>& a) const;
  /// The axis-k face at lattice address a (0 <= a_k <= n, 0 <= a_j < n), or no_face outside.
  tree::FaceId face(int k, const IVec<Dim>& a) const;
  /// Number of axis-k lattice positions along axis j.
  long extent(int k, int j) const { return j == k ? n_ + 1 : n_; }
  Vec<Dim> face_position(int k, const IVec<Dim>& a) const;
  /// Index of the axis-k face at address a among that axis' lattice faces (axis 0 fastest); a must
  /// be inside.
  long flat_face(int k, const IVec<Dim>& a) const;
  /// The axis-k face of flat index `flat`.
  tree::FaceId face_at(int k, long flat) const { return faces_[k][flat]; }
  /// Number of axis-k lattice faces (the product of extent(k, j) over j).
  long face_count(int k) const { return static_cast<long>(faces_[k].size()); }

 private:
  long flat_cell(const IVec<Dim>& a) const;
  int level_ = 0;
  long n_ = 0;
  Vec<Dim> h_, lo_;
  std::vector<tree::CellId> cells_;
  std::array<std::vector<tree::FaceId>, Dim> faces_;
};

/// Weight of corner `corner` (bit j: +1 along axis j) of a multilinear stencil with fractions t.
/// Defined here so that the per-particle loops of every transfer inline it.
template <int Dim>
double multilinear_weight(const Vec<Dim>& t, int corner) {
  double w = 1.0;
  for (int j = 0; j < Dim; ++j) w *= (corner >> j) & 1 ? t[j] : 1.0 - t[j];
  return w;
}
/// Its gradient on a lattice of spacing h; 0 along the clamped axes.
template <int Dim>
Vec<Dim> multilinear_gradient(const Vec<Dim>& t, const std::array<bool, Dim>& clamped, int corner,
                              const Vec<Dim>& h) {
  Vec<Dim> g;
  for (int j = 0; j < Dim; ++j) {
    if (clamped[j]) {
      g[j] = 0.0;
      continue;
    }
    double w = ((corner >> j) & 1 ? 1.0 : -1.0) / h[j];
    for (int i = 0; i < Dim; ++i)
      if (i != j) w *= (corner >> i) & 1 ? t[i] : 1.0 - t[i];
    g[j] = w;
  }
  return g;
}

/// The multilinear stencil of a point for component k: base lattice address and fractions.
template <int Dim>
struct LinearStencil {
  IVec<Dim> base;
  Vec<Dim> t;                       ///< fraction in [0, 1] along each axis
  std::array<bool, Dim> clamped{};  ///< the coordinate left the lattice (derivative 0 along it)

  LinearStencil(const RegularLattice<Dim>& lattice, int k, const Vec<Dim>& x);
  /// Weight of corner `corner` (bit j: +1 along axis j) and its gradient.
  double weight(int corner) const;
  Vec<Dim> gradient(int corner, const Vec<Dim>& h) const;
};

enum class RegularScheme { pic, apic };

/// Particle -> face on a uniform tree. `masses` may be empty (unit masses). APIC reads the field
/// "apic" (Dim*Dim doubles per particle). `out` is reset to graph.face_capacity(); a face no
/// particle weighs on is unknown.
template <int Dim>
TransferReport linear_to_faces(const tree::CellGraph<Dim>& graph, const RegularLattice<Dim>& lattice,
                               const particles::Particles<Dim>& particles, const particles::CellBins& bins,
                               RegularScheme scheme, std::span<const double> masses, FaceValues& out);

/// The same transfer as a gather (every face reads the particles of the 2 x 3^(Dim-1) cells its hat
/// covers): the definition the scatter is tested against and benchmarked beside. Equal to
/// linear_to_faces up to the order of each face's sum.
template <int Dim>
TransferReport linear_to_faces_gather(const tree::CellGraph<Dim>& graph, const RegularLattice<Dim>& lattice,
                                      const particles::Particles<Dim>& particles,
                                      const particles::CellBins& bins, RegularScheme scheme,
                                      std::span<const double> masses, FaceValues& out);

/// Face -> point on a uniform tree: v (out) at every x. With `affine` non-empty (Dim*Dim doubles per
/// point) APIC's matrix C is written there too. `order` (optional, a permutation of the points, e.g.
/// CellBins::index): the order the points are visited in; the same values in any order, and fewer
/// cache misses in one that keeps a cell's points together.
template <int Dim>
TransferReport linear_to_points(const RegularLattice<Dim>& lattice, std::span<const double> u,
                                std::span<const Vec<Dim>> x, std::span<Vec<Dim>> v,
                                std::span<double> affine = {}, std::span<const std::int32_t> order = {});

/// sum_p m_p v_p (masses empty: unit masses).
template <int Dim>
Vec<Dim> particle_momentum(const particles::Particles<Dim>& particles, std::span<const double> masses = {});
/// sum over faces of weight_f u_f e_axis.
template <int Dim>
Vec<Dim> face_momentum(const tree::CellGraph<Dim>& graph, const FaceValues& faces);
/// APIC's particle angular momentum about the origin (z only in 2D): sum_p m_p (x_p x v_p +
/// sum_k (D_k c_k) x e_k), D_k from the particle's multilinear stencil; `affine` may be empty (C = 0).
template <int Dim>
Eigen::Vector3d particle_angular_momentum(const RegularLattice<Dim>& lattice,
                                          const particles::Particles<Dim>& particles,
                                          std::span<const double> affine,
                                          std::span<const double> masses = {});
/// APIC's affine kinetic energy, what the particles' velocities alone leave out: sum_p m_p / 2
/// sum_k c_k . D_k c_k (c_k row k of the particle's C). Face -> particle fits v + C (x_f - x_p) by
/// weighted least squares, so |v_p|^2 / 2 plus the particle's share of this never exceeds its
/// stencil's sum_f w_f u_f^2 / 2, and equals it for a linear field.
template <int Dim>
double particle_affine_energy(const RegularLattice<Dim>& lattice, const particles::Particles<Dim>& particles,
                              std::span<const double> affine, std::span<const double> masses = {});
/// sum over faces of weight_f x_f x (u_f e_axis).
template <int Dim>
Eigen::Vector3d face_angular_momentum(const tree::CellGraph<Dim>& graph, const FaceValues& faces);

}  // namespace liquid::transfer
