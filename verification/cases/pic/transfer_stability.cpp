// Case transfer-stability: do repeated transfer pairs keep a steady flow, or amplify its noise?
//
// Problem. The Taylor-Green cells of `vorticity` (u = (sin x cos y, -cos x sin y), w = 0 in 3D) in
// a closed box [0, pi]^Dim full of liquid, with the PIC solver's whole step (particles -> faces,
// projection, faces -> particles) run with dt = 1e-4: the particles move by 1e-4 a step, so the
// flow at them should not change, and every change of their velocities is what the transfer pair
// and the projection do to it. Rows: the uniform tree and the adaptive one (finest level in the
// central region [pi/4, 3pi/4]^Dim with the band's hops, one level coarser elsewhere: vorticity's
// tree), each with the paper's transfer (PHS r^5 with degree 2, both directions) and with PHS r^3
// with degree 1, the RBF everywhere; the adaptive tree also with APIC in its uniform patches and PHS
// r^3 + degree 1 across level changes (PicOptions::uniform_patches); 2D at finest level 5, 3D at 4; 40 steps
// (full tier: 160). No reseeding (the particles do not move). Measured: the particles' L-inf velocity error
// (the largest component) after the first step, half-way and after the last (warned about past 0.1 of the
// peak speed). Every row's error grows: the RBF pair does not smooth, so each step's interpolation error
// stays; the paper's pair in 3D grows it geometrically instead; the faces' L-inf error after the last step,
// the particles' kinetic energy over its value at seeding (volume-weighted shares, particle_volumes), and the
// largest Lebesgue constant of the face -> particle stencils over the tree's cells (the largest sum of
// |cardinal function| over each cell's corners, edge and face centres and centre: how much an error in the
// face values can grow at a particle). Expected (asserted): the 2D rows and the 3D rows with PHS r^3 + degree
// 1 keep the error below 0.3 (a flow of peak speed 1). Gated: the error after the last step, per row. The
// paper's transfer in 3D is reported and warned about, since its error grows without bound
// (docs/findings/transfer-stability.md).

#include <cmath>

#include <fmt/format.h>

#include "common/case.hpp"
#include "liquid/core/timer.hpp"
#include "liquid/pic/adaptive_pic.hpp"
#include "liquid/rbf/interpolant_cache.hpp"
#include "liquid/transfer/face_stencil.hpp"
#include "studies/flow_measures.hpp"

