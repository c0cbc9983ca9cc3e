#include "liquid/rbf/interpolant.hpp"

#include "liquid/core/error.hpp"
#include "liquid/rbf/saddle.hpp"

namespace liquid::rbf {

template <int Dim>
Interpolant<Dim>::Interpolant(std::span<const Vec<Dim>> nodes, const Config& config)
    : nodes_(nodes.begin(), nodes.end()), centre_(Vec<Dim>::Zero()) {
  status_.n_nodes = n_nodes();
  status_.degree_requested = config.degree;
  if (nodes_.empty()) {
    status_.info = Info::empty_stencil;
    return;
  }
  for (const auto& x : nodes_) centre_ += x;
  centre_ /= n_nodes();
  radius_ = 0.0;
  for (const auto& x : nodes_) radius_ = std::max(radius_, (x - centre_).norm());
  if (!std::isfinite(radius_)) {
    status_.info = Info::non_finite;
    return;
  }
  if (radius_ == 0.0) radius_ = 1.0;  // a single node: a constant interpolant
  for (auto& x : nodes_) x = (x - centre_) / radius_;
  system_ = std::make_unique<detail::SaddleSystem<Dim>>(nodes_, config);
  status_ = system_->status;
}

template <int Dim>
Interpolant<Dim>::~Interpolant() = default;
template <int Dim>
Interpolant<Dim>::Interpolant(Interpolant&&) noexcept = default;
template <int Dim>
Interpolant<Dim>& Interpolant<Dim>::operator=(Interpolant&&) noexcept = default;

template <int Dim>
void Interpolant<Dim>::fit(const Eigen::MatrixXd& values) {
  LIQUID_VERIFY(status_.usable(), "RBF interpolant unusable: {}", status_.describe());
  LIQUID_VERIFY(values.rows() == n_nodes(), "RBF interpolant has {} nodes but {} value rows were given",
                n_nodes(), values.rows());
  LIQUID_VERIFY(values.allFinite(), "RBF interpolant given non-finite values");
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n_nodes() + system_->n_terms, values.cols());
  rhs.topRows(n_nodes()) = values;
  coefficients_ = system_->solve(rhs);
}

template <int Dim>
Eigen::RowVectorXd Interpolant<Dim>::value(const Vec<Dim>& x) const {
  LIQUID_VERIFY(coefficients_.size() > 0, "RBF interpolant evaluated before fit()");
  const Vec<Dim> z = (x - centre_) / radius_;
  const int n = n_nodes();
  Eigen::RowVectorXd out = Eigen::RowVectorXd::Zero(coefficients_.cols());
  for (int j = 0; j < n; ++j) out += system_->kernel.value((z - nodes_[j]).norm()) * coefficients_.row(j);
  for (int t = 0; t < system_->n_terms; ++t) out += system_->basis.value(t, z) * coefficients_.row(n + t);
  return out;
}

template <int Dim>
double Interpolant<Dim>::value_at(const Vec<Dim>& x, int column) const {
  LIQUID_VERIFY(coefficients_.size() > 0, "RBF interpolant evaluated before fit()");
  LIQUID_VERIFY(column >= 0 && column < coefficients_.cols(), "RBF interpolant has no field {}", column);
  const Vec<Dim> z = (x - centre_) / radius_;
  const int n = n_nodes();
  double out = 0.0;
  for (int j = 0; j < n; ++j) out += system_->kernel.value((z - nodes_[j]).norm()) * coefficients_(j, column);
  for (int t = 0; t < system_->n_terms; ++t) out += system_->basis.value(t, z) * coefficients_(n + t, column);
  return out;
}

template <int Dim>
Eigen::MatrixXd Interpolant<Dim>::gradient(const Vec<Dim>& x) const {
  LIQUID_VERIFY(coefficients_.size() > 0, "RBF interpolant evaluated before fit()");
  const Vec<Dim> z = (x - centre_) / radius_;
  const int n = n_nodes();
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(Dim, coefficients_.cols());
  for (int j = 0; j < n; ++j) {
    const Vec<Dim> d = z - nodes_[j];
    const double g = system_->kernel.gradient_factor(d.norm());
    for (int k = 0; k < Dim; ++k) out.row(k) += g * d[k] * coefficients_.row(j);
  }
  for (int t = 0; t < system_->n_terms; ++t)
    for (int k = 0; k < Dim; ++k) out.row(k) += system_->basis.derivative(t, k, z) * coefficients_.row(n + t);
  return out / radius_;
}

template class Interpolant<2>;
template class Interpolant<3>;

}  // namespace liquid::rbf
