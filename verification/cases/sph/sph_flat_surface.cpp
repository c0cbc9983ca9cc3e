// Case sph-flat-surface: how far the particle surface lies from a flat face, before and after the
// particles are adaptively down-sampled (Adams et al. 2007, Sec. 5.3, Figs. 5-6). Case
// sph-sphere-surface: the same for a curved surface, a disc (2D) or a ball (3D).
//
// Problem. The box B = [0.2, 0.8]^Dim sampled by N particles at uniformly random positions, all of
// level 0 with spacing s = (|B| / N)^(1/Dim) and support r = 2.5 s, each given its exact distance to
// the faces of B and then redistanced once (the distances the solver would carry): "before". Then
// down-sampled as the solver does, at rest: passes of redistance + feature size + split/merge (levels
// 0..4, footpoint disks r/2) until a pass changes fewer than 1% of the particles (at most 10), and
// redistanced once more: "after". Sizes: 2D N = 6000 (full tier 24000), 3D N = 20000 (full tier 100000; the
// paper's figure: 100k down to 20k). Surfaces, each extracted (surface::extract) on a grid of cells s/2 over
// [0.1, 0.9]^Dim:
//   distance     the paper's, Eqs. 5-8, from the carried distances;
//   zhu-bridson  the same with d_i = r_i / 2 (as the paper derives it);
//   blobby       sum of normalised weights = 1/2.
// Measured per surface, before and after: the distance |phi_B(v)| of every mesh vertex v from the true
// faces, mean and max, over the vertices whose nearest face point lies at least 2 r from every edge
// of B (away from the edges and corners); the change of the mean through the down-sampling.
// Vertices farther than 3 r from every face (holes and fragments inside or outside) are counted as
// stray and left out of the mean and max.
// The sphere: the ball of radius 0.3 about the centre of [0, 1]^Dim sampled the same way (N random
// particles inside it, s = (|ball| / N)^(1/Dim)), every vertex measured (no edges), |phi| the
// distance from the sphere; the same sizes, expectations and gates.
// Expected (the paper's claim): the distance-based surface is the least sensitive to the resampling;
// reported (a note when it holds, a warning when not), not asserted. Beside it, row 'distance, exact
// d': the distance surface of the down-sampled particles given their exact distances and redistanced
// once (as "before" is), which separates the model from the distances carried through the passes. Asserted:
// before resampling the distance surface is the closest of the three to the faces, within s on average,
// without stray vertices; after, still without stray vertices. Gated: every mean and max, and the particle
// count. A user varies the problem with --seed S (the random sample and the splits' turns), --particles N,
// --aspect A (the box: 0.6 wide along x and 0.6 / A along the other axes, the longer side kept at
// 0.6) and --radius R (the sphere, 0.05 to 0.35); the gate runs the defaults.

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <random>

#include <fmt/format.h>

#include "common/case.hpp"
#include "liquid/levelset/levelset.hpp"
#include "liquid/sph/distance_surface.hpp"
#include "liquid/sph/feature_size.hpp"
#include "liquid/sph/resample.hpp"
#include "liquid/surface/surface.hpp"

