#include "fit.hpp"

#include <cmath>
#include <limits>
#include <vector>

#include <gsl/gsl_fit.h>

namespace liquid::verification {

double fit_order(std::span<const double> h, std::span<const double> error) {
  std::vector<double> x, y;
  for (std::size_t i = 0; i < h.size() && i < error.size(); ++i) {
    if (!(h[i] > 0.0) || !(error[i] > 0.0) || !std::isfinite(h[i]) || !std::isfinite(error[i])) continue;
    x.push_back(std::log2(h[i]));
    y.push_back(std::log2(error[i]));
  }
  if (x.size() < 2) return std::numeric_limits<double>::quiet_NaN();
  double c0, c1, cov00, cov01, cov11, sumsq;
  gsl_fit_linear(x.data(), 1, y.data(), 1, x.size(), &c0, &c1, &cov00, &cov01, &cov11, &sumsq);
  return c1;
}

double pair_order(double h_coarse, double e_coarse, double h_fine, double e_fine) {
  if (!(e_coarse > 0.0) || !(e_fine > 0.0) || !(h_coarse > h_fine) || !(h_fine > 0.0))
    return std::numeric_limits<double>::quiet_NaN();
  return std::log2(e_coarse / e_fine) / std::log2(h_coarse / h_fine);
}

}  // namespace liquid::verification
