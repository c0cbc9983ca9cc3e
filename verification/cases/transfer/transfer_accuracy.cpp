// Case transfer-accuracy: how well each particle/grid transfer reconstructs a smooth velocity, on
// non-graded trees (paper Fig. 4, made quantitative), and what a PIC round trip costs in energy.
//
// Methods. rbf: the paper's transfer, PHS r^5 + polynomials of degree 2 on the cells incident to
// the target (TransferOptions::paper_rbf). mls: HOPIC's cubic moving least squares on 2 rings
// (cubic_mls). linear: a linear least-squares fit on the RBF's stencil (linear_fit), the linear
// interpolation of scattered data. On uniform trees, also the regular baselines: PIC (multilinear
// weights) and APIC (the same weights plus the affine matrix).
// Tables.
//  1. Reconstruction (Fig. 4). X(x, y) = (cos(x + 2y), sin(x - 2y)) on [-2, 2]^2, sampled as normal
//     components at the face midpoints of a seeded random non-graded quadtree (levels 3 to 5, level
//     jump 2, split probability 0.4, seed 4), reconstructed at the cell centres of a regular 64^2
//     grid. 3D: X = (cos(x + 2y), sin(x - 2y), cos(y - 2z)) on [-1, 1]^3 (half the width, so that
//     levels 2 to 4 resolve it), on 24^3 points. RMSE and L-inf of |X_rec - X| per method.
//     Expected (paper): rbf below mls; both below linear.
//  2. Convergence: the same reconstruction as every leaf of that tree is split 0..3 times (3D 0..2):
//     L-inf per method and the fitted order in h (finest cell).
//  3. Round trip particles -> faces -> particles with one method both ways, particles at 2^d
//     jittered Halton points per cell of the same trees, carrying X: L-inf at all particles and at
//     the interior ones (at least 1/8 of the width from every wall), and orders. Walls are where
//     scattered transfers are one-sided (paper Sec. 7); the interior orders are asserted (> 1.5),
//     the wall figures gated.
//  4. Energy: a Taylor-Green velocity (sin x cos y, -cos x sin y) (3D: (sin x cos y, -cos x sin y, 0))
//     on [0, pi]^d, uniform trees of levels 4..6 (3D 3..4), 2^d particles per cell: the kinetic
//     energy lost per transfer pair, 1 - (KE_10 / KE_0)^(1/10) over 10 pairs, per method (rbf, PIC,
//     APIC; APIC's KE with its affine part, particle_affine_energy). Expected: APIC and rbf lose less
//     than PIC.

#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "common/case.hpp"
#include "common/fit.hpp"
#include "liquid/core/timer.hpp"
#include "liquid/particles/seeding.hpp"
#include "liquid/transfer/regular.hpp"
#include "liquid/transfer/scattered.hpp"
#include "liquid/tree/builders.hpp"
#include "studies/flow_measures.hpp"

