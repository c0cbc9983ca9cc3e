#include "liquid/transfer/mls.hpp"

#include <Eigen/QR>

#include <algorithm>
#include <cmath>

#include "liquid/core/error.hpp"
#include "liquid/rbf/polynomial.hpp"

namespace liquid::transfer {

template <int Dim>
int mls_weights(std::span<const Vec<Dim>> nodes, const Vec<Dim>& at, int degree, std::vector<double>& out) {
  LIQUID_VERIFY(degree >= 0 && degree <= 4, "MLS: degree {} is outside [0, 4]", degree);
  const int n = static_cast<int>(nodes.size());
  out.assign(n, 0.0);
  if (n == 0) return -1;
  double far = 0.0;
  for (const auto& x : nodes) far = std::max(far, (x - at).norm());
  if (!(far > 0.0)) {  // every node on the evaluation point
    std::fill(out.begin(), out.end(), 1.0 / n);
    return 0;
  }
  const double radius = 1.5 * far;
  Eigen::VectorXd sqrt_theta(n);
  for (int i = 0; i < n; ++i) {
    const double q = (nodes[i] - at).squaredNorm() / (radius * radius);
    sqrt_theta[i] = (1.0 - q) * (1.0 - q);  // sqrt of (1 - q)^4
  }
  for (int m = std::min(degree, 4); m >= 0; --m) {
    const rbf::PolynomialBasis<Dim> basis(m);
    const int t = basis.size();
    if (t > n) continue;
    Eigen::MatrixXd a(n, t);
    for (int i = 0; i < n; ++i) {
      const Vec<Dim> z = (nodes[i] - at) / far;  // the value at `at` is the constant coefficient
      for (int j = 0; j < t; ++j) a(i, j) = sqrt_theta[i] * basis.value(j, z);
    }
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(a);
    qr.setThreshold(1e-10);
    if (qr.rank() < t) continue;
    // value = e_0^T (A^T A)^-1 A^T diag(sqrt_theta) u: solve A^T A g = e_0 through the QR, w =
    // diag(sqrt_theta) A g.
    Eigen::VectorXd e0 = Eigen::VectorXd::Zero(t);
    e0[0] = 1.0;
    const Eigen::MatrixXd r = qr.matrixR().topLeftCorner(t, t).template triangularView<Eigen::Upper>();
    // A P = Q R  =>  A^T A = P R^T R P^T  =>  g = P R^-1 R^-T P^T e0.
    Eigen::VectorXd y = qr.colsPermutation().transpose() * e0;
    y = r.transpose().template triangularView<Eigen::Lower>().solve(y);
    y = r.template triangularView<Eigen::Upper>().solve(y);
    const Eigen::VectorXd g = qr.colsPermutation() * y;
    const Eigen::VectorXd w = a * g;
    for (int i = 0; i < n; ++i) out[i] = sqrt_theta[i] * w[i];
    return m;
  }
  std::fill(out.begin(), out.end(), 1.0 / n);  // unreachable for n >= 1 (degree 0 has rank 1)
  return 0;
}

template int mls_weights<2>(std::span<const Vec<2>>, const Vec<2>&, int, std::vector<double>&);
template int mls_weights<3>(std::span<const Vec<3>>, const Vec<3>&, int, std::vector<double>&);

}  // namespace liquid::transfer
