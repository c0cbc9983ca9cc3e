#pragma once
// The factorised RBF + polynomial saddle-point matrix of a node set already translated and scaled
// to the unit ball. Shared by the RBF-FD weights and the interpolant; internal to the rbf module.

#include <span>
#include <type_traits>

#include <Eigen/Core>
#include <Eigen/LU>

#include "liquid/rbf/kernel.hpp"
#include "liquid/rbf/polynomial.hpp"
#include "liquid/rbf/weights.hpp"

namespace liquid::rbf::detail {

template <int Dim>
struct SaddleSystem {
  /// Chooses the highest degree <= config.degree that the nodes can carry, assembles and factorises.
  /// On return `status` says whether `lu` may be used.
  SaddleSystem(std::span<const Vec<Dim>> unit_nodes, const Config& config);

  Phs kernel;
  PolynomialBasis<Dim> basis;
  /// Solves K x = rhs with one step of iterative refinement, which brings the round-off of the
  /// high-order settings (s = 7, degree 4 on fine stencils) back to that of a pivoted QR.
  /// A vector right-hand side stays a vector, so that both solves take Eigen's vector kernels.
  template <class Rhs>
  auto solve(const Rhs& rhs) const {
    using X = std::conditional_t<Rhs::ColsAtCompileTime == 1, Eigen::VectorXd, Eigen::MatrixXd>;
    X x = lu.solve(rhs);
    x += lu.solve(rhs - matrix * x);
    return x;
  }

  /// LU with partial pivoting: the matrix is symmetric but indefinite (the zero polynomial block),
  /// and LU is much cheaper than a column-pivoted QR. Rank deficiency shows as a huge condition
  /// estimate.
  Eigen::PartialPivLU<Eigen::MatrixXd> lu;
  Eigen::MatrixXd matrix;  ///< K itself, for the refinement step
  Status status;
  int n_nodes = 0;
  int n_terms = 0;
};

}  // namespace liquid::rbf::detail
