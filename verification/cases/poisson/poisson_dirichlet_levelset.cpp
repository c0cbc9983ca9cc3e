// Cases poisson-dirichlet-levelset-2d (paper Fig. 17) and poisson-dirichlet-levelset-3d (new).
//
// Problem. Lap p = f with the exact solution
//   2D: p = (y - x^2 + 1)^4 + (x^2 + y^2) - 1          on [-1.5, 1.5] x [-1.75, 1.25],
//   3D: p = (z - x^2 - y^2 + 1)^4 + (x^2 + y^2 + z^2) - 1  on [-1.5, 1.5]^2 x [-1.75, 1.25],
// and the interface S = {p = 0}: unknowns at the cell centres inside S (p < 0), p = 0 on S imposed
// at the points where stencil edges cross S (second order: Shortley-Weller in FD rows, crossing
// points as RBF-FD nodes elsewhere). With u = y - x^2 + 1 (2D) or u = z - x^2 - y^2 + 1 (3D):
//   2D: f = 48 x^2 u^2 - 8 u^3 + 12 u^2 + 4,
//   3D: f = 48 (x^2 + y^2) u^2 - 16 u^3 + 12 u^2 + 6.
// Tree. Base level L, level L + 2 in a narrow band around S (up to 2 levels between neighbours).
// Later rows split every cell of the first row's tree once more (the paper's recursive
// subdivision); --rows rebuild builds each row's tree afresh instead.
// Levels (base, quick / full): 2D 7:10 / 7:11, 3D 4:5 / 4:6. The 3D study is pre-asymptotic from
// base level 3 (docs/findings/poisson-convergence.md), so it starts at 4.
// Expected: L-inf order >= 1.9 for p and >= 1.8 for dp/dn at faces between unknowns.

#include "studies/paper_studies.hpp"

namespace liquid::verification {
namespace {

CaseResult run2(const CaseOptions& o) {
  return run_poisson_study<2>(dirichlet_study<2>(o.full), o);
}
CaseResult run3(const CaseOptions& o) {
  return run_poisson_study<3>(dirichlet_study<3>(o.full), o);
}

}  // namespace

LIQUID_VERIFICATION_CASE({"poisson-dirichlet-levelset-2d",
                          "Lap p = f inside S = {p = 0}, p = 0 on S at stencil-edge crossings, quadtree",
                          true, run2, poisson_study_options});
LIQUID_VERIFICATION_CASE({"poisson-dirichlet-levelset-3d",
                          "Lap p = f inside S = {p = 0}, p = 0 on S at stencil-edge crossings, octree", true,
                          run3, poisson_study_options});

}  // namespace liquid::verification
