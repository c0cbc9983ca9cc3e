#pragma once
// RBF-FD weights: for nodes x_1..x_n and an evaluation point x0, weights w with
//   (L u)(x0) ~= sum_j w_j u(x_j)
// exact for polynomials of the basis degree, from the saddle-point system
//   [ A   P ] [ w     ]   [ L phi(|x - x_j|) at x0 ]
//   [ P^T 0 ] [ gamma ] = [ L p_t(x) at x0        ]
// with A_ij = phi(|x_i - x_j|), P_jt = p_t(x_j). The stencil is translated to x0 and scaled by its
// radius R = max_j |x_j - x0| before solving (so the system does not depend on h), and the weights
// are scaled back (1 for values, 1/R for first derivatives, 1/R^2 for the Laplacian). gamma is
// discarded.
//
// Hard stencils are normal input: when the nodes cannot carry the requested polynomial degree
// (too few nodes, collinear or coplanar nodes) the degree is lowered and reported; coincident nodes
// and singular systems are reported through Status and give no weights. No NaN leaves this module.

#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "liquid/core/types.hpp"

namespace liquid::rbf {

/// A linear differential operator  value * u + gradient . grad u + laplacian * Lap u.
template <int Dim>
struct Operator {
  double value = 0.0;
  Vec<Dim> gradient = Vec<Dim>::Zero();
  double laplacian = 0.0;

  static Operator identity() { return {1.0, Vec<Dim>::Zero(), 0.0}; }
  static Operator partial(int k) {
    Operator op;
    op.gradient[k] = 1.0;
    return op;
  }
  /// Derivative along direction n (not normalised here).
  static Operator directional(const Vec<Dim>& n) { return {0.0, n, 0.0}; }
  static Operator lap() { return {0.0, Vec<Dim>::Zero(), 1.0}; }

  Operator operator+(const Operator& o) const {
    return {value + o.value, gradient + o.gradient, laplacian + o.laplacian};
  }
  Operator operator*(double a) const { return {a * value, a * gradient, a * laplacian}; }
};

/// How Status::condition is estimated from the saddle system's LU (both are 1-norm lower bounds).
enum class ConditionEstimate {
  /// Hager's gradient ascent with Higham's alternating probe (Eigen's rcond): up to 10 solves.
  hager_higham,
  /// Hager's first probe and Higham's alternating one, without the ascent: one two-column solve.
  /// Not above hager_higham's figure but for rounding (the ascent starts from the same probe); how
  /// close it comes: docs/findings/table1.md.
  probes,
};

/// Choices of the discretisation; defaults are the paper's operator settings.
struct Config {
  int exponent = 3;                     ///< PHS exponent s (odd, 1..9)
  int degree = 2;                       ///< requested total degree of the appended polynomials (0..4)
  double rank_tolerance = 1e-9;         ///< relative threshold of the rank test on the polynomial block
  double coincidence_tolerance = 1e-9;  ///< nodes closer than this times R are coincident
  double max_condition = 1e14;          ///< estimated condition number past which a system is refused
  /// How `max_condition` is checked (the transfers take probes; see TransferOptions).
  ConditionEstimate condition_estimate = ConditionEstimate::hager_higham;
};

enum class Info {
  ok,                ///< weights computed at the requested degree
  degree_reduced,    ///< weights computed at a lower degree (see Status::degree_used)
  empty_stencil,     ///< no nodes, or every node sits on the evaluation point
  coincident_nodes,  ///< two nodes coincide (Status::node_a, node_b)
  singular_system,   ///< the saddle-point matrix is rank deficient or too ill-conditioned
  non_finite,        ///< a node coordinate or a computed weight was not finite
};

const char* to_string(Info info);

/// What the weight computation did; the caller decides whether to accept it.
struct Status {
  Info info = Info::ok;
  int n_nodes = 0;
  int degree_requested = 0;
  int degree_used = -1;
  double condition = 0.0;         ///< 1-norm condition estimate of the scaled system (see Config)
  bool laplacian_defined = true;  ///< false for s = 1 with a node on the evaluation point
  int node_a = -1, node_b = -1;   ///< the offending pair for coincident_nodes

  bool usable() const { return info == Info::ok || info == Info::degree_reduced; }
  /// One line for logs and error messages.
  std::string describe() const;
};

/// Weights of the basic operators at one point: column 0 the value, columns 1..Dim the partial
/// derivatives, column Dim+1 the Laplacian; one row per node, in physical units.
template <int Dim>
struct BasisWeights {
  Eigen::Matrix<double, Eigen::Dynamic, Dim + 2> w;
  Status status;

  /// Weights of an operator as a combination of the columns. Throws when the status is not usable.
  void combine(const Operator<Dim>& op, std::vector<double>& out) const;
};

/// Basis weights for `nodes` evaluated at `at` (both in physical coordinates).
template <int Dim>
BasisWeights<Dim> basis_weights(std::span<const Vec<Dim>> nodes, const Vec<Dim>& at, const Config& config);

/// Weights of one operator; `out` receives one weight per node when the status is usable and is
/// left empty otherwise.
template <int Dim>
Status weights(std::span<const Vec<Dim>> nodes, const Vec<Dim>& at, const Operator<Dim>& op,
               const Config& config, std::vector<double>& out);

/// Interpolation weights at `at` alone (the value column of basis_weights, one right-hand side
/// instead of Dim + 2: what the particle -> face transfer needs per face). Same status rules.
template <int Dim>
Status value_weights(std::span<const Vec<Dim>> nodes, const Vec<Dim>& at, const Config& config,
                     std::vector<double>& out);

}  // namespace liquid::rbf