namespace liquid::verification {
namespace {

using sph::SurfaceModel;

struct Errors {
  double mean = 0.0, max = 0.0;
  long vertices = 0, stray = 0;  ///< vertices measured; vertices farther than `reach` from every face
};

/// The sampled solid: its level set, the box its random samples are drawn in, its volume, and which
/// mesh vertices are measured (margin: how far from an edge a vertex must lie).
template <int Dim>
struct Solid {
  std::string what;  ///< "box" or "sphere", for the tables
  levelset::Function<Dim> phi;
  Box<Dim> bounds;
  double volume = 0.0;
  std::function<bool(const Vec<Dim>&, double)> measured;
};

/// The box: 0.6 wide along x and 0.6 / aspect along the other axes (the longer side kept at 0.6),
/// centred in the unit box.
template <int Dim>
Solid<Dim> box_solid(double aspect) {
  Vec<Dim> half = Vec<Dim>::Constant(0.3 * std::min(1.0, 1.0 / aspect));
  half[0] = 0.3 * std::min(1.0, aspect);
  const Box<Dim> box{Vec<Dim>::Constant(0.5) - half, Vec<Dim>::Constant(0.5) + half};
  // A vertex counts when its nearest face point lies at least `margin` from every edge.
  const auto away_from_edges = [box](const Vec<Dim>& v, double margin) {
    int axis = 0;
    double best = 1e300;
    for (int d = 0; d < Dim; ++d)
      for (double face : {box.lo[d], box.hi[d]})
        if (std::abs(v[d] - face) < best) best = std::abs(v[d] - face), axis = d;
    for (int d = 0; d < Dim; ++d)
      if (d != axis && (v[d] < box.lo[d] + margin || v[d] > box.hi[d] - margin)) return false;
    return true;
  };
  return {aspect == 1.0 ? std::string("box") : fmt::format("box of aspect {:g}", aspect),
          levelset::box<Dim>(box), box, box.volume(), away_from_edges};
}

template <int Dim>
Solid<Dim> sphere_solid(double radius) {
  const Vec<Dim> centre = Vec<Dim>::Constant(0.5);
  const double volume =
      Dim == 2 ? std::numbers::pi * radius * radius : 4.0 / 3.0 * std::numbers::pi * std::pow(radius, 3);
  return {radius == 0.3 ? std::string("sphere") : fmt::format("sphere of radius {:g}", radius),
          levelset::sphere<Dim>(centre, radius), Box<Dim>{centre.array() - radius, centre.array() + radius},
          volume, [](const Vec<Dim>&, double) { return true; }};
}

/// Vertex distances |phi| from the solid's surface, over the vertices it measures and within `reach`
/// of the surface; the others farther (fragments and holes) are counted as stray.
template <int Dim>
Errors face_errors(const surface::Mesh<Dim>& mesh, const Solid<Dim>& solid, double margin, double reach) {
  Errors e;
  for (const auto& v : mesh.vertices) {
    if (!solid.measured(v, margin)) continue;
    const double err = std::abs(solid.phi(v));
    if (err > reach) {
      ++e.stray;
      continue;
    }
    e.mean += err, e.max = std::max(e.max, err), ++e.vertices;
  }
  if (e.vertices > 0) e.mean /= static_cast<double>(e.vertices);
  return e;
}

template <int Dim>
Errors surface_errors(const sph::SphParticles<Dim>& p, SurfaceModel model, const Solid<Dim>& solid,
                      double s) {
  const sph::PointTree<Dim> tree(p.x);
  const sph::SurfaceField<Dim> field(tree, p.x, p.radius, p.distance, model);
  const surface::Function<Dim> phi = [&](const Vec<Dim>& x) { return -field.value(x); };
  const Box<Dim> grid{Vec<Dim>::Constant(0.1), Vec<Dim>::Constant(0.9)};
  const auto mesh = surface::extract<Dim>(phi, grid, 0.5 * s);
  return face_errors<Dim>(mesh, solid, 2.0 * 2.5 * s, 3.0 * 2.5 * s);
}

template <int Dim>
CaseResult measure(const Solid<Dim>& solid, const CaseOptions& options) {
  CaseResult result;
  const long n =
      options.particles.value_or(Dim == 2 ? (options.full ? 24000 : 6000) : (options.full ? 100000 : 20000));
  const Box<Dim>& box = solid.bounds;
  const double s = std::pow(solid.volume / static_cast<double>(n), 1.0 / Dim);
  sph::Sizes sizes;
  sizes.radius = 2.5 * s;
  sph::SphParticles<Dim> p;
  std::mt19937_64 rng(options.seed ? *options.seed + Dim : 5 + Dim);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  while (p.size() < n) {
    Vec<Dim> x;
    for (int d = 0; d < Dim; ++d) x[d] = box.lo[d] + box.size()[d] * u(rng);
    if (solid.phi(x) < 0.0) p.add(sizes, x, Vec<Dim>::Zero(), 0, -solid.phi(x), 1.0);
  }
  // The distances the solver carries: one redistancing of the exact ones on the random sample.
  auto redistance_of = [](sph::SphParticles<Dim>& q) {
    const sph::PointTree<Dim> tree(q.x);
    sph::redistance<Dim>(q, sph::find_neighbours_cells<Dim>(q.x, q.radius), tree, 1, 0.5);
  };
  auto redistance_now = [&] { redistance_of(p); };
  redistance_now();
  const SurfaceModel models[] = {SurfaceModel::distance, SurfaceModel::zhu_bridson, SurfaceModel::blobby};
  Errors before[3], after[3];
  for (int m = 0; m < 3; ++m) before[m] = surface_errors<Dim>(p, models[m], solid, s);
  // Down-sampling at rest, as AdaptiveSph's resampling steps do it.
  sph::ResampleOptions ro;
  ro.max_level = 4;
  std::mt19937_64 split_rng(options.seed ? *options.seed + 11 : 11);
  int passes = 0;
  for (; passes < 10; ++passes) {
    const sph::PointTree<Dim> tree(p.x);
    const sph::NeighbourLists nbrs = sph::find_neighbours_cells<Dim>(p.x, p.radius);
    sph::redistance<Dim>(p, nbrs, tree, 1, 0.5);
    sph::feature_size<Dim>(p, nbrs);
    const int count = p.size();
    const sph::ResampleStats r = sph::resample<Dim>(p, nbrs, sizes, ro, nullptr, split_rng);
    if (100 * (r.split + r.merged) < count) {
      ++passes;
      break;
    }
  }
  // The same down-sampled particles with their exact distances, redistanced once as before the
  // down-sampling: what the distance model does on them when the carried distances are right.
  sph::SphParticles<Dim> exact = p;
  for (int i = 0; i < exact.size(); ++i) exact.distance[i] = -solid.phi(exact.x[i]);
  redistance_of(exact);
  const Errors exact_after = surface_errors<Dim>(exact, SurfaceModel::distance, solid, s);
  redistance_now();
  for (int m = 0; m < 3; ++m) after[m] = surface_errors<Dim>(p, models[m], solid, s);
  std::vector<int> per_level(5, 0);
  for (int i = 0; i < p.size(); ++i) ++per_level[std::min<int>(p.level[i], 4)];

  Table table(
      fmt::format("distance of the surface from the faces of a {}D {}, in spacings s = {:.4g} "
                  "(N = {} random particles, down-sampled to {} in {} passes; levels {}, {}, {}, {}, {})",
                  Dim, solid.what, s, n, p.size(), passes, per_level[0], per_level[1], per_level[2],
                  per_level[3], per_level[4]),
      {"surface", "mean before", "max before", "stray before", "mean after", "max after", "stray after",
       "mean moved"});
  double moved[3];
  for (int m = 0; m < 3; ++m) {
    moved[m] = std::abs(after[m].mean - before[m].mean) / s;
    table.add_row({std::string(sph::to_string(models[m])), before[m].mean / s, before[m].max / s,
                   before[m].stray, after[m].mean / s, after[m].max / s, after[m].stray, moved[m]});
    const std::string key = sph::to_string(models[m]);
    result.gate.push_back({key + " mean before", GateFigure::Kind::error, before[m].mean / s});
    result.gate.push_back({key + " max before", GateFigure::Kind::error, before[m].max / s});
    result.gate.push_back({key + " mean after", GateFigure::Kind::error, after[m].mean / s});
    result.gate.push_back({key + " max after", GateFigure::Kind::error, after[m].max / s});
  }
  const double exact_moved = std::abs(exact_after.mean - before[0].mean) / s;
  table.add_row({std::string("distance, exact d"), before[0].mean / s, before[0].max / s, before[0].stray,
                 exact_after.mean / s, exact_after.max / s, exact_after.stray, exact_moved});
  result.gate.push_back({"distance with exact d mean after", GateFigure::Kind::error, exact_after.mean / s});
  result.gate.push_back({"particles after down-sampling", GateFigure::Kind::count, double(p.size())});
  result.expect(before[0].mean < s,
                fmt::format("the distance surface lies {:.3g} s from the faces on average before "
                            "resampling",
                            before[0].mean / s));
  result.expect(
      before[0].mean < before[1].mean && before[0].mean < before[2].mean && before[0].stray == 0,
      fmt::format("before resampling the distance surface lies {:.3g} s from the faces ({} stray vertices); "
                  "Zhu-Bridson's {:.3g} s, the blobbies' {:.3g} s",
                  before[0].mean / s, before[0].stray, before[1].mean / s, before[2].mean / s));
  result.expect(
      after[0].stray == 0,
      fmt::format("after down-sampling the distance surface has {} stray vertices", after[0].stray));
  const bool claim = moved[0] < moved[1] && moved[0] < moved[2];
  (claim ? result.notes : result.warnings)
      .push_back(
          fmt::format("the paper's claim (the distance surface least sensitive to resampling) {}: its mean "
                      "moved {:.3g} s, Zhu-Bridson's {:.3g} s, the blobbies' {:.3g} s",
                      claim ? "holds" : "does not hold here", moved[0], moved[1], moved[2]));
  // Ties within a thousandth of a spacing count (in the quick 3D rows few surface particles are
  // resampled: two models move by 0 or 1e-5 s).
  const bool model_claim = exact_moved <= std::min(moved[1], moved[2]) + 1e-3;
  (model_claim ? result.notes : result.warnings)
      .push_back(fmt::format(
          "with the down-sampled particles' exact distances (redistanced once, as before down-sampling) the "
          "distance surface's mean moves {:.3g} s: the model itself {} the paper's claim; the {:.3g} s above "
          "come from the distances carried through the passes (row 'distance, exact d')",
          exact_moved, model_claim ? "keeps" : "does not keep", moved[0]));
  result.notes.push_back(fmt::format("{}D {}: {} particles down-sampled to {} ({:.0f}%)", Dim, solid.what, n,
                                     p.size(), 100.0 * p.size() / static_cast<double>(n)));
  result.tables.push_back(std::move(table));
  return result;
}

template <int Dim>
CaseResult run_box(const CaseOptions& options) {
  return measure<Dim>(box_solid<Dim>(options.aspect.value_or(1.0)), options);
}

template <int Dim>
CaseResult run_sphere(const CaseOptions& options) {
  return measure<Dim>(sphere_solid<Dim>(options.radius.value_or(0.3)), options);
}

}  // namespace

LIQUID_VERIFICATION_CASE(
    {"sph-flat-surface",
     "distance of the distance-based, Zhu-Bridson and blobby surfaces from a flat face, before "
     "and after adaptive down-sampling (2D, Figs. 5-6)",
     true,
     run_box<2>,
     {Option::seed, Option::particles, Option::aspect}});
LIQUID_VERIFICATION_CASE(
    {"sph-flat-surface-3d",
     "distance of the distance-based, Zhu-Bridson and blobby surfaces from a cube's faces, "
     "before and after adaptive down-sampling (3D, Fig. 6)",
     true,
     run_box<3>,
     {Option::seed, Option::particles, Option::aspect}});
LIQUID_VERIFICATION_CASE(
    {"sph-sphere-surface",
     "distance of the distance-based, Zhu-Bridson and blobby surfaces from a circle, before and after "
     "adaptive down-sampling (2D, a curved surface)",
     true,
     run_sphere<2>,
     {Option::seed, Option::particles, Option::radius}});
LIQUID_VERIFICATION_CASE(
    {"sph-sphere-surface-3d",
     "distance of the distance-based, Zhu-Bridson and blobby surfaces from a sphere, before and after "
     "adaptive down-sampling (3D, a curved surface)",
     true,
     run_sphere<3>,
     {Option::seed, Option::particles, Option::radius}});

}  // namespace liquid::verification
