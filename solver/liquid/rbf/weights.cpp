#include "liquid/rbf/weights.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <fmt/format.h>
#include <Eigen/QR>

#include "liquid/core/error.hpp"
#include "liquid/rbf/saddle.hpp"

namespace liquid::rbf {

const char* to_string(Info info) {
  switch (info) {
    case Info::ok:
      return "ok";
    case Info::degree_reduced:
      return "degree_reduced";
    case Info::empty_stencil:
      return "empty_stencil";
    case Info::coincident_nodes:
      return "coincident_nodes";
    case Info::singular_system:
      return "singular_system";
    case Info::non_finite:
      return "non_finite";
  }
  return "unknown";
}

std::string Status::describe() const {
  std::string s = fmt::format("{}: {} nodes, degree {} of {} requested, condition ~{:.2e}", to_string(info),
                              n_nodes, degree_used, degree_requested, condition);
  if (info == Info::coincident_nodes) s += fmt::format(", nodes {} and {} coincide", node_a, node_b);
  return s;
}

namespace detail {

namespace {
// Highest degree whose polynomial block has full column rank on these nodes (-1: none). `P` (out)
// holds the basis of degree min(requested, 4) at the nodes; a lower degree's block is its first
// columns (the terms are ordered by total degree).
template <int Dim>
int carried_degree(std::span<const Vec<Dim>> z, int requested, double tolerance, Eigen::MatrixXd& P) {
  const int n = static_cast<int>(z.size());
  const int top = std::min(requested, 4);
  const PolynomialBasis<Dim> full(top);
  P.resize(n, full.size());
  for (int j = 0; j < n; ++j)
    for (int t = 0; t < full.size(); ++t) P(j, t) = full.value(t, z[j]);
  for (int m = top; m >= 0; --m) {
    const int n_terms = n_polynomial_terms(Dim, m);
    if (n_terms > n) continue;
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(P.leftCols(n_terms));
    qr.setThreshold(tolerance);
    if (qr.rank() == n_terms) return m;
  }
  return -1;
}

/// ||K||_1 times a lower bound of ||K^-1||_1 from two fixed probes: K^-1 applied to the constant
/// vector 1/n (the start of Hager's ascent) and to Higham's alternating vector
/// (-1)^i (1 + i / (n - 1)), whose image bounds ||K^-1||_1 from below after the factor 2 / (3n).
/// A zero pivot gives an infinite or NaN image: an infinite condition.
double probe_condition(const Eigen::PartialPivLU<Eigen::MatrixXd>& lu, const Eigen::MatrixXd& K) {
  const Eigen::Index n = K.rows();
  Eigen::Matrix<double, Eigen::Dynamic, 2> probe(n, 2);
  for (Eigen::Index i = 0; i < n; ++i) {
    probe(i, 0) = 1.0 / static_cast<double>(n);
    const double ramp = n > 1 ? static_cast<double>(i) / static_cast<double>(n - 1) : 0.0;
    probe(i, 1) = (i % 2 == 0 ? 1.0 : -1.0) * (1.0 + ramp);
  }
  const Eigen::Matrix<double, Eigen::Dynamic, 2> image = lu.solve(probe);
  if (!image.allFinite()) return std::numeric_limits<double>::infinity();
  const double inverse =
      std::max(image.col(0).lpNorm<1>(), 2.0 * image.col(1).lpNorm<1>() / (3.0 * static_cast<double>(n)));
  return K.cwiseAbs().colwise().sum().maxCoeff() * inverse;
}
}  // namespace

template <int Dim>
SaddleSystem<Dim>::SaddleSystem(std::span<const Vec<Dim>> z, const Config& config)
    : kernel(config.exponent), basis(-1) {
  n_nodes = static_cast<int>(z.size());
  status.n_nodes = n_nodes;
  status.degree_requested = config.degree;
  if (n_nodes == 0) {
    status.info = Info::empty_stencil;
    return;
  }
  // The pairwise distances, once: for the coincidence test and then the kernel block.
  thread_local std::vector<double> distance;
  distance.resize(static_cast<std::size_t>(n_nodes) * n_nodes);
  for (int i = 0; i < n_nodes; ++i) {
    if (!z[i].allFinite()) {
      status.info = Info::non_finite;
      status.node_a = i;
      return;
    }
    for (int j = 0; j < i; ++j) {
      const double d = (z[i] - z[j]).norm();
      if (d < config.coincidence_tolerance) {
        status.info = Info::coincident_nodes;
        status.node_a = j;
        status.node_b = i;
        return;
      }
      distance[static_cast<std::size_t>(i) * n_nodes + j] = d;
    }
  }
  Eigen::MatrixXd P;
  const int degree = carried_degree<Dim>(z, config.degree, config.rank_tolerance, P);
  status.degree_used = degree;
  basis = PolynomialBasis<Dim>(degree);
  n_terms = basis.size();

  const int size = n_nodes + n_terms;
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(size, size);
  for (int i = 0; i < n_nodes; ++i) {
    for (int j = 0; j < i; ++j)
      K(i, j) = K(j, i) = kernel.value(distance[static_cast<std::size_t>(i) * n_nodes + j]);
    for (int t = 0; t < n_terms; ++t) K(i, n_nodes + t) = K(n_nodes + t, i) = P(i, t);
  }
  lu.compute(K);
  matrix = std::move(K);
  if (config.condition_estimate == ConditionEstimate::probes) {
    status.condition = probe_condition(lu, matrix);
  } else {
    // A singular K (a zero pivot) makes the estimate 0 or NaN; both read as an infinite condition.
    const double rcond = lu.rcond();
    status.condition = rcond > 0.0 ? 1.0 / rcond : std::numeric_limits<double>::infinity();
  }
  if (!(status.condition <= config.max_condition)) {
    status.info = Info::singular_system;
    return;
  }
  status.info = degree < config.degree ? Info::degree_reduced : Info::ok;
}

template struct SaddleSystem<2>;
template struct SaddleSystem<3>;

}  // namespace detail

template <int Dim>
void BasisWeights<Dim>::combine(const Operator<Dim>& op, std::vector<double>& out) const {
  LIQUID_VERIFY(status.usable(), "RBF-FD weights unusable: {}", status.describe());
  LIQUID_VERIFY(op.laplacian == 0.0 || status.laplacian_defined,
                "the Laplacian of PHS r^1 is singular at a node on the evaluation point");
  const Eigen::Index n = w.rows();
  out.assign(n, 0.0);
  for (Eigen::Index j = 0; j < n; ++j) {
    double v = op.value * w(j, 0) + op.laplacian * w(j, Dim + 1);
    for (int k = 0; k < Dim; ++k) v += op.gradient[k] * w(j, 1 + k);
    out[j] = v;
  }
}

template <int Dim>
BasisWeights<Dim> basis_weights(std::span<const Vec<Dim>> nodes, const Vec<Dim>& at, const Config& config) {
  BasisWeights<Dim> result;
  const int n = static_cast<int>(nodes.size());
  result.status.n_nodes = n;
  result.status.degree_requested = config.degree;

  double radius = 0.0;
  for (const auto& x : nodes) radius = std::max(radius, (x - at).norm());
  if (!std::isfinite(radius) || !at.allFinite()) {
    result.status.info = Info::non_finite;
    return result;
  }
  if (n == 0 || radius == 0.0) {
    result.status.info = Info::empty_stencil;
    return result;
  }
  std::vector<Vec<Dim>> z(n);
  for (int j = 0; j < n; ++j) z[j] = (nodes[j] - at) / radius;

  detail::SaddleSystem<Dim> system(z, config);
  result.status = system.status;
  if (!system.status.usable()) return result;

  // Right-hand sides: the basic operators applied to phi(|x - z_j|) and p_t(x) at x = 0.
  const int n_terms = system.n_terms;
  Eigen::Matrix<double, Eigen::Dynamic, Dim + 2> rhs(n + n_terms, Dim + 2);
  for (int j = 0; j < n; ++j) {
    const double r = z[j].norm();
    rhs(j, 0) = system.kernel.value(r);
    const double g = system.kernel.gradient_factor(r);
    for (int k = 0; k < Dim; ++k) rhs(j, 1 + k) = -z[j][k] * g;
    double lap = system.kernel.laplacian(r, Dim);
    if (!std::isfinite(lap)) {
      result.status.laplacian_defined = false;
      lap = 0.0;
    }
    rhs(j, Dim + 1) = lap;
  }
  const Vec<Dim> origin = Vec<Dim>::Zero();
  for (int t = 0; t < n_terms; ++t) {
    rhs(n + t, 0) = system.basis.value(t, origin);
    for (int k = 0; k < Dim; ++k) rhs(n + t, 1 + k) = system.basis.derivative(t, k, origin);
    rhs(n + t, Dim + 1) = system.basis.laplacian(t, origin);
  }
  Eigen::Matrix<double, Eigen::Dynamic, Dim + 2> solution = system.solve(rhs);
  result.w = solution.topRows(n);
  result.w.template middleCols<Dim>(1) /= radius;
  result.w.col(Dim + 1) /= radius * radius;
  if (!result.w.allFinite()) {
    result.status.info = Info::non_finite;
    result.w.resize(0, Dim + 2);
  }
  return result;
}

template <int Dim>
Status weights(std::span<const Vec<Dim>> nodes, const Vec<Dim>& at, const Operator<Dim>& op,
               const Config& config, std::vector<double>& out) {
  out.clear();
  BasisWeights<Dim> bw = basis_weights<Dim>(nodes, at, config);
  if (!bw.status.usable()) return bw.status;
  if (op.laplacian != 0.0 && !bw.status.laplacian_defined) {
    bw.status.info = Info::singular_system;
    return bw.status;
  }
  bw.combine(op, out);
  return bw.status;
}

template <int Dim>
Status value_weights(std::span<const Vec<Dim>> nodes, const Vec<Dim>& at, const Config& config,
                     std::vector<double>& out) {
  out.clear();
  Status status;
  const int n = static_cast<int>(nodes.size());
  status.n_nodes = n;
  status.degree_requested = config.degree;
  double radius = 0.0;
  for (const auto& x : nodes) radius = std::max(radius, (x - at).norm());
  if (!std::isfinite(radius) || !at.allFinite()) {
    status.info = Info::non_finite;
    return status;
  }
  if (n == 0 || radius == 0.0) {
    status.info = Info::empty_stencil;
    return status;
  }
  thread_local std::vector<Vec<Dim>> z;
  z.resize(n);
  for (int j = 0; j < n; ++j) z[j] = (nodes[j] - at) / radius;
  detail::SaddleSystem<Dim> system(z, config);
  status = system.status;
  if (!status.usable()) return status;
  // One right-hand side: phi(|z_j|) and the basis at the evaluation point (the origin).
  const int n_terms = system.n_terms;
  Eigen::VectorXd rhs(n + n_terms);
  for (int j = 0; j < n; ++j) rhs[j] = system.kernel.value(z[j].norm());
  const Vec<Dim> origin = Vec<Dim>::Zero();
  for (int t = 0; t < n_terms; ++t) rhs[n + t] = system.basis.value(t, origin);
  const Eigen::VectorXd w = system.solve(rhs);
  if (!w.head(n).allFinite()) {
    status.info = Info::non_finite;
    return status;
  }
  out.assign(w.data(), w.data() + n);
  return status;
}

template struct BasisWeights<2>;
template struct BasisWeights<3>;
template BasisWeights<2> basis_weights<2>(std::span<const Vec<2>>, const Vec<2>&, const Config&);
template BasisWeights<3> basis_weights<3>(std::span<const Vec<3>>, const Vec<3>&, const Config&);
template Status value_weights<2>(std::span<const Vec<2>>, const Vec<2>&, const Config&, std::vector<double>&);
template Status value_weights<3>(std::span<const Vec<3>>, const Vec<3>&, const Config&, std::vector<double>&);
template Status weights<2>(std::span<const Vec<2>>, const Vec<2>&, const Operator<2>&, const Config&,
                           std::vector<double>&);
template Status weights<3>(std::span<const Vec<3>>, const Vec<3>&, const Operator<3>&, const Config&,
                           std::vector<double>&);

}  // namespace liquid::rbf
