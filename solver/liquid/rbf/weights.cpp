#include "liquid/rbf/weights.hpp"

#include <algorithm>
#include <array>
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
/// A zero pivot gives an infinite or NaN image: an infinite condition. `solve(probe)` applies K^-1
/// to the n x 2 probe in place (Eigen's LU or SmallLu).
template <class Matrix, class Solve>
double probe_condition(const Matrix& K, Solve&& solve) {
  const Eigen::Index n = K.rows();
  Eigen::Matrix<double, Eigen::Dynamic, 2> probe(n, 2);
  for (Eigen::Index i = 0; i < n; ++i) {
    probe(i, 0) = 1.0 / static_cast<double>(n);
    const double ramp = n > 1 ? static_cast<double>(i) / static_cast<double>(n - 1) : 0.0;
    probe(i, 1) = (i % 2 == 0 ? 1.0 : -1.0) * (1.0 + ramp);
  }
  solve(probe);
  if (!probe.allFinite()) return std::numeric_limits<double>::infinity();
  const double inverse =
      std::max(probe.col(0).lpNorm<1>(), 2.0 * probe.col(1).lpNorm<1>() / (3.0 * static_cast<double>(n)));
  return K.cwiseAbs().colwise().sum().maxCoeff() * inverse;
}

/// The saddle matrix [A P; P^T 0] into K (size n + n_terms, zeroed by the caller), with A_ij the
/// kernel at distance[i * n + j] (j < i; 0 on the diagonal) and P the first n_terms columns of `P`.
template <class Matrix>
void fill_saddle(Matrix& K, const std::vector<double>& distance, const Eigen::MatrixXd& P, int n, int n_terms,
                 const Phs& kernel) {
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < i; ++j)
      K(i, j) = K(j, i) = kernel.value(distance[static_cast<std::size_t>(i) * n + j]);
    for (int t = 0; t < n_terms; ++t) K(i, n + t) = K(n + t, i) = P(i, t);
  }
}

/// Sets status.info from the condition estimate and the degree carried.
void judge(Status& status, int degree, const Config& config) {
  if (!(status.condition <= config.max_condition))
    status.info = Info::singular_system;
  else
    status.info = degree < config.degree ? Info::degree_reduced : Info::ok;
}

/// The distances |z_i - z_j| for j < i, at distance[i * n + j]. False, with the status set, when a
/// node is not finite or two nodes are closer than the coincidence tolerance.
template <int Dim>
bool pairwise_distances(std::span<const Vec<Dim>> z, const Config& config, Status& status,
                        std::vector<double>& distance) {
  const int n = static_cast<int>(z.size());
  distance.resize(static_cast<std::size_t>(n) * n);
  for (int i = 0; i < n; ++i) {
    if (!z[i].allFinite()) {
      status.info = Info::non_finite;
      status.node_a = i;
      return false;
    }
    for (int j = 0; j < i; ++j) {
      const double d = (z[i] - z[j]).norm();
      if (d < config.coincidence_tolerance) {
        status.info = Info::coincident_nodes;
        status.node_a = j;
        status.node_b = i;
        return false;
      }
      distance[static_cast<std::size_t>(i) * n + j] = d;
    }
  }
  return true;
}

/// LU with partial pivoting of a small dense matrix held on the stack, for value_weights' one
/// saddle system per face: below some 40 unknowns Eigen's blocked LU spends more in packing and
/// kernel calls than in arithmetic (a 20 x 20 system took about twice as long). Column-major; the
/// same pivot rule as Eigen's (the first largest magnitude in the column).
class SmallLu {
 public:
  static constexpr int capacity = 48;

  /// Copies the leading n x n block of `k` (column-major, leading dimension n) and factorises it.
  void factorise(const double* k, int n) {
    n_ = n;
    std::copy_n(k, static_cast<std::size_t>(n) * n, a_.begin());
    for (int c = 0; c < n; ++c) {
      double* col = &a_[static_cast<std::size_t>(c) * n];
      int pivot = c;
      double largest = std::abs(col[c]);
      for (int i = c + 1; i < n; ++i)
        if (std::abs(col[i]) > largest) largest = std::abs(col[i]), pivot = i;
      swap_[c] = pivot;
      if (pivot != c)
        for (int j = 0; j < n; ++j)
          std::swap(a_[static_cast<std::size_t>(j) * n + c], a_[static_cast<std::size_t>(j) * n + pivot]);
      // A zero pivot is left in place: the solves then give infinities, which the condition
      // estimate reads as a singular system.
      if (col[c] != 0.0) {
        const double inverse = 1.0 / col[c];
        for (int i = c + 1; i < n; ++i) col[i] *= inverse;
      }
      for (int j = c + 1; j < n; ++j) {
        double* cj = &a_[static_cast<std::size_t>(j) * n];
        const double f = cj[c];
        if (f == 0.0) continue;
        for (int i = c + 1; i < n; ++i) cj[i] -= col[i] * f;
      }
    }
  }
  /// Solves in place.
  void solve(double* b) const {
    const int n = n_;
    for (int c = 0; c < n; ++c)
      if (swap_[c] != c) std::swap(b[c], b[swap_[c]]);
    for (int c = 0; c < n; ++c) {
      const double* col = &a_[static_cast<std::size_t>(c) * n];
      const double f = b[c];
      if (f != 0.0)
        for (int i = c + 1; i < n; ++i) b[i] -= col[i] * f;
    }
    for (int c = n - 1; c >= 0; --c) {
      const double* col = &a_[static_cast<std::size_t>(c) * n];
      b[c] /= col[c];
      const double f = b[c];
      for (int i = 0; i < c; ++i) b[i] -= col[i] * f;
    }
  }

