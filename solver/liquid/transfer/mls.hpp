#pragma once
// Moving least squares weights (the reconstruction of HOPIC, Edwards & Bridson 2012): the value at
// `at` of the polynomial of total degree `degree` fitted to the nodes by least squares with the
// weight theta(r) = (1 - (r/R)^2)^4, R = 1.5 times the largest node distance from `at`. The value is
// a linear combination of the node values; these are its weights. The degree is lowered until the
// weighted Vandermonde matrix has full column rank.

#include <span>
#include <vector>

#include "liquid/core/types.hpp"

namespace liquid::transfer {

/// Weights (out, one per node) and returns the degree used, -1 when there are no nodes.
template <int Dim>
int mls_weights(std::span<const Vec<Dim>> nodes, const Vec<Dim>& at, int degree, std::vector<double>& out);

}  // namespace liquid::transfer
