#pragma once
// Observed orders of convergence.

#include <span>

namespace liquid::verification {

/// Least-squares slope of log2(error) against log2(h) (GSL's linear fit). Points with a
/// non-positive or non-finite error or h are skipped; NaN when fewer than two remain.
double fit_order(std::span<const double> h, std::span<const double> error);

/// Order between two successive rows: log2(e_coarse / e_fine) / log2(h_coarse / h_fine).
double pair_order(double h_coarse, double e_coarse, double h_fine, double e_fine);

}  // namespace liquid::verification
