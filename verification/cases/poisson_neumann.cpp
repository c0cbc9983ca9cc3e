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

#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "cases/paper_studies.hpp"
#include "common/fit.hpp"
#include "common/poisson_study.hpp"
#include "liquid/levelset/levelset.hpp"
#include "liquid/tree/builders.hpp"

namespace liquid::verification {
namespace {}  // namespace

template <int Dim>
PoissonStudy<Dim> neumann_study(bool full) {
  PoissonStudy<Dim> s;
  s.domain = Box<Dim>{Vec<Dim>::Zero(), Vec<Dim>::Constant(std::numbers::pi)};
  s.exact = [](const Vec<Dim>& x) {
    double p = 1.0;
    for (int k = 0; k < Dim; ++k) p *= std::cos(x[k]);
    return p - 1.0;
  };
  s.gradient = [](const Vec<Dim>& x) {
    Vec<Dim> g;
    for (int k = 0; k < Dim; ++k) {
      g[k] = -std::sin(x[k]);
      for (int j = 0; j < Dim; ++j)
        if (j != k) g[k] *= std::cos(x[j]);
    }
    return g;
  };
  s.laplacian = [](const Vec<Dim>& x) {
    double p = 1.0;
    for (int k = 0; k < Dim; ++k) p *= std::cos(x[k]);
    return -Dim * p;
  };
  const auto circle = levelset::sphere<Dim>(Vec<Dim>::Constant(0.5 * std::numbers::pi), 0.9);
  const Box<Dim> domain = s.domain;
  s.make_tree = [domain, circle](int level, const CellGraphOptions<Dim>& options) {
    return tree::narrow_band<Dim>(domain, circle, level, level + 2, 2.0, options);
  };
  s.self_similar = true;
  if (Dim == 2)
    s.level_min = 5, s.level_max = full ? 9 : 8;
  else
    s.level_min = 3, s.level_max = full ? 5 : 4;
  return s;
}
template PoissonStudy<2> neumann_study<2>(bool);
template PoissonStudy<3> neumann_study<3>(bool);

namespace {

// Which irregular-stencil rule gives the best L-inf? The same study under each rule.
template <int Dim>
void compare_rules(int level_min, int level_max, Table& table, CaseResult& result) {
  for (const auto rule : {mac::StencilRule::nearest, mac::StencilRule::face_grown, mac::StencilRule::ring}) {
    PoissonStudy<Dim> s = neumann_study<Dim>(false);
    s.discretisation.rule = rule;
    s.level_min = level_min, s.level_max = level_max;
    const auto runs = solve_rows<Dim>(s, result, fmt::format("{}D {}", Dim, mac::to_string(rule)));
    if (runs.empty()) continue;
    std::vector<double> hs, ep, eg;
    for (const auto& r : runs) hs.push_back(r.h), ep.push_back(r.err_p), eg.push_back(r.err_grad);
    const double assembly = runs.back().assembly_seconds;
    const long rbf_rows = runs.back().assembly.n_rbf_rows, unknowns = runs.back().n_unknowns;
    const std::string key = fmt::format("{}D {}", Dim, mac::to_string(rule));
    result.gate.push_back({key + " finest err p", GateFigure::Kind::error, ep.back()});
    result.gate.push_back({key + " finest err dp/dn", GateFigure::Kind::error, eg.back()});
    table.add_row({long(Dim), std::string(mac::to_string(rule)), fmt::format("{}:{}", level_min, level_max),
                   unknowns, rbf_rows, ep.back(), fit_order(hs, ep), eg.back(), fit_order(hs, eg), assembly});
  }
}

CaseResult run_rules(const CaseOptions& o) {
  CaseResult result;
  Table table("Neumann problem under each stencil rule (finest row; orders fitted over the rows)",
              {"dim", "rule", "levels", "unknowns", "rbf rows", "err p", "order p", "err dp/dn",
               "order dp/dn", "assembly s"});
  compare_rules<2>(5, o.full ? 8 : 7, table, result);
  compare_rules<3>(2, o.full ? 4 : 3, table, result);
  result.tables.push_back(std::move(table));
  result.notes.push_back(
      "nearest: the N cells nearest the centre; face-grown: face neighbours, then the nearest of "
      "the next ring; ring: whole k-rings until N (N = 2 x polynomial terms + 1). The default is "
      "the rule with the smallest errors here.");
  return result;
}

CaseResult run2(const CaseOptions& o) {
  return run_poisson_study<2>(neumann_study<2>(o.full), o);
}
CaseResult run3(const CaseOptions& o) {
  return run_poisson_study<3>(neumann_study<3>(o.full), o);
}

}  // namespace

LIQUID_VERIFICATION_CASE({"poisson-stencil-rules",
                          "the Neumann problems under each RBF-FD stencil rule: which gives the best L-inf",
                          true, run_rules});
LIQUID_VERIFICATION_CASE({"poisson-neumann-2d",
                          "Lap p = f, p = cos x cos y - 1 on [0,pi]^2, Neumann, non-graded quadtree", true,
                          run2});
LIQUID_VERIFICATION_CASE({"poisson-neumann-3d",
                          "Lap p = f, p = cos x cos y cos z - 1 on [0,pi]^3, Neumann, non-graded octree",
                          true, run3});

}  // namespace liquid::verification
