// Case poisson-adaptivity-gain: a problem where the adaptive tree should pay, measured.
//
// Problem. Lap p = f with the exact solution p = tanh(d / eps), d = |x| - R the signed distance to
// a circle (sphere) centred in [-1, 1]^d, and Dirichlet walls carrying p: a layer of width about
// eps along the interface, and p flat (|p| -> 1) away from it. 2D: R = 0.35, eps = 0.02 (5 cells
// of the finest quick row); 3D: R = 0.4, eps = 0.04 (1.3 cells). f = p'' + (d - 1) p' / r along the radius
// (support::tanh_layer). Trees. Adaptive: a narrow band at the finest level covering |d| < 8 eps (2D) / 5 eps
// (3D), where p varies, as coarse as the level-jump limit (2) allows elsewhere; each row splits every cell of
// the first row's tree once more, so the band stays the same region. Uniform: every cell at the
// adaptive row's finest level. Rows (finest levels, quick / full): 2D 7:9 / 7:10 over base 3,
// 3D 5:6 / 5:7 over base 2.
// Measured per row: unknowns, L-inf error of p, assembly + solve seconds, both trees. The gain at
// equal error is the uniform grid's time (and unknowns) interpolated in log-log to the adaptive
// row's error, divided by the adaptive row's. Expected: at the finest row the adaptive tree needs
// at least 3 times fewer unknowns than the uniform grid for the same error, and in 2D at least 3
// times less time. In 3D the time gain is reported, not asserted (see below).

#include <cmath>

#include <fmt/format.h>

#include "liquid/tree/builders.hpp"
#include "studies/poisson_study.hpp"
#include "support/manufactured.hpp"