namespace liquid::verification {
namespace {

struct Method {
  const char* name;
  transfer::TransferOptions options;
};
const Method kMethods[] = {{"rbf", transfer::TransferOptions::paper_rbf()},
                           {"mls", transfer::TransferOptions::cubic_mls()},
                           {"linear", transfer::TransferOptions::linear_fit()}};

template <int Dim>
Vec<Dim> field(const Vec<Dim>& x) {
  Vec<Dim> v;
  v[0] = std::cos(x[0] + 2 * x[1]);
  v[1] = std::sin(x[0] - 2 * x[1]);
  if constexpr (Dim == 3) v[2] = std::cos(x[1] - 2 * x[2]);
  return v;
}

template <int Dim>
Box<Dim> fig4_domain() {
  const double w = Dim == 2 ? 2.0 : 1.0;
  return {Vec<Dim>::Constant(-w), Vec<Dim>::Constant(w)};
}

template <int Dim>
bool interior(const Vec<Dim>& x) {
  const Box<Dim> d = fig4_domain<Dim>();
  return ((x - d.lo).array() >= 0.125 * d.size().array()).all() &&
         ((d.hi - x).array() >= 0.125 * d.size().array()).all();
}

template <int Dim>
tree::CellGraph<Dim> fig4_tree(int extra) {
  tree::CellGraphOptions<Dim> o;
  o.max_jump = 2;
  const auto base = tree::random<Dim>(fig4_domain<Dim>(), 4, Dim == 2 ? 3 : 2, Dim == 2 ? 5 : 4, 0.4, o);
  return extra == 0 ? base : tree::refined<Dim>(base, extra, o);
}

template <int Dim>
double finest_h(const tree::CellGraph<Dim>& g) {
  return std::ldexp(g.domain().size().maxCoeff(), -g.deepest_level());
}

struct Errors {
  double rmse = 0.0, linf = 0.0, linf_interior = 0.0;
};

template <int Dim>
Errors compare(std::span<const Vec<Dim>> x, std::span<const Vec<Dim>> v) {
  Errors e;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double d = (v[i] - field<Dim>(x[i])).norm();
    e.rmse += d * d;
    e.linf = std::max(e.linf, d);
    if (interior(x[i])) e.linf_interior = std::max(e.linf_interior, d);
  }
  e.rmse = std::sqrt(e.rmse / static_cast<double>(x.size()));
  return e;
}

/// The regular grid of sample points: cell centres of n^Dim cells over the domain.
template <int Dim>
std::vector<Vec<Dim>> grid_points(const Box<Dim>& d, int n) {
  std::vector<Vec<Dim>> pts;
  long total = 1;
  for (int k = 0; k < Dim; ++k) total *= n;
  for (long i = 0; i < total; ++i) {
    Vec<Dim> x;
    long r = i;
    for (int k = 0; k < Dim; ++k, r /= n)
      x[k] = d.lo[k] + (static_cast<double>(r % n) + 0.5) * d.size()[k] / n;
    pts.push_back(x);
  }
  return pts;
}

template <int Dim>
Errors reconstruct(const tree::CellGraph<Dim>& g, std::span<const Vec<Dim>> pts,
                   const particles::CellBins& bins, const Method& m, double& seconds) {
  std::vector<double> u(g.face_capacity(), 0.0);
  g.for_each_face([&](tree::FaceId f) { u[f] = field<Dim>(g.face_centre(f))[g.face(f).axis]; });
  std::vector<Vec<Dim>> v(pts.size());
  Stopwatch clock;
  transfer::faces_to_points<Dim>(g, u, {}, pts, bins, m.options, v);
  seconds = clock.seconds();
  return compare<Dim>(pts, v);
}

template <int Dim>
void reconstruction(const CaseOptions& options, Table& fig4, Table& conv, Table& trip, CaseResult& result) {
  const int n_points = Dim == 2 ? 64 : 24;
  const auto pts = grid_points<Dim>(fig4_domain<Dim>(), n_points);
  const int rows = Dim == 2 ? (options.full ? 5 : 4) : (options.full ? 4 : 3);
  std::vector<double> hs;
  std::vector<std::vector<double>> e_rec(3), e_trip(3), e_inner(3);
  for (int extra = 0; extra < rows; ++extra) {
    const auto g = fig4_tree<Dim>(extra);
    particles::CellBins bins;
    particles::bin_particles<Dim>(g, pts, bins);
    particles::Particles<Dim> p;
    particles::SeedOptions so;
    so.jitter = 0.5;
    particles::seed_region<Dim>(
        g, [](const Vec<Dim>&) { return -1.0; }, so, p);
    for (int i = 0; i < p.size(); ++i) p.v[i] = field<Dim>(p.x[i]);
    particles::CellBins pbins;
    particles::bin_particles<Dim>(g, p.x, pbins);
    hs.push_back(finest_h(g));
    for (int k = 0; k < 3; ++k) {
      const Method& m = kMethods[k];
      double seconds = 0.0;
      const Errors e = reconstruct<Dim>(g, pts, bins, m, seconds);
      e_rec[k].push_back(e.linf);
      if (extra == 0) {
        fig4.add_row(
            {long(Dim), std::string(m.name), long(g.n_cells()), long(g.n_faces()), e.rmse, e.linf, seconds});
        result.gate.push_back(
            {fmt::format("{}D fig4 {} rmse", Dim, m.name), GateFigure::Kind::error, e.rmse});
        result.gate.push_back(
            {fmt::format("{}D fig4 {} linf", Dim, m.name), GateFigure::Kind::error, e.linf});
      }
      transfer::FaceValues faces;
      transfer::particles_to_faces<Dim>(g, p, pbins, m.options, faces);
      std::vector<Vec<Dim>> back(p.size());
      transfer::faces_to_points<Dim>(g, faces.value, faces.known, p.x, pbins, m.options, back);
      const Errors t = compare<Dim>(p.x, back);
      e_trip[k].push_back(t.linf);
      e_inner[k].push_back(t.linf_interior);
    }
    conv.add_row({long(Dim), long(extra), hs.back(), long(g.n_faces()), e_rec[0].back(), e_rec[1].back(),
                  e_rec[2].back()});
    trip.add_row({long(Dim), long(extra), hs.back(), long(p.size()), e_trip[0].back(), e_inner[0].back(),
                  e_trip[1].back(), e_inner[1].back(), e_trip[2].back(), e_inner[2].back()});
  }
  std::vector<Table::Cell> orders{long(Dim), std::string("order"), std::monostate{}, std::monostate{}};
  std::vector<Table::Cell> trip_orders = orders;
  for (int k = 0; k < 3; ++k) {
    const char* name = kMethods[k].name;
    const double o = fit_order(hs, e_rec[k]), t = fit_order(hs, e_trip[k]), ti = fit_order(hs, e_inner[k]);
    orders.push_back(o);
    trip_orders.push_back(t);
    trip_orders.push_back(ti);
    result.gate.push_back(
        {fmt::format("{}D reconstruction {} order", Dim, name), GateFigure::Kind::order, o});
    result.gate.push_back(
        {fmt::format("{}D round trip {} interior order", Dim, name), GateFigure::Kind::order, ti});
    result.gate.push_back(
        {fmt::format("{}D round trip {} finest linf", Dim, name), GateFigure::Kind::error, e_trip[k].back()});
    result.gate.push_back({fmt::format("{}D round trip {} finest interior linf", Dim, name),
                           GateFigure::Kind::error, e_inner[k].back()});
    result.expect(o > 1.5,
                  fmt::format("{}D reconstruction order of {}: {:.2f} (expected > 1.5)", Dim, name, o));
    result.expect(ti > 1.5, fmt::format("{}D round-trip order of {} in the interior: {:.2f} (expected > 1.5)",
                                        Dim, name, ti));
  }
  conv.add_row(std::move(orders));
  trip.add_row(std::move(trip_orders));
  const double rbf = e_rec[0].front(), mls = e_rec[1].front(), lin = e_rec[2].front();
  result.expect(rbf < lin && mls < lin,
                fmt::format("{}D Fig. 4: rbf {:.3e} and mls {:.3e} should both be below linear {:.3e}", Dim,
                            rbf, mls, lin));
  result.notes.push_back(fmt::format("{}D Fig. 4 (paper: rbf below mls): L-inf rbf {:.3e}, mls {:.3e} ({})",
                                     Dim, rbf, mls, rbf < mls ? "holds" : "does not hold here"));
  for (std::size_t r = 1; r < hs.size(); ++r)
    if (e_rec[1][r] < e_rec[0][r]) {
      result.notes.push_back(
          fmt::format("{}D: refined, cubic MLS converges faster and is below rbf from row {} on "
                      "(L-inf {:.3e} against {:.3e})",
                      Dim, r, e_rec[1][r], e_rec[0][r]));
      break;
    }
}

template <int Dim>
double kinetic(const particles::Particles<Dim>& p) {
  double e = 0.0;
  for (const auto& v : p.v) e += 0.5 * v.squaredNorm();
  return e;
}

template <int Dim>
void energy(const CaseOptions& options, Table& table, CaseResult& result) {
  constexpr int pairs = 10;
  const int first = Dim == 2 ? 4 : 3, last = first + (Dim == 2 ? 2 : 1) + (options.full ? 1 : 0);
  const Box<Dim> domain{Vec<Dim>::Zero(), Vec<Dim>::Constant(std::numbers::pi)};
  for (int level = first; level <= last; ++level) {
    const auto g = tree::uniform<Dim>(domain, level);
    const transfer::RegularLattice<Dim> lattice(g);
    particles::Particles<Dim> start;
    particles::SeedOptions so;
    so.jitter = 0.5;
    particles::seed_region<Dim>(
        g, [](const Vec<Dim>&) { return -1.0; }, so, start);
    for (int i = 0; i < start.size(); ++i) start.v[i] = taylor_green<Dim>(start.x[i]);
    start.add_field("apic", Dim * Dim);
    particles::CellBins bins;
    particles::bin_particles<Dim>(g, start.x, bins);
    const double ke0 = kinetic(start);
    std::vector<Table::Cell> row{long(Dim), long(level), long(start.size())};
    double loss[3];
    for (int method = 0; method < 3; ++method) {  // rbf, pic, apic
      particles::Particles<Dim> p = start;
      transfer::FaceValues faces;
      for (int k = 0; k < pairs; ++k) {
        if (method == 0) {
          transfer::particles_to_faces<Dim>(g, p, bins, transfer::TransferOptions::paper_rbf(), faces);
          transfer::faces_to_points<Dim>(g, faces.value, faces.known, p.x, bins,
                                         transfer::TransferOptions::paper_rbf(), p.v);
        } else {
          const auto scheme = method == 1 ? transfer::RegularScheme::pic : transfer::RegularScheme::apic;
          transfer::linear_to_faces<Dim>(g, lattice, p, bins, scheme, {}, faces);
          transfer::linear_to_points<Dim>(lattice, faces.value, p.x, p.v,
                                          method == 2 ? p.field(p.field_index("apic")) : std::span<double>{});
        }
      }
      // APIC's energy counts its affine part (zero at the start: C = 0).
      const double ke = kinetic(p) + (method == 2 ? transfer::particle_affine_energy<Dim>(
                                                        lattice, p, p.field(p.field_index("apic")))
                                                  : 0.0);
      loss[method] = 1.0 - std::pow(ke / ke0, 1.0 / pairs);
      row.push_back(loss[method]);
    }
    table.add_row(std::move(row));
    const char* names[3] = {"rbf", "pic", "apic"};
    for (int m = 0; m < 3; ++m)
      result.gate.push_back({fmt::format("{}D level {} energy loss per pair {}", Dim, level, names[m]),
                             GateFigure::Kind::error, std::abs(loss[m])});
    result.expect(
        loss[0] < loss[1] && loss[2] < loss[1],
        fmt::format("{}D level {}: energy lost per pair rbf {:.2e}, apic {:.2e} should be below pic {:.2e}",
                    Dim, level, loss[0], loss[2], loss[1]));
  }
}

CaseResult run(const CaseOptions& options) {
  CaseResult result;
  Table fig4("1. reconstruction of X from face midpoints of a non-graded tree (paper Fig. 4)",
             {"dim", "method", "cells", "faces", "RMSE", "L-inf", "seconds"});
  Table conv("2. reconstruction L-inf as the tree is refined",
             {"dim", "extra", "h", "faces", "rbf", "mls", "linear"});
  Table trip(
      "3. round trip particles -> faces -> particles, L-inf at all / interior particles",
      {"dim", "extra", "h", "particles", "rbf", "rbf inner", "mls", "mls inner", "linear", "linear inner"});
  Table ke("4. kinetic energy lost per transfer pair (Taylor-Green, uniform trees)",
           {"dim", "level", "particles", "rbf", "pic", "apic"});
  reconstruction<2>(options, fig4, conv, trip, result);
  reconstruction<3>(options, fig4, conv, trip, result);
  energy<2>(options, ke, result);
  energy<3>(options, ke, result);
  for (Table* t : {&fig4, &conv, &trip, &ke}) result.tables.push_back(std::move(*t));
  result.notes.push_back("order rows: least-squares slope of log L-inf against log h (finest cell)");
  return result;
}

}  // namespace

LIQUID_VERIFICATION_CASE(
    {"transfer-accuracy",
     "particle/grid transfers: RBF, MLS and linear on non-graded trees; PIC/APIC energy loss", true, run,
     no_options});

}  // namespace liquid::verification
