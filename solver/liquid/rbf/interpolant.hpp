#pragma once
// An RBF interpolant with appended polynomials: factorise once for a node set, fit any number of
// value columns, evaluate values and gradients at many points. Used by the particle/grid transfers
// (PHS s = 5 with degree 2 by default, the paper's transfer setting).

#include <memory>
#include <span>

#include <Eigen/Core>

#include "liquid/core/types.hpp"
#include "liquid/rbf/weights.hpp"

namespace liquid::rbf {

namespace detail {
template <int Dim>
struct SaddleSystem;
}

template <int Dim>
class Interpolant {
 public:
  /// A node set translated to its centroid, scaled to the unit ball and factorised: what the
  /// interpolants of congruent stencils share (InterpolantCache). Immutable once made.
  struct Factors;
  /// Factors of `nodes`, in whatever frame they are given; an interpolant on them reads its points
  /// in that frame (see the constructor taking factors).
  static std::shared_ptr<const Factors> factorise(std::span<const Vec<Dim>> nodes, const Config& config);

  /// Factorises the system for `nodes` (copied). Check status().usable() before fitting.
  Interpolant(std::span<const Vec<Dim>> nodes, const Config& config);
  /// An interpolant on shared factors whose nodes were given in units of `scale` from `origin`: a
  /// point x is read as (x - origin) / scale.
  Interpolant(std::shared_ptr<const Factors> factors, const Vec<Dim>& origin, double scale);
  ~Interpolant();
  /// A moved-from interpolant may only be destroyed or assigned to.
  Interpolant(Interpolant&&) noexcept;
  Interpolant& operator=(Interpolant&&) noexcept;

  const Status& status() const;
  int n_nodes() const;

  /// Fits the interpolant to `values` (one row per node, one column per field). Throws when the
  /// status is not usable or the row count differs from the node count.
  void fit(const Eigen::MatrixXd& values);

  /// Interpolated fields at x (one entry per fitted column).
  Eigen::RowVectorXd value(const Vec<Dim>& x) const;
  /// The fitted field `column` at x, without allocating (the transfers' inner loop).
  double value_at(const Vec<Dim>& x, int column = 0) const;
  /// Gradient of every fitted field at x: row k holds d/dx_k.
  Eigen::MatrixXd gradient(const Vec<Dim>& x) const;
  /// value_at(x, column) and that field's gradient (Dim entries written to `grad`) in one pass over
  /// the nodes, without allocating: the same bits as the two calls (APIC's g2p, one per particle).
  double value_and_gradient(const Vec<Dim>& x, int column, double* grad) const;

  /// The Lebesgue function's largest value over `points`: max over x of sum_j |w_j(x)|, with w_j
  /// the cardinal functions (the interpolant of the j-th unit vector). It bounds how much the
  /// interpolant can amplify errors in the node values: a value of 50 lets a 0.01 error at the
  /// nodes become 0.5 at a point. Independent of fit(); one solve with a column per point.
  double lebesgue(std::span<const Vec<Dim>> points) const;
  /// lebesgue() over the 3^Dim lattice of the cube [-1/2, 1/2]^Dim (corners, edge and face
  /// centres, centre) read in this interpolant's frame: for an interpolant of the cache
  /// (origin the cell centre, scale its size) the whole cell. Computed once per factorisation
  /// and shared by every interpolant on the same factors.
  double cell_lebesgue() const;

 private:
  Vec<Dim> unit(const Vec<Dim>& x) const;  // x in the factors' unit-ball coordinates

  std::shared_ptr<const Factors> factors_;
  Vec<Dim> origin_ = Vec<Dim>::Zero();
  double scale_ = 1.0;
  Eigen::MatrixXd coefficients_;  // (n + n_terms) x n_fields
};

}  // namespace liquid::rbf