namespace liquid::verification {
namespace {

constexpr double kGain = 3.0;

// y at x by linear interpolation of log y against log x over the points (xs, ys) sorted by
// decreasing x; outside their range, the nearest two points' line. `outside` says which.
double loglog_at(const std::vector<double>& xs, const std::vector<double>& ys, double x, bool& outside) {
  const std::size_t n = xs.size();
  std::size_t k = 1;
  while (k + 1 < n && xs[k] > x) ++k;
  outside = x > xs.front() || x < xs.back();
  const double t = (std::log(x) - std::log(xs[k - 1])) / (std::log(xs[k]) - std::log(xs[k - 1]));
  return std::exp(std::log(ys[k - 1]) + t * (std::log(ys[k]) - std::log(ys[k - 1])));
}

template <int Dim>
void study(const CaseOptions& options, Table& table, CaseResult& result, Json& series) {
  const double radius = Dim == 2 ? 0.35 : 0.4, eps = Dim == 2 ? 0.02 : 0.04;
  // The layer is |d| < ~4 eps; the band covers 8 eps (2D) / 5 eps (3D) on each side.
  const double half_width = (Dim == 2 ? 8.0 : 5.0) * eps;
  PoissonStudy<Dim> s;
  s.domain = Box<Dim>{Vec<Dim>::Constant(-1.0), Vec<Dim>::Constant(1.0)};
  s.use(support::tanh_layer<Dim>(Vec<Dim>::Zero(), radius, eps));
  s.dirichlet_walls = true;
  const int coarse = Dim == 2 ? 3 : 2, first_fine = Dim == 2 ? 7 : 5;
  s.finest_offset = first_fine - coarse;
  s.level_min = coarse;
  s.level_max = coarse + (options.full ? 3 : 2) - (Dim == 3 ? 1 : 0);
  s.max_cells = options.max_cells;
  const Box<Dim> domain = s.domain;
  const double band_cells = half_width / (2.0 / std::ldexp(1.0, first_fine));
  s.make_tree = [domain, radius, band_cells](int level, const tree::CellGraphOptions<Dim>& o) {
    const auto circle = levelset::sphere<Dim>(Vec<Dim>::Zero(), radius);
    return tree::narrow_band<Dim>(domain, circle, level, level + (Dim == 2 ? 4 : 3), band_cells, o);
  };
  s.rows = RowProtocol::refine;

  std::vector<PoissonRun> adaptive = solve_rows<Dim>(s, result, fmt::format("{}D adaptive", Dim));
  std::vector<PoissonRun> uniform;
  tree::CellGraphOptions<Dim> o;
  for (int level = s.level_min; level <= s.level_max; ++level) {
    const tree::CellGraph<Dim> flat = tree::uniform<Dim>(domain, level + s.finest_offset, o);
    PoissonRun u = solve_poisson<Dim>(flat, s);
    result.expect(u.solve.converged(),
                  fmt::format("{}D uniform level {}: {}", Dim, level + s.finest_offset, u.solve.describe()));
    if (!u.solve.converged()) break;
    uniform.push_back(std::move(u));
  }
  if (adaptive.size() < 2 || uniform.size() < 2) return;

  std::vector<double> ue, ut, un, ae, at;
  for (const auto& u : uniform)
    ue.push_back(u.err_p), ut.push_back(u.assembly_seconds + u.solve_seconds), un.push_back(u.n_unknowns);
  double gain_time = 0.0, gain_unknowns = 0.0;
  for (std::size_t k = 0; k < adaptive.size(); ++k) {
    const PoissonRun& a = adaptive[k];
    const PoissonRun& u = uniform[std::min(k, uniform.size() - 1)];
    const double t = a.assembly_seconds + a.solve_seconds;
    bool outside = false;
    const double t_u = loglog_at(ue, ut, a.err_p, outside);
    const double n_u = loglog_at(ue, un, a.err_p, outside);
    gain_time = t_u / t;
    gain_unknowns = n_u / double(a.n_unknowns);
    ae.push_back(a.err_p), at.push_back(t);
    const int fine = s.level_min + static_cast<int>(k) + s.finest_offset;
    table.add_row({long(Dim), long(fine), a.n_unknowns, a.err_p, a.assembly_seconds, a.solve_seconds,
                   long(a.solve.iterations), u.n_unknowns, u.err_p, u.assembly_seconds, u.solve_seconds,
                   long(u.solve.iterations), gain_unknowns, gain_time,
                   std::string(outside ? "extrapolated" : "interpolated")});
    result.gate.push_back(
        {fmt::format("{}D level {} adaptive err p", Dim, fine), GateFigure::Kind::error, a.err_p});
    result.gate.push_back(
        {fmt::format("{}D level {} uniform err p", Dim, fine), GateFigure::Kind::error, u.err_p});
    result.gate.push_back({fmt::format("{}D level {} adaptive unknowns", Dim, fine), GateFigure::Kind::count,
                           double(a.n_unknowns)});
  }
  result.fields.set(fmt::format("gain_time_{}d", Dim), gain_time);
  result.fields.set(fmt::format("gain_unknowns_{}d", Dim), gain_unknowns);
  result.expect(
      gain_unknowns >= kGain,
      fmt::format("{}D finest row: the adaptive tree needs only {:.2f} times fewer unknowns than the "
                  "uniform grid at equal error (expected at least {})",
                  Dim, gain_unknowns, kGain));
  // In 3D the time gain is not asserted: the degree-3 RBF-FD rows of an octree carry 40-100 nodes,
  // so an adaptive unknown costs several uniform ones in assembly and in each BiCGSTAB+ILUT
  // iteration (see the table's assembly and solve columns; docs/findings/poisson-convergence.md).
  if (Dim == 2)
    result.expect(gain_time >= kGain,
                  fmt::format("{}D finest row: the adaptive tree is only {:.2f} times faster "
                              "than the uniform grid at equal error (expected at least {})",
                              Dim, gain_time, kGain));
  else if (gain_time < kGain)
    result.warnings.push_back(
        fmt::format("{}D finest row: {:.1f} times fewer unknowns but only {:.2f} times faster at equal "
                    "error: the octree's "
                    "RBF-FD rows are dense (assembly and per-iteration cost per unknown several times the "
                    "uniform grid's)",
                    Dim, gain_unknowns, gain_time));
  // Where the two curves of time against error cross, if they do within the rows.
  std::string crossover = "none within the rows: the adaptive tree is faster at every error measured";
  for (std::size_t k = 0; k < adaptive.size(); ++k) {
    bool outside = false;
    if (loglog_at(ue, ut, ae[k], outside) < at[k]) {
      crossover =
          fmt::format("the uniform grid is faster down to an error of {:.2e} (adaptive row {})", ae[k], k);
    }
  }
  result.notes.push_back(fmt::format("{}D: crossover of time against error: {}", Dim, crossover));
  for (auto [label, e, t] : {std::tuple{"adaptive", &ae, &at}, std::tuple{"uniform", &ue, &ut}}) {
    series.push(series_entry(
        fmt::format("poisson-adaptivity-gain {}D: time to solution against the L-inf error of p", Dim), label,
        *e, *t, "L-inf error of p", "assembly + solve seconds"));
  }
}

CaseResult run(const CaseOptions& options) {
  CaseResult result;
  Table table(
      "a sharp layer along a circle (sphere): narrow-band tree against the uniform grid of its finest h",
      {"dim", "finest level", "adaptive unknowns", "adaptive err p", "assembly s", "solve s", "its",
       "uniform unknowns", "uniform err p", "assembly s", "solve s", "its", "unknowns gain", "time gain",
       "at equal error"});
  Json series = Json::array();
  study<2>(options, table, result, series);
  study<3>(options, table, result, series);
  result.tables.push_back(std::move(table));
  result.fields.set("series", std::move(series));
  result.notes.push_back(
      "gain = the uniform grid's unknowns (time) at the adaptive row's error, interpolated log-log between "
      "its "
      "rows (extrapolated from the nearest two past them), over the adaptive row's; time = assembly + solve, "
      "bicgstab-ilut to 1e-10 on both; one run each (time figures are not gated, unknowns and errors are)");
  return result;
}

}  // namespace

LIQUID_VERIFICATION_CASE({"poisson-adaptivity-gain",
                          "a sharp tanh layer on a circle/sphere: narrow-band tree vs uniform grid, time and "
                          "unknowns at equal L-inf error",
                          true, run, no_options});

}  // namespace liquid::verification
