#pragma once
// The factorised RBF + polynomial saddle-point matrix of a node set already translated and scaled
// to the unit ball. Shared by the RBF-FD weights and the interpolant; internal to the rbf module.

#include <span>

#include <Eigen/Core>
#include <Eigen/QR>

#include "liquid/rbf/kernel.hpp"
#include "liquid/rbf/polynomial.hpp"
#include "liquid/rbf/weights.hpp"

namespace liquid::rbf::detail {

template <int Dim>
struct SaddleSystem {
  /// Chooses the highest degree <= config.degree that the nodes can carry, assembles and factorises.
  /// On return `status` says whether `qr` may be used.
  SaddleSystem(std::span<const Vec<Dim>> unit_nodes, const Config& config);

  Phs kernel;
  PolynomialBasis<Dim> basis;
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr;
  Status status;
  int n_nodes = 0;
  int n_terms = 0;
};

}  // namespace liquid::rbf::detail
