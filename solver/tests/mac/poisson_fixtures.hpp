#pragma once
// Shared by the PPE tests: a non-graded tree refined around a sphere, a quadratic p that every
// consistent row reproduces exactly, and the direct solution's distance from it.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "liquid/levelset/levelset.hpp"
#include "liquid/mac/poisson.hpp"
#include "liquid/tree/builders.hpp"

namespace liquid::mac::testing {

/// Levels `level` to `level + 2` around a sphere of radius 0.55, level jumps up to 2.
template <int Dim>
tree::CellGraph<Dim> non_graded(int level, double half_width = 1.0) {
  const Box<Dim> domain{Vec<Dim>::Constant(-half_width), Vec<Dim>::Constant(half_width)};
  tree::CellGraphOptions<Dim> options;
  options.max_jump = 2;
  return tree::narrow_band<Dim>(domain, levelset::sphere<Dim>(Vec<Dim>::Constant(0.1), 0.55), level,
                                level + 2, 2.0, options);
}

// p = 1 + x - 2y + x^2 + 0.5 xy - y^2 (+ 0.7 z^2 - yz in 3D): quadratic, Lap p = 2 - 2 (+ 1.4).
template <int Dim>
double quad(const Vec<Dim>& x) {
  double p = 1 + x[0] - 2 * x[1] + x[0] * x[0] + 0.5 * x[0] * x[1] - x[1] * x[1];
  if constexpr (Dim == 3) p += 0.7 * x[2] * x[2] - x[1] * x[2];
  return p;
}

// The L-inf distance of the direct solution of `sys` from quad at the unknowns' centres; the
// solution goes to `solution` when given.
template <int Dim>
double direct_error_against_quad(const tree::CellGraph<Dim>& graph, const PoissonSystem<Dim>& sys,
                                 linalg::Vector* solution = nullptr) {
  linalg::Vector p;
  const auto st = linalg::solve(sys.A, sys.b, p, {linalg::SolverKind::direct});
  EXPECT_TRUE(st.converged()) << st.describe();
  if (!st.converged()) return std::numeric_limits<double>::infinity();
  double err = 0.0;
  for (long i = 0; i < sys.n_unknowns(); ++i)
    err = std::max(err, std::abs(p[i] - quad<Dim>(graph.centre(sys.layout.cell_of_dof[i]))));
  if (solution) *solution = p;
  return err;
}

}  // namespace liquid::mac::testing
