#pragma once
// The particle surface models and the redistancing of Adams et al. 2007, Sec. 5.
//
// Surface models, each a level-set function positive inside the liquid, negative outside:
//   distance    phi(x) = d(x) - |a(x) - x|          (Eqs. 5-7), with the carried distances d_i
//   zhu-bridson the same with d_i = r_i / 2          (Zhu and Bridson 2005, as the paper states it)
//   blobby      phi(x) = sum_i w_i(x) s_i^Dim / I_i - 1/2, s_i the particle's spacing and I_i the
//               integral of w_i: 1 deep inside a regular lattice, so the iso-level 1/2 sits near the
//               last layer's edge
// with the weights w_i(x) = (1 - (|x - x_i| / r_i)^2)^3 of Eq. 8. Where no particle reaches, phi is
// -(the largest radius) for the distance and Zhu-Bridson models, -1/2 for the blobbies.
//
// Redistancing (Sec. 5.2): particles with d_i < r_i are projected onto phi = 0 along the gradient
// (values at s = 0, r_i/2, r_i, `bisections` halvings of the interval that changes sign, then linear
// interpolation; the paper uses one); each projected particle carries a footpoint disk (centre y_i,
// normal the surface's at y_i, radius `disk` r_i: the paper's is r_i, AdaptiveSph's default half of it,
// see SphOptions::disk_radius); a Dijkstra-ordered fast march over the neighbour graph then
// gives every particle the distance to the nearest disk it is reached from, and that disk's closest
// point as its footpoint (march.hpp: the paper's queue, or rounds of relaxation on all threads).

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "liquid/core/types.hpp"
#include "liquid/sph/march.hpp"
#include "liquid/sph/neighbours.hpp"
#include "liquid/sph/sph_particles.hpp"

namespace liquid::sph {

enum class SurfaceModel { distance, zhu_bridson, blobby };
const char* to_string(SurfaceModel model);

/// The implicit surface of a particle set (views: the spans must outlive it).
template <int Dim>
class SurfaceField {
 public:
  /// `tree` holds exactly the points x; `distance` is read by the distance model only; `spacing_ratio`
  /// (support radius / spacing, the paper's h) by the blobby model only.
  SurfaceField(const PointTree<Dim>& tree, std::span<const Vec<Dim>> x, std::span<const double> radius,
               std::span<const double> distance, SurfaceModel model, double spacing_ratio = 2.5);

  double value(const Vec<Dim>& y) const;
  /// phi and its gradient (exact derivatives of the weighted sums).
  std::pair<double, Vec<Dim>> value_gradient(const Vec<Dim>& y) const;

 private:
  /// The particles of one radius (one level), in a tree of their own.
  struct Group {
    double radius = 0.0;
    std::vector<std::int32_t> index;  ///< the group's particles, by their index in x
    PointTree<Dim> tree;
  };

  const PointTree<Dim>& tree_;
  std::span<const Vec<Dim>> x_;
  std::span<const double> radius_, distance_;
  SurfaceModel model_;
  double spacing_ratio_ = 2.5, max_radius_ = 0.0;
  /// With a few distinct radii (levels), one tree per radius, each searched within its own radius:
  /// one search of `tree_` within the largest radius finds 2^max_level times too many particles
  /// where the small ones crowd. Empty: one radius, or too many distinct ones; `tree_` is searched.
  std::vector<Group> groups_;
};

struct RedistanceStats {
  long projected = 0;   ///< particles placed on the surface by the projection
  long failed = 0;      ///< particles with d_i < r_i whose ray met no sign change
  long propagated = 0;  ///< particles given a distance by the march
  long unreached = 0;   ///< particles no disk reached (they keep their carried distance)
};

/// Updates p.distance and p.foot from the distance surface of the carried distances. `tree` holds
/// the positions p.x and `nbrs` their neighbour lists.
template <int Dim>
RedistanceStats redistance(SphParticles<Dim>& p, const NeighbourLists& nbrs, const PointTree<Dim>& tree,
                           int bisections = 1, double disk = 0.5, MarchOrder order = MarchOrder::serial);

/// The point of the disk (centre c, unit normal n, radius R) nearest x.
template <int Dim>
Vec<Dim> closest_on_disk(const Vec<Dim>& x, const Vec<Dim>& c, const Vec<Dim>& n, double R) {
  const Vec<Dim> w = x - c;
  const Vec<Dim> t = w - w.dot(n) * n;
  const double len = t.norm();
  return len <= R ? Vec<Dim>(c + t) : Vec<Dim>(c + (R / len) * t);
}

}  // namespace liquid::sph
