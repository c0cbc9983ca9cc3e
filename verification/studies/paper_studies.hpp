#pragma once
// The paper's Poisson studies as PoissonStudy values, shared by the cases that run them
// (poisson-neumann-*, poisson-dirichlet-levelset-*, poisson-stencil-rules, poisson-rbf-degree,
// and the solver comparisons). Each case file states its problem; the values are made here once.

#include "studies/poisson_study.hpp"

namespace liquid::verification {

/// The paper's PPE solver comparison (Sec. 6): an adaptive solver against the regular one at the
/// same finest h, with the paper's claim; the last pair (AMG on both sides) is ours.
struct SolverPair {
  linalg::SolverKind adaptive, regular;
  const char* claim;
};
inline const SolverPair kPaperSolverPairs[] = {
    {linalg::SolverKind::bicgstab_jacobi, linalg::SolverKind::cg_jacobi, "2.6x faster"},
    {linalg::SolverKind::bicgstab_ilut, linalg::SolverKind::cg_ic, "2.5x faster, 3x fewer iterations"},
    {linalg::SolverKind::bicgstab_amg, linalg::SolverKind::cg_amg, "(not in the paper)"}};

/// Lap p = f on [0, pi]^Dim, p = prod cos x_k - 1, Neumann walls; a narrow band (base level L,
/// L + 2 within 2 finest cells) around a circle (sphere) of radius 0.9 at the centre; rows refine
/// the first tree. Levels 2D 5:8 (full 5:9), 3D 3:4 (full 3:5).
template <int Dim>
PoissonStudy<Dim> neumann_study(bool full);

/// Lap p = f inside S = {p = 0} for p = support::quartic_bowl, p = 0 on S; a narrow band around S
/// measured in p / |grad p|; rows refine the first tree. Levels 2D 7:10 (full 7:11), 3D 4:5 (4:6).
template <int Dim>
PoissonStudy<Dim> dirichlet_study(bool full);

}  // namespace liquid::verification