namespace liquid::verification {
namespace {

template <int Dim>
Vec<Dim> exact(const Vec<Dim>& x) {
  return taylor_green<Dim>(x);
}

struct Transfer {
  const char* name;
  int exponent, degree;
  bool patches;  ///< APIC in the adaptive tree's uniform patches (PicOptions::uniform_patches)
};
constexpr Transfer kTransfers[] = {
    {"PHS r^5 + degree 2 (paper)", 5, 2, false},
    {"PHS r^3 + degree 1", 3, 1, false},
    {"APIC in patches, PHS r^3 + degree 1 and its gradient (default)", 3, 1, true}};

struct Row {
  double error_first = 0, error_half = 0, error_last = 0, face_error = 0, energy = 0, lebesgue = 0,
         seconds = 0;
  long particles = 0, cells = 0;
};

/// The largest Lebesgue constant of the face -> particle stencils of the tree's cells.
template <int Dim>
double largest_lebesgue(const tree::CellGraph<Dim>& graph, const transfer::TransferOptions& options) {
  rbf::InterpolantCache<Dim> cache;
  const rbf::Config config = options.rbf_config();
  const std::vector<double> zero(graph.face_capacity(), 0.0);
  transfer::FaceStencil<Dim> stencil;
  double largest = 0.0;
  graph.for_each_cell([&](tree::CellId c) {
    transfer::gather_face_stencil<Dim>(graph, c, options.rings, zero, {}, stencil);
    for (int axis = 0; axis < Dim; ++axis) {
      if (stencil.nodes[axis].empty()) continue;
      const rbf::Interpolant<Dim> interp = transfer::fitted_interpolant<Dim>(
          graph, c, stencil.nodes[axis], stencil.values[axis], config, &cache);
      if (interp.status().usable()) largest = std::max(largest, interp.cell_lebesgue());
    }
  });
  return largest;
}

template <int Dim>
double particle_error(const pic::AdaptivePic<Dim>& sim) {
  double e = 0.0;
  for (int i = 0; i < sim.particles().size(); ++i)
    e = std::max(
        e, (sim.particles().v[i] - exact<Dim>(sim.particles().x[i])).template lpNorm<Eigen::Infinity>());
  return e;
}

template <int Dim>
double particle_energy(const pic::AdaptivePic<Dim>& sim) {
  return twice_kinetic_energy<Dim>(sim, std::pow(M_PI, Dim));
}

template <int Dim>
Row run_row(bool adaptive, const Transfer& t, int level, int steps) {
  pic::PicOptions<Dim> o;
  o.domain = Box<Dim>{Vec<Dim>::Zero(), Vec<Dim>::Constant(M_PI)};
  o.gravity = Vec<Dim>::Zero();
  o.adaptive = adaptive;
  o.finest_level = level;
  o.coarse_level = adaptive ? level - 1 : level;
  if (adaptive)
    o.refine = levelset::box<Dim>({Vec<Dim>::Constant(M_PI / 4), Vec<Dim>::Constant(3 * M_PI / 4)});
  o.reseed = false;
  o.rbf.exponent = t.exponent;
  o.rbf.degree = t.degree;
  o.uniform_patches = t.patches;
  pic::AdaptivePic<Dim> sim(o);
  sim.seed([](const Vec<Dim>&) { return -1.0; }, exact<Dim>);
  const double e0 = particle_energy(sim);
  Row row;
  row.particles = sim.particles().size();
  row.cells = sim.graph().n_cells();
  row.lebesgue = largest_lebesgue<Dim>(sim.graph(), o.rbf);
  Stopwatch clock;
  for (int s = 0; s < steps; ++s) {
    const pic::PicStepReport r = sim.advance(1e-4);
    LIQUID_VERIFY(r.ppe.converged(), "transfer-stability: the PPE did not converge at step {}: {}", s + 1,
                  r.ppe.describe());
    if (s == 0) row.error_first = particle_error(sim);
    if (s + 1 == steps / 2) row.error_half = particle_error(sim);
  }
  row.seconds = clock.seconds();
  row.error_last = particle_error(sim);
  row.energy = particle_energy(sim) / e0;
  const tree::CellGraph<Dim>& g = sim.graph();
  g.for_each_face([&](tree::FaceId f) {
    row.face_error = std::max(
        row.face_error, std::abs(sim.face_velocity()[f] - exact<Dim>(g.face_centre(f))[g.face(f).axis]));
  });
  return row;
}

template <int Dim>
void rows(const CaseOptions& options, Table& table, CaseResult& result) {
  const int level = Dim == 2 ? 5 : 4;
  const int steps = options.full ? 160 : 40;
  for (bool adaptive : {false, true})
    for (const Transfer& t : kTransfers) {
      if (t.patches && !adaptive) continue;  // a uniform tree's RBF rows take no patches
      const Row r = run_row<Dim>(adaptive, t, level, steps);
      const std::string tree = adaptive ? "adaptive" : "uniform";
      table.add_row({long(Dim), tree, std::string(t.name), long(level), r.cells, r.particles, long(steps),
                     r.error_first, r.error_half, r.error_last, r.error_last / r.error_half, r.face_error,
                     r.energy, r.lebesgue, r.seconds});
      const std::string key = fmt::format("{}D {} r^{} degree {}{}", Dim, tree, t.exponent, t.degree,
                                          t.patches ? " patches" : "");
      result.gate.push_back({key + " particle error after the steps", GateFigure::Kind::error, r.error_last});
      result.expect(std::isfinite(r.error_last), key + ": a non-finite velocity");
      if (Dim == 2 || t.exponent == 3)
        result.expect(r.error_last < 0.3,
                      fmt::format("{}: the velocity error grew to {:.3g} in {} steps of a "
                                  "steady flow (from {:.3g} after the first)",
                                  key, r.error_last, steps, r.error_first));
      if (r.error_last > 0.1)
        result.warnings.push_back(
            fmt::format("{}: the velocity error of a steady flow grew to {:.3g} of its peak speed in {} "
                        "steps ({:.3g} after "
                        "the first, {:.3g} half-way), the energy to {:.3g} of its start: the transfer pair "
                        "amplifies noise "
                        "(largest Lebesgue constant {:.3g})",
                        key, r.error_last, steps, r.error_first, r.error_half, r.energy, r.lebesgue));
    }
}

CaseResult run(const CaseOptions& options) {
  CaseResult result;
  Table table(
      "the PIC step repeated on the Taylor-Green cells with dt = 1e-4 (the particles stay put): what the "
      "transfer pair and the projection do to a steady flow",
      {"dim", "tree", "transfer", "finest", "cells", "particles", "steps", "L-inf first step",
       "L-inf half-way", "L-inf last step", "last / half-way", "faces L-inf", "KE / KE(0)",
       "largest Lebesgue constant", "seconds"});
  rows<2>(options, table, result);
  rows<3>(options, table, result);
  result.tables.push_back(std::move(table));
  result.notes.push_back(
      "no reseeding; 'largest Lebesgue constant': of the face -> particle stencils, over each cell's "
      "corners, edge and face centres and centre. Both transfer directions take the row's kernel; a "
      "driver that changed only face -> particle found it alone decides the 3D adaptive growth (README)");
  return result;
}

}  // namespace

LIQUID_VERIFICATION_CASE({"transfer-stability",
                          "the PIC step repeated on a steady Taylor-Green flow with the particles held: "
                          "does the transfer pair amplify noise (uniform and adaptive trees, 2D and 3D)",
                          true, run, no_options});

}  // namespace liquid::verification