 private:
  int n_ = 0;
  std::array<double, static_cast<std::size_t>(capacity) * capacity> a_;
  std::array<int, capacity> swap_;
};

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
  if (!pairwise_distances<Dim>(z, config, status, distance)) return;
  Eigen::MatrixXd P;
  const int degree = carried_degree<Dim>(z, config.degree, config.rank_tolerance, P);
  status.degree_used = degree;
  basis = PolynomialBasis<Dim>(degree);
  n_terms = basis.size();

  const int size = n_nodes + n_terms;
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(size, size);
  fill_saddle(K, distance, P, n_nodes, n_terms, kernel);
  lu.compute(K);
  matrix = std::move(K);
  if (config.condition_estimate == ConditionEstimate::probes) {
    status.condition = probe_condition(matrix, [&](auto& probe) { probe = lu.solve(probe).eval(); });
  } else {
    // A singular K (a zero pivot) makes the estimate 0 or NaN; both read as an infinite condition.
    const double rcond = lu.rcond();
    status.condition = rcond > 0.0 ? 1.0 / rcond : std::numeric_limits<double>::infinity();
  }
  judge(status, degree, config);
}

/// value_weights on nodes already in the unit ball, for systems of at most SmallLu::capacity
/// unknowns: the saddle system of SaddleSystem (the same degree rule, condition test and one step of
/// iterative refinement) factorised by SmallLu. `status` comes in with the node count and the
/// requested degree.
template <int Dim>
Status small_value_weights(std::span<const Vec<Dim>> z, const Config& config, Status status,
                           std::vector<double>& out) {
  const int n = static_cast<int>(z.size());
  thread_local std::vector<double> distance;
  if (!pairwise_distances<Dim>(z, config, status, distance)) return status;
  thread_local Eigen::MatrixXd P;
  const int degree = carried_degree<Dim>(z, config.degree, config.rank_tolerance, P);
  status.degree_used = degree;
  const PolynomialBasis<Dim> basis(degree);
  const Phs kernel(config.exponent);
  const int n_terms = basis.size();
  const int size = n + n_terms;
  thread_local std::array<double, static_cast<std::size_t>(SmallLu::capacity) * SmallLu::capacity> k;
  Eigen::Map<Eigen::MatrixXd> K(k.data(), size, size);
  K.setZero();
  fill_saddle(K, distance, P, n, n_terms, kernel);
  thread_local SmallLu lu;
  lu.factorise(k.data(), size);
  if (config.condition_estimate == ConditionEstimate::probes) {
    status.condition = probe_condition(K, [&](auto& probe) {
      lu.solve(probe.col(0).data());
      lu.solve(probe.col(1).data());
    });
  } else {
    // Only the estimate comes from Eigen's LU, so that the weights do not depend on the estimate.
    const double rcond = Eigen::PartialPivLU<Eigen::MatrixXd>(K).rcond();
    status.condition = rcond > 0.0 ? 1.0 / rcond : std::numeric_limits<double>::infinity();
  }
  judge(status, degree, config);
  if (status.info == Info::singular_system) return status;
  // One right-hand side: phi(|z_j|) and the basis at the evaluation point (the origin), then one
  // step of iterative refinement against the matrix itself.
  std::array<double, SmallLu::capacity> rhs, x, r;
  for (int j = 0; j < n; ++j) rhs[j] = kernel.value(z[j].norm());
  const Vec<Dim> origin = Vec<Dim>::Zero();
  for (int t = 0; t < n_terms; ++t) rhs[n + t] = basis.value(t, origin);
  std::copy_n(rhs.begin(), size, x.begin());
  lu.solve(x.data());
  std::copy_n(rhs.begin(), size, r.begin());
  for (int j = 0; j < size; ++j) {
    const double xj = x[j];
    for (int i = 0; i < size; ++i) r[i] -= K(i, j) * xj;
  }
  lu.solve(r.data());
  for (int i = 0; i < size; ++i) x[i] += r[i];
  for (int j = 0; j < n; ++j)
    if (!std::isfinite(x[j])) {
      status.info = Info::non_finite;
      return status;
    }
  out.assign(x.begin(), x.begin() + n);
  return status;
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
  if (n + n_polynomial_terms(Dim, std::min(std::max(config.degree, 0), 4)) <= detail::SmallLu::capacity)
    return detail::small_value_weights<Dim>(z, config, status, out);
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
