// Case divergence-conservation: which divergence conserves better on non-graded trees, the
// finite-volume flux sum or the paper's RBF-FD divergence?
//
// Problem. The staggered velocity u = (sin x cos y, sin y cos z, sin z cos x) (its first Dim
// components, z = 0.3 in 2D) sampled as normal components at face centres of the non-graded
// trees of poisson-neumann-2d/3d on [0, pi]^d; exact div u = cos x cos y + cos y cos z (+ cos z cos x).
// Measured per level: the L-inf error of each divergence at cell centres (all cells and T-junction
// cells apart), and the conservation defect |sum_c V_c div_c - boundary flux| relative to the
// total |flux|, i.e. how much mass the discrete divergence creates or destroys.
// Expected: the flux sum conserves to round-off (defect < 1e-12); both divergences converge.

#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "common/case.hpp"
#include "common/fit.hpp"
#include "liquid/levelset/levelset.hpp"
#include "liquid/mac/divergence.hpp"
#include "liquid/tree/builders.hpp"

namespace liquid::verification {
namespace {

template <int Dim>
double velocity(const Vec<Dim>& x, int k) {
  const double z = Dim == 3 ? x[Dim - 1] : 0.3;
  const double c[3] = {x[0], x[1], z};
  return std::sin(c[k]) * std::cos(c[(k + 1) % 3]);
}

template <int Dim>
double exact_divergence(const Vec<Dim>& x) {
  const double z = Dim == 3 ? x[Dim - 1] : 0.3;
  const double c[3] = {x[0], x[1], z};
  double d = 0.0;
  for (int k = 0; k < Dim; ++k) d += std::cos(c[k]) * std::cos(c[(k + 1) % 3]);
  return d;
}

template <int Dim>
void study(int level_min, int level_max, Table& table, CaseResult& result) {
  const double pi = std::numbers::pi;
  const Box<Dim> domain{Vec<Dim>::Zero(), Vec<Dim>::Constant(pi)};
  const auto circle = levelset::sphere<Dim>(Vec<Dim>::Constant(0.5 * pi), 0.9);
  std::vector<double> hs, e_fv, e_rbf;
  for (int level = level_min; level <= level_max; ++level) {
    const tree::CellGraph<Dim> g = tree::narrow_band<Dim>(domain, circle, level, level + 2, 2.0);
    std::vector<double> u(g.face_capacity(), 0.0);
    double boundary = 0.0, total = 0.0;
    g.for_each_face([&](tree::FaceId f) {
      const tree::GraphFace& gf = g.face(f);
      u[f] = velocity<Dim>(g.face_centre(f), gf.axis);
      const double flux = u[f] * g.face_area(f);
      total += std::abs(flux);
      if (gf.is_boundary()) boundary += gf.cell[0] != tree::no_cell ? flux : -flux;
    });
    const auto fv = mac::fv_divergence<Dim>(g, u);
    const auto rbf = mac::rbf_divergence<Dim>(g, u);
    double err_fv = 0, err_rbf = 0, err_fv_t = 0, err_rbf_t = 0, sum_fv = 0, sum_rbf = 0, h = 1e300;
    g.for_each_cell([&](tree::CellId c) {
      const double exact = exact_divergence<Dim>(g.centre(c));
      bool tjunction = false;
      for (tree::FaceId f : g.faces(c)) tjunction = tjunction || g.face(f).hanging();
      err_fv = std::max(err_fv, std::abs(fv[c] - exact));
      err_rbf = std::max(err_rbf, std::abs(rbf[c] - exact));
      if (tjunction) {
        err_fv_t = std::max(err_fv_t, std::abs(fv[c] - exact));
        err_rbf_t = std::max(err_rbf_t, std::abs(rbf[c] - exact));
      }
      sum_fv += g.volume(c) * fv[c];
      sum_rbf += g.volume(c) * rbf[c];
      h = std::min(h, g.cell_size(c).maxCoeff());
    });
    const double defect_fv = std::abs(sum_fv - boundary) / total,
                 defect_rbf = std::abs(sum_rbf - boundary) / total;
    hs.push_back(h), e_fv.push_back(err_fv), e_rbf.push_back(err_rbf);
    table.add_row({long(Dim), long(level), h, long(g.n_cells()), err_fv, err_fv_t, defect_fv, err_rbf,
                   err_rbf_t, defect_rbf});
    result.expect(defect_fv < 1e-12,
                  fmt::format("{}D level {}: flux-sum defect {:.2e}", Dim, level, defect_fv));
    result.gate.push_back(
        {fmt::format("{}D level {} err rbf", Dim, level), GateFigure::Kind::error, err_rbf});
    result.gate.push_back({fmt::format("{}D level {} err fv", Dim, level), GateFigure::Kind::error, err_fv});
  }
  const double o_fv = fit_order(hs, e_fv), o_rbf = fit_order(hs, e_rbf);
  result.notes.push_back(
      fmt::format("{}D orders of the L-inf error: flux sum {:.2f}, RBF-FD {:.2f}", Dim, o_fv, o_rbf));
  result.expect(o_rbf > 0.8, fmt::format("{}D: RBF-FD divergence order {:.2f}", Dim, o_rbf));
}

CaseResult run(const CaseOptions& options) {
  CaseResult result;
  Table table("divergence at cell centres: flux sum (FV) against RBF-FD",
              {"dim", "level", "h", "cells", "err FV", "err FV t-junction", "defect FV", "err RBF",
               "err RBF t-junction", "defect RBF"});
  study<2>(4, options.full ? 8 : 7, table, result);
  study<3>(2, options.full ? 4 : 3, table, result);
  result.tables.push_back(std::move(table));
  result.notes.push_back(
      "defect = |sum over cells of volume x divergence - boundary flux| / sum of |face fluxes|: "
      "the mass the discrete divergence creates or destroys");
  return result;
}

}  // namespace

LIQUID_VERIFICATION_CASE({"divergence-conservation",
                          "divergence of a face velocity: flux sum against RBF-FD, accuracy and conservation",
                          true, run, no_options});

}  // namespace liquid::verification
