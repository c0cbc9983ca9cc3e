#pragma once
// The extended local feature size of Adams et al. 2007, Sec. 4.1:
//   elfs(x) = min over surface points y of |x - y| + lfs(y),
// with lfs(y) the distance from y to an approximate medial axis made of particles.
//
// Medial axis: particles i, j (neighbours) lie across it when the directions to their footpoints
// make an angle above gamma (the paper's 60 degrees) and |y_i - y_j| > |x_i - x_j| (which prunes
// branches near the surface); of these, the particles with at least half of their neighbours also
// across it are kept; a particle without neighbours is medial too. lfs(y_i) is the distance from the
// footpoint y_i to the nearest medial particle; particles near the surface (|x_i - y_i| < r_i) start a
// march over the neighbour graph that carries (y', lfs(y')) inwards (march.hpp: the paper's
// Dijkstra order, or rounds of relaxation on all threads).

#include <vector>

#include "liquid/sph/march.hpp"
#include "liquid/sph/neighbours.hpp"
#include "liquid/sph/sph_particles.hpp"

namespace liquid::sph {

struct FeatureStats {
  long medial = 0;        ///< particles on the approximate medial axis
  long near_surface = 0;  ///< particles the march started from
  long unreached = 0;     ///< particles left at infinite elfs
};

/// Writes p.elfs from p.foot (the last redistancing's footpoints). `medial`, when given, receives the
/// medial-axis flag of every particle.
template <int Dim>
FeatureStats feature_size(SphParticles<Dim>& p, const NeighbourLists& nbrs, double gamma_degrees = 60.0,
                          std::vector<char>* medial = nullptr, MarchOrder order = MarchOrder::serial);

}  // namespace liquid::sph
