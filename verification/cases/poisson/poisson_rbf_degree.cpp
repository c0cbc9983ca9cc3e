// Case poisson-rbf-degree: the paper's Poisson studies with the RBF-FD Laplacian rows augmented by
// polynomials of degree 2 (the paper's Pi_2) and of degree 3 (the default), side by side.
//
// Problem. The studies of poisson-neumann-2d/3d and poisson-dirichlet-levelset-2d/3d, with rows
// made as the paper makes them: the first row's tree, every cell split once more per row (--rows
// refine), so T-junctions stay in place and each row is a true refinement of the one before.
// Levels (quick / full): Neumann 2D 5:7 / 5:8, Dirichlet 2D 7:9 / 7:10, Neumann 3D 3:4 / 3:5,
// Dirichlet 3D 3:4 / 4:6 (base levels; the finest cells are two levels deeper; 4:6 ends at 900k
// unknowns). Jumps up to 2.
//
// Why. With degree 2 the RBF-FD rows at T-junctions reproduce quadratics only: their truncation
// error is O(h) on a layer of cells, and on these problems its constant is large at affordable
// sizes (fourth derivatives of 10^2-10^3 in the Dirichlet problems), so dp/dn converges below 1.8
// in several studies. Degree 3 makes the rows exact on cubics, at about 2-4 times the assembly
// cost (bigger stencils, bigger local systems).
//
// Expected. Degree 3 meets the floors (order >= 1.9 for p, >= 1.8 for dp/dn) in every study; the
// quick tier does not assert the 3D Dirichlet one, which is pre-asymptotic from base level 3, and
// the full tier starts it at base level 4 (orders: docs/findings/rbf-fd-degree.md). Degree 2 rows
// are reported and gated against their accepted figures, not held to the floors: they are the
// paper's scheme, kept here to show what the default's change of degree buys.

#include <fmt/format.h>

#include <algorithm>

#include "common/fit.hpp"
#include "liquid/core/error.hpp"
#include "studies/paper_studies.hpp"
#include "studies/poisson_study.hpp"

namespace liquid::verification {
namespace {

struct Setting {
  const char* name;
  bool neumann;
  int quick_min, quick_max;            // base levels of the quick tier's rows
  int full_min, full_max;              // and of the full tier's
  bool asserted_quick, asserted_full;  // whether degree 3 must meet the floors
};

template <int Dim>
void compare(const Setting& setting, const CaseOptions& options, Table& table, CaseResult& result) {
  for (int degree : {2, 3}) {
    PoissonStudy<Dim> s = setting.neumann ? neumann_study<Dim>(false) : dirichlet_study<Dim>(false);
    s.discretisation.rbf.degree = degree;
    s.rows = RowProtocol::refine;
    const int level_min = options.full ? setting.full_min : setting.quick_min;
    const int level_max = options.full ? setting.full_max : setting.quick_max;
    const bool asserted = options.full ? setting.asserted_full : setting.asserted_quick;
    s.level_min = level_min, s.level_max = level_max;
    const auto runs = solve_rows<Dim>(s, result, fmt::format("{} degree {}", setting.name, degree));
    if (runs.empty()) continue;
    std::vector<double> hs, ep, eg;
    int jump = 0;
    for (const auto& r : runs) {
      hs.push_back(r.h), ep.push_back(r.err_p), eg.push_back(r.err_grad);
      jump = std::max(jump, r.max_level_jump);
    }
    const PoissonRun& last = runs.back();
    const double order_p = fit_order(hs, ep), order_g = fit_order(hs, eg);
    table.add_row({std::string(setting.name), long{degree}, fmt::format("{}:{}", level_min, level_max),
                   last.n_unknowns, long{jump}, ep.back(), order_p, eg.back(), order_g, last.assembly_seconds,
                   last.solve_seconds});
    const std::string key = fmt::format("{} degree {}", setting.name, degree);
    result.gate.push_back({key + " finest err p", GateFigure::Kind::error, ep.back()});
    result.gate.push_back({key + " finest err dp/dn", GateFigure::Kind::error, eg.back()});
    result.gate.push_back({key + " order p", GateFigure::Kind::order, order_p});
    result.gate.push_back({key + " order dp/dn", GateFigure::Kind::order, order_g});
    if (degree == 3 && asserted) {
      result.expect(order_p >= s.order_floor, fmt::format("{} degree 3: order p {:.2f} below the floor {}",
                                                          setting.name, order_p, s.order_floor));
      result.expect(order_g >= s.order_grad_floor,
                    fmt::format("{} degree 3: order dp/dn {:.2f} below the floor {}", setting.name, order_g,
                                s.order_grad_floor));
    }
    result.expect(jump == 2, fmt::format("{}: largest level jump {}, not 2", setting.name, jump));
  }
}

CaseResult run(const CaseOptions& options) {
  CaseResult result;
  Table table(
      "RBF-FD Laplacian rows with polynomials of degree 2 and 3, rows by recursive subdivision "
      "(finest row; orders fitted over the rows)",
      {"study", "degree", "levels", "unknowns", "jump", "err p", "order p", "err dp/dn", "order dp/dn",
       "assembly s", "solve s"});
  compare<2>({"neumann-2d", true, 5, 7, 5, 8, true, true}, options, table, result);
  compare<2>({"dirichlet-2d", false, 7, 9, 7, 10, true, true}, options, table, result);
  compare<3>({"neumann-3d", true, 3, 4, 3, 5, true, true}, options, table, result);
  compare<3>({"dirichlet-3d", false, 3, 4, 4, 6, false, true}, options, table, result);
  result.tables.push_back(std::move(table));
  result.notes.push_back(
      options.full
          ? "degree 3 (the default) is asserted to meet the floors (p >= 1.9, dp/dn >= 1.8) on every "
            "study; degree 2 (the paper's) is reported only"
          : "degree 3 (the default) is asserted to meet the floors (p >= 1.9, dp/dn >= 1.8) except on "
            "dirichlet-3d, pre-asymptotic from base level 3 (the full tier starts it at 4 and asserts "
            "it; so does poisson-dirichlet-levelset-3d, from 4:5); degree 2 (the paper's) is reported "
            "only");
  result.notes.push_back("assembly and solve seconds are those of the finest row");
  return result;
}

}  // namespace

LIQUID_VERIFICATION_CASE(
    {"poisson-rbf-degree",
     "the paper's Poisson studies with RBF-FD rows of polynomial degree 2 and 3, side by side", true, run,
     no_options});

}  // namespace liquid::verification
