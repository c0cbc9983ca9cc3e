// Cases poisson-neumann-2d and poisson-neumann-3d (paper Figs. 14 and 15).
//
// Problem. Lap p = f on [0, pi]^d with homogeneous Neumann walls, exact solution
//   p = cos x cos y - 1            (2D),     p = cos x cos y cos z - 1     (3D),
// so f = -d (p + 1). The system is singular; one unknown near the centre is pinned to the exact
// value, as the paper does.
// Tree. Non-graded: base level L everywhere and level L + 2 in a narrow band around a circle
// (sphere) of radius 0.9 centred in the domain, as coarse as the level-jump limit (2 by default)
// allows in between, so level jumps of 2 meet at T-junctions. Each row splits every cell of the
// first row's tree once more (the paper's recursive subdivision), so every level shifts by one and
// the band stays where it is; --rows rebuild instead builds each row's band afresh (its width
// counted in finest cells). Levels (base, quick / full): 2D 5:8 / 5:9, 3D 3:4 / 3:5.
// Expected: L-inf order >= 1.9 for p and >= 1.8 for dp/dn at faces (the paper shows about 2).

#include "studies/paper_studies.hpp"

namespace liquid::verification {
namespace {

CaseResult run2(const CaseOptions& o) {
  return run_poisson_study<2>(neumann_study<2>(o.full), o);
}
CaseResult run3(const CaseOptions& o) {
  return run_poisson_study<3>(neumann_study<3>(o.full), o);
}

}  // namespace

LIQUID_VERIFICATION_CASE({"poisson-neumann-2d",
                          "Lap p = f, p = cos x cos y - 1 on [0,pi]^2, Neumann, non-graded quadtree", true,
                          run2, poisson_study_options});
LIQUID_VERIFICATION_CASE({"poisson-neumann-3d",
                          "Lap p = f, p = cos x cos y cos z - 1 on [0,pi]^3, Neumann, non-graded octree",
                          true, run3, poisson_study_options});

}  // namespace liquid::verification
