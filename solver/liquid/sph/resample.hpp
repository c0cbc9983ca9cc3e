#pragma once
// Feature-size resampling of Adams et al. 2007, Sec. 4.2: split a particle when elfs < alpha r_i,
// merge when elfs > beta r_i (alpha = 2, beta = 3).
//
// Split: a level-l particle becomes two of level l - 1, symmetric about it at distance
// d = r_child / (2h), along a direction that keeps both children at least d from every other particle
// (old ones and those made earlier in the same pass) and inside the liquid (on the liquid's side of
// the parent's footpoint tangent plane, and outside every obstacle). Valid directions are found by
// testing a set of candidate directions (2D: 180 angles; 3D: 600 quasi-uniform points on the sphere,
// rotated at random per split) and one is picked at random; when none is valid, d is lowered by 20%
// and the search repeated (12 tries in all, so d is lowered at most 11 times; then the split is skipped and
// counted). Children keep the parent's velocity and acceleration: mass and momentum are conserved exactly.
// Merge: two neighbours of the same level, both marked, become one of level l + 1 at their midpoint
// when no other particle is within r_new / (2h) of it and it is outside every obstacle; otherwise the
// next marked neighbour is tried. The new velocity (and acceleration) is the mass-weighted mean.

#include <cmath>
#include <cstdint>
#include <functional>
#include <random>

#include "liquid/sph/neighbours.hpp"
#include "liquid/sph/sph_particles.hpp"

namespace liquid::sph {

struct ResampleOptions {
  double alpha = 2.0;  ///< split when elfs < alpha r_i
  double beta = 3.0;   ///< merge when elfs > beta r_i (the paper's, for 3D; see for_dimension)
  int max_level = 3;   ///< no merge above this level
  /// The caller's clock (steps), stamped on the particles a pass makes (SphParticles::born).
  std::int64_t now = 0;
  /// A particle a split made less than this long ago (on the clock above) is not merged: the
  /// children of a split are not merged back before the flow has moved them (0: the paper's, no wait).
  std::int64_t merge_min_age = 0;
  /// Churn is counted over this window (on the clock above): a merge of a particle a split made,
  /// or a split of one a merge made, less than this long ago. 0 counts none.
  std::int64_t churn_window = 0;

  /// The paper's alpha = 2 and beta = 3 are for 3D, where a merged particle's radius grows by 2^(1/3):
  /// it merged at elfs > 3 r and splits again only below 2 * 2^(1/3) r = 2.52 r, a margin of 1.19.
  /// In 2D the radius grows by 2^(1/2), which leaves 3 against 2.83, a margin of 1.06, and a still
  /// tank churns: near its surface particles split and merge every pass. beta = 3 * 2^(1/d - 1/3)
  /// keeps the paper's margin in every dimension (2D: 3.37). Why: docs/findings/sph.md.
  static ResampleOptions for_dimension(int dim) {
    ResampleOptions o;
    o.beta = 3.0 * std::pow(2.0, 1.0 / dim - 1.0 / 3.0);
    return o;
  }
};

/// A split places its two children d = r_child / (2h) from the parent when no other particle is
/// closer than d to either; else it lowers d by kSplitShrink and tries again, kSplitTries times in
/// all (then the split is skipped). So no child ever lies closer to another particle than
/// closest_child_bound() times the nominal d.
inline constexpr int kSplitTries = 12;
inline constexpr double kSplitShrink = 0.8;
inline double closest_child_bound() {
  return std::pow(kSplitShrink, kSplitTries - 1);
}

struct ResampleStats {
  long split = 0;          ///< particles split (each into two)
  long merged = 0;         ///< pairs merged (each into one)
  long split_skipped = 0;  ///< marked for a split but no valid placement at any tried distance
  long merge_skipped = 0;  ///< marked for a merge but no partner could merge
  long lowered = 0;        ///< splits placed closer than r_child / (2h)
  long churn_merged = 0;   ///< merges with a partner a split made within ResampleOptions::churn_window
  long churn_split = 0;    ///< splits of a particle a merge made within ResampleOptions::churn_window
  long merge_waited = 0;   ///< marked for a merge but younger than ResampleOptions::merge_min_age
  /// The smallest (distance from a new child to its nearest other particle) / (r_child / (2h)) over
  /// the pass: 1 unless a split had to lower d. Infinite when nothing was split.
  double closest_child_ratio = SphParticles<2>::infinity;
};

/// A solid test: true when x is inside an obstacle (or outside the container).
template <int Dim>
using SolidTest = std::function<bool(const Vec<Dim>&)>;

/// Splits and merges by p.elfs (and p.foot for the tangent-plane test); `nbrs` are the lists of the
/// current positions. New particles are appended, replaced ones removed: indices change. `origin`,
/// when given, receives for each particle after the pass its index before it, or -1 for a particle
/// the pass made.
template <int Dim>
ResampleStats resample(SphParticles<Dim>& p, const NeighbourLists& nbrs, const Sizes& sizes,
                       const ResampleOptions& options, const SolidTest<Dim>& solid, std::mt19937_64& rng,
                       std::vector<std::int32_t>* origin = nullptr);

/// Splits particle-by-particle regardless of elfs (for tests and cases): every particle whose flag is
/// set and whose level is above 0; the same placement rules as resample().
template <int Dim>
ResampleStats split_marked(SphParticles<Dim>& p, const NeighbourLists& nbrs, const Sizes& sizes,
                           const std::vector<char>& marked, const SolidTest<Dim>& solid,
                           std::mt19937_64& rng);

/// Merges marked pairs regardless of elfs (for tests and cases); the same rules as resample().
template <int Dim>
ResampleStats merge_marked(SphParticles<Dim>& p, const NeighbourLists& nbrs, const Sizes& sizes,
                           const std::vector<char>& marked, int max_level, const SolidTest<Dim>& solid);

}  // namespace liquid::sph
