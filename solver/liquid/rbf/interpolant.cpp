#include "liquid/rbf/interpolant.hpp"

#include <cmath>
#include <limits>
#include <mutex>
#include <optional>

#include "liquid/core/error.hpp"
#include "liquid/rbf/saddle.hpp"

namespace liquid::rbf {

template <int Dim>
struct Interpolant<Dim>::Factors {
  std::vector<Vec<Dim>> nodes;  // scaled to the unit ball around centre
  Vec<Dim> centre = Vec<Dim>::Zero();
  double radius = 1.0;
  Status status;
  std::optional<detail::SaddleSystem<Dim>> system;
  mutable std::once_flag cell_lebesgue_once;
  mutable double cell_lebesgue = std::numeric_limits<double>::quiet_NaN();
};

template <int Dim>
std::shared_ptr<const typename Interpolant<Dim>::Factors> Interpolant<Dim>::factorise(
    std::span<const Vec<Dim>> nodes, const Config& config) {
  auto f = std::make_shared<Factors>();
  f->nodes.assign(nodes.begin(), nodes.end());
  const int n = static_cast<int>(f->nodes.size());
  f->status.n_nodes = n;
  f->status.degree_requested = config.degree;
  if (n == 0) {
    f->status.info = Info::empty_stencil;
    return f;
  }
  for (const auto& x : f->nodes) f->centre += x;
  f->centre /= n;
  f->radius = 0.0;
  for (const auto& x : f->nodes) f->radius = std::max(f->radius, (x - f->centre).norm());
  if (!std::isfinite(f->radius)) {
    f->status.info = Info::non_finite;
    return f;
  }
  if (f->radius == 0.0) f->radius = 1.0;  // a single node: a constant interpolant
  for (auto& x : f->nodes) x = (x - f->centre) / f->radius;
  f->system.emplace(f->nodes, config);
  f->status = f->system->status;
  return f;
}

template <int Dim>
Interpolant<Dim>::Interpolant(std::span<const Vec<Dim>> nodes, const Config& config)
    : factors_(factorise(nodes, config)) {}

template <int Dim>
Interpolant<Dim>::Interpolant(std::shared_ptr<const Factors> factors, const Vec<Dim>& origin, double scale)
    : factors_(std::move(factors)), origin_(origin), scale_(scale) {
  LIQUID_VERIFY(factors_ != nullptr, "RBF interpolant given no factors");
  LIQUID_VERIFY(scale > 0.0 && std::isfinite(scale), "RBF interpolant scale {} is not positive", scale);
}

template <int Dim>
Interpolant<Dim>::~Interpolant() = default;
template <int Dim>
Interpolant<Dim>::Interpolant(Interpolant&&) noexcept = default;
template <int Dim>
Interpolant<Dim>& Interpolant<Dim>::operator=(Interpolant&&) noexcept = default;

template <int Dim>
const Status& Interpolant<Dim>::status() const {
  return factors_->status;
}

template <int Dim>
int Interpolant<Dim>::n_nodes() const {
  return static_cast<int>(factors_->nodes.size());
}

template <int Dim>
Vec<Dim> Interpolant<Dim>::unit(const Vec<Dim>& x) const {
  return ((x - origin_) / scale_ - factors_->centre) / factors_->radius;
}

template <int Dim>
void Interpolant<Dim>::fit(const Eigen::MatrixXd& values) {
  LIQUID_VERIFY(status().usable(), "RBF interpolant unusable: {}", status().describe());
  LIQUID_VERIFY(values.rows() == n_nodes(), "RBF interpolant has {} nodes but {} value rows were given",
                n_nodes(), values.rows());
  LIQUID_VERIFY(values.allFinite(), "RBF interpolant given non-finite values");
  const int size = n_nodes() + factors_->system->n_terms;
  if (values.cols() == 1) {  // a vector right-hand side takes Eigen's vector kernels, not GEMM's
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(size);
    rhs.head(n_nodes()) = values.col(0);
    coefficients_ = factors_->system->solve(rhs);
    return;
  }
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(size, values.cols());
  rhs.topRows(n_nodes()) = values;
  coefficients_ = factors_->system->solve(rhs);
}

template <int Dim>
Eigen::RowVectorXd Interpolant<Dim>::value(const Vec<Dim>& x) const {
  LIQUID_VERIFY(coefficients_.size() > 0, "RBF interpolant evaluated before fit()");
  const Vec<Dim> z = unit(x);
  const int n = n_nodes();
  const auto& system = *factors_->system;
  Eigen::RowVectorXd out = Eigen::RowVectorXd::Zero(coefficients_.cols());
  for (int j = 0; j < n; ++j)
    out += system.kernel.value((z - factors_->nodes[j]).norm()) * coefficients_.row(j);
  for (int t = 0; t < system.n_terms; ++t) out += system.basis.value(t, z) * coefficients_.row(n + t);
  return out;
}

template <int Dim>
double Interpolant<Dim>::value_at(const Vec<Dim>& x, int column) const {
  LIQUID_VERIFY(coefficients_.size() > 0, "RBF interpolant evaluated before fit()");
  LIQUID_VERIFY(column >= 0 && column < coefficients_.cols(), "RBF interpolant has no field {}", column);
  const Vec<Dim> z = unit(x);
  const int n = n_nodes();
  const auto& system = *factors_->system;
  double out = 0.0;
  for (int j = 0; j < n; ++j)
    out += system.kernel.value((z - factors_->nodes[j]).norm()) * coefficients_(j, column);
  for (int t = 0; t < system.n_terms; ++t) out += system.basis.value(t, z) * coefficients_(n + t, column);
  return out;
}

template <int Dim>
Eigen::MatrixXd Interpolant<Dim>::gradient(const Vec<Dim>& x) const {
  LIQUID_VERIFY(coefficients_.size() > 0, "RBF interpolant evaluated before fit()");
  const Vec<Dim> z = unit(x);
  const int n = n_nodes();
  const auto& system = *factors_->system;
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(Dim, coefficients_.cols());
  for (int j = 0; j < n; ++j) {
    const Vec<Dim> d = z - factors_->nodes[j];
    const double g = system.kernel.gradient_factor(d.norm());
    for (int k = 0; k < Dim; ++k) out.row(k) += g * d[k] * coefficients_.row(j);
  }
  for (int t = 0; t < system.n_terms; ++t)
    for (int k = 0; k < Dim; ++k) out.row(k) += system.basis.derivative(t, k, z) * coefficients_.row(n + t);
  return out / (factors_->radius * scale_);
}

template <int Dim>
double Interpolant<Dim>::value_and_gradient(const Vec<Dim>& x, int column, double* grad) const {
  LIQUID_VERIFY(coefficients_.size() > 0, "RBF interpolant evaluated before fit()");
  LIQUID_VERIFY(column >= 0 && column < coefficients_.cols(), "RBF interpolant has no field {}", column);
  const Vec<Dim> z = unit(x);
  const int n = n_nodes();
  const auto& system = *factors_->system;
  double value = 0.0;
  Vec<Dim> g = Vec<Dim>::Zero();
  for (int j = 0; j < n; ++j) {
    const Vec<Dim> d = z - factors_->nodes[j];
    const double r = d.norm();
    const double c = coefficients_(j, column);
    value += system.kernel.value(r) * c;
    const double factor = system.kernel.gradient_factor(r);
    for (int k = 0; k < Dim; ++k) g[k] += factor * d[k] * c;
  }
  for (int t = 0; t < system.n_terms; ++t) {
    const double c = coefficients_(n + t, column);
    value += system.basis.value(t, z) * c;
    for (int k = 0; k < Dim; ++k) g[k] += system.basis.derivative(t, k, z) * c;
  }
  const double scale = factors_->radius * scale_;
  for (int k = 0; k < Dim; ++k) grad[k] = g[k] / scale;
  return value;
}

template <int Dim>
double Interpolant<Dim>::lebesgue(std::span<const Vec<Dim>> points) const {
  LIQUID_VERIFY(status().usable(), "RBF interpolant unusable: {}", status().describe());
  const int n = n_nodes();
  const auto& system = *factors_->system;
  const int size = n + system.n_terms;
  // The saddle matrix is symmetric, so the cardinal functions' values at x are the first n entries
  // of its inverse applied to (phi(|x - x_j|), p_t(x)).
  Eigen::MatrixXd rhs(size, static_cast<Eigen::Index>(points.size()));
  for (std::size_t k = 0; k < points.size(); ++k) {
    const Vec<Dim> z = unit(points[k]);
    for (int j = 0; j < n; ++j) rhs(j, k) = system.kernel.value((z - factors_->nodes[j]).norm());
    for (int t = 0; t < system.n_terms; ++t) rhs(n + t, k) = system.basis.value(t, z);
  }
  const Eigen::MatrixXd w = system.solve(rhs);
  double largest = 0.0;
  for (Eigen::Index k = 0; k < w.cols(); ++k) largest = std::max(largest, w.col(k).head(n).cwiseAbs().sum());
  return largest;
}

template <int Dim>
double Interpolant<Dim>::cell_lebesgue() const {
  std::call_once(factors_->cell_lebesgue_once, [&] {
    std::vector<Vec<Dim>> lattice;
    constexpr int count = Dim == 2 ? 9 : 27;
    for (int k = 0; k < count; ++k) {
      Vec<Dim> u;
      for (int a = 0, r = k; a < Dim; ++a, r /= 3) u[a] = 0.5 * (r % 3) - 0.5;
      lattice.push_back(origin_ + scale_ * u);
    }
    factors_->cell_lebesgue = lebesgue(lattice);
  });
  return factors_->cell_lebesgue;
}

template class Interpolant<2>;
template class Interpolant<3>;

}  // namespace liquid::rbf
