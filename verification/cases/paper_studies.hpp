#pragma once
// The paper's Poisson studies as PoissonStudy values, shared by the cases that run them
// (poisson-neumann-*, poisson-dirichlet-levelset-*, poisson-stencil-rules, poisson-rbf-degree).

#include "common/poisson_study.hpp"

namespace liquid::verification {

/// Lap p = f on [0, pi]^Dim, p = prod cos x_k - 1, Neumann walls; narrow band around a circle
/// (sphere) of radius 0.9, base level L and L + 2 (poisson_neumann.cpp).
template <int Dim>
PoissonStudy<Dim> neumann_study(bool full);

/// The level-set Dirichlet problem of poisson_dirichlet_levelset.cpp.
template <int Dim>
PoissonStudy<Dim> dirichlet_study(bool full);

}  // namespace liquid::verification
