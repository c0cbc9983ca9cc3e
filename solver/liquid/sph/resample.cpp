#include "liquid/sph/resample.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/Geometry>

#include "liquid/core/error.hpp"

namespace liquid::sph {

namespace {

/// Candidate split directions (up to sign): a half circle of angles in 2D, a Fibonacci sphere in 3D.
template <int Dim>
std::vector<Vec<Dim>> base_directions() {
  std::vector<Vec<Dim>> dirs;
  if constexpr (Dim == 2) {
    const int k = 180;
    for (int i = 0; i < k; ++i) {
      const double t = std::numbers::pi * i / k;
      dirs.push_back(Vec<2>(std::cos(t), std::sin(t)));
    }
  } else {
    const int k = 600;
    const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < k; ++i) {
      const double z = 1.0 - 2.0 * (i + 0.5) / k, rho = std::sqrt(1.0 - z * z);
      dirs.push_back(Vec<3>(rho * std::cos(golden * i), rho * std::sin(golden * i), z));
    }
  }
  return dirs;
}

/// The candidates turned by a random rotation (a random angle in 2D, a random unit quaternion in 3D).
template <int Dim>
std::vector<Vec<Dim>> turned(const std::vector<Vec<Dim>>& base, std::mt19937_64& rng) {
  std::vector<Vec<Dim>> out(base.size());
  if constexpr (Dim == 2) {
    std::uniform_real_distribution<double> angle(0.0, std::numbers::pi / base.size());
    const double t = angle(rng), c = std::cos(t), s = std::sin(t);
    for (std::size_t i = 0; i < base.size(); ++i)
      out[i] = Vec<2>(c * base[i][0] - s * base[i][1], s * base[i][0] + c * base[i][1]);
  } else {
    std::normal_distribution<double> g;
    Eigen::Quaterniond q(g(rng), g(rng), g(rng), g(rng));
    q.normalize();
    const Eigen::Matrix3d R = q.toRotationMatrix();
    for (std::size_t i = 0; i < base.size(); ++i) out[i] = R * base[i];
  }
  return out;
}

/// True when particle i was made by `how` (a split or a merge) less than `window` before `now`.
template <int Dim>
bool made_within(const SphParticles<Dim>& p, int i, typename SphParticles<Dim>::Birth how, std::int64_t now,
                 std::int64_t window) {
  return window > 0 && p.birth[i] == how && p.born[i] >= 0 && now - p.born[i] < window;
}

template <int Dim>
struct Pass {
  SphParticles<Dim>& p;
  const NeighbourLists& nbrs;
  const Sizes& sizes;
  const SolidTest<Dim>& solid;
  const int n_old;
  std::int64_t now = 0, churn_window = 0;  ///< the clock stamped on new particles; churn's window
  std::vector<char> removed;
  std::vector<std::vector<int>> born_of;  ///< per old particle: the new particles made from or beside it
  ResampleStats stats;
  std::vector<Vec<Dim>> near_;  ///< split's scratch: the particles that can crowd a child

  Pass(SphParticles<Dim>& p_, const NeighbourLists& nbrs_, const Sizes& sizes_, const SolidTest<Dim>& solid_)
      : p(p_),
        nbrs(nbrs_),
        sizes(sizes_),
        solid(solid_),
        n_old(p_.size()),
        removed(p_.size(), 0),
        born_of(p_.size()) {
    LIQUID_VERIFY(nbrs.n_particles() == n_old, "resample: {} particles, neighbour lists for {}", n_old,
                  nbrs.n_particles());
    LIQUID_VERIFY(p.birth.size() == p.x.size() && p.born.size() == p.x.size(),
                  "resample: {} particles, {} births and {} birth steps", n_old, p.birth.size(),
                  p.born.size());
  }

  bool in_solid(const Vec<Dim>& x) const { return solid && solid(x); }

  /// True when old particle i was made by `how` within the churn window.
  bool young(int i, typename SphParticles<Dim>::Birth how) const {
    return made_within(p, i, how, now, churn_window);
  }

  /// The distance from x to the nearest live particle around old particle i (i itself and `skip`
  /// excluded), old or new.
  double clearance(const Vec<Dim>& x, int i, int skip = -1) const {
    double best = SphParticles<Dim>::infinity;
    auto look = [&](int k) {
      for (int b : born_of[k]) best = std::min(best, (p.x[b] - x).norm());
    };
    look(i);
    for (int j : nbrs.of(i)) {
      if (j != skip && !removed[j]) best = std::min(best, (p.x[j] - x).norm());
      look(j);
    }
    return best;
  }

  void split(int i, const std::vector<Vec<Dim>>& base, std::mt19937_64& rng) {
    const int level = p.level[i];
    const double nominal = sizes.spacing_of<Dim>(level - 1) / 2.0;  // r_child / (2h)
    const Vec<Dim> out = p.foot[i] - p.x[i];
    const double out_len = out.norm();
    const bool plane = out_len > 0.0 && std::isfinite(out_len);
    const std::vector<Vec<Dim>> dirs = turned(base, rng);
    std::vector<int> valid;
    double d = nominal;
    // Only a particle closer to x_i than 2d can come within d of a child d away from x_i: those are
    // gathered once per distance, and every direction is tested against them alone (the same test as
    // clearance() < d, which scans every neighbour and is far slower in 3D).
    std::vector<Vec<Dim>>& near = near_;
    const Vec<Dim> xi = p.x[i];
    const auto gather = [&](double reach) {
      near.clear();
      const auto take = [&](const Vec<Dim>& y) {
        if ((y - xi).squaredNorm() < reach * reach) near.push_back(y);
      };
      const auto born = [&](int k) {
        for (int b : born_of[k]) take(p.x[b]);
      };
      born(i);
      for (int j : nbrs.of(i)) {
        if (!removed[j]) take(p.x[j]);
        born(j);
      }
    };
    const auto crowded = [&](const Vec<Dim>& c, double dd) {
      for (const Vec<Dim>& y : near)
        if ((y - c).squaredNorm() < dd * dd) return true;
      return false;
    };
    for (int attempt = 0; attempt < kSplitTries; ++attempt, d *= kSplitShrink) {
      valid.clear();
      gather(2.0 * d);
      for (int k = 0; k < static_cast<int>(dirs.size()); ++k) {
        bool ok = true;
        for (double sgn : {1.0, -1.0}) {
          const Vec<Dim> c = xi + sgn * d * dirs[k];
          if (crowded(c, d) || in_solid(c) || (plane && (p.foot[i] - c).dot(out) <= 0.0)) {
            ok = false;
            break;
          }
        }
        if (ok) valid.push_back(k);
      }
      if (!valid.empty()) break;
    }
    if (valid.empty()) {
      ++stats.split_skipped;
      return;
    }
    std::uniform_int_distribution<int> pick(0, static_cast<int>(valid.size()) - 1);
    const Vec<Dim> u = dirs[valid[pick(rng)]];
    if (d < nominal) ++stats.lowered;
    const Vec<Dim> x0 = p.x[i], v0 = p.v[i], a0 = p.a[i], foot = p.foot[i];
    const double elfs = p.elfs[i], rho = p.density[i];
    stats.churn_split += young(i, SphParticles<Dim>::Birth::merge);
    removed[i] = 1;
    for (double sgn : {1.0, -1.0}) {
      const Vec<Dim> c = x0 + sgn * d * u;
      stats.closest_child_ratio = std::min(stats.closest_child_ratio, clearance(c, i) / nominal);
      const double dist = plane ? std::max(0.0, (foot - c).dot(out) / out_len) : 0.0;
      const int k = p.add(sizes, c, v0, level - 1, dist, rho);
      p.a[k] = a0, p.foot[k] = foot, p.elfs[k] = elfs;
      p.birth[k] = SphParticles<Dim>::Birth::split, p.born[k] = now;
      born_of[i].push_back(k);
    }
    ++stats.split;
  }

  /// Merges i with the first marked neighbour of its level that can; false when none can.
  /// "First" is in index order, and the particles keep the seeding lattice's row order (splits and
  /// merges append), so on a lattice the pairs share one direction and the merged particles form a
  /// coarser lattice. The nearest marked neighbour, or this rule on Morton-sorted particles, churn
  /// through far more splits and merges (likely: pairs of mixed directions leave gaps that the next
  /// redistancing reads as surface). Why: docs/findings/sph.md.
  bool merge(int i, const std::vector<char>& marked) {
    const int level = p.level[i];
    const double clear = sizes.spacing_of<Dim>(level + 1) / 2.0;  // r_new / (2h)
    for (int j : nbrs.of(i)) {
      if (j >= n_old || removed[j] || !marked[j] || p.level[j] != level) continue;
      const Vec<Dim> c = 0.5 * (p.x[i] + p.x[j]);
      if (in_solid(c)) continue;
      if (std::min(clearance(c, i, j), clearance(c, j, i)) < clear) continue;
      const double mi = p.mass[i], mj = p.mass[j];
      const Vec<Dim> v = (mi * p.v[i] + mj * p.v[j]) / (mi + mj), a = (mi * p.a[i] + mj * p.a[j]) / (mi + mj);
      const double dist = 0.5 * (p.distance[i] + p.distance[j]), elfs = std::min(p.elfs[i], p.elfs[j]);
      const Vec<Dim> foot = p.distance[i] <= p.distance[j] ? p.foot[i] : p.foot[j];
      // The volumes add: rho = (m_i + m_j) / (m_i / rho_i + m_j / rho_j) (0 where a density is unknown).
      const double rho = p.density[i] > 0.0 && p.density[j] > 0.0
                             ? (mi + mj) / (mi / p.density[i] + mj / p.density[j])
                             : 0.0;
      removed[i] = removed[j] = 1;
      const int k = p.add(sizes, c, v, level + 1, dist, rho);
      p.a[k] = a, p.foot[k] = foot, p.elfs[k] = elfs;
      p.birth[k] = SphParticles<Dim>::Birth::merge, p.born[k] = now;
      stats.churn_merged +=
          young(i, SphParticles<Dim>::Birth::split) || young(j, SphParticles<Dim>::Birth::split);
      born_of[i].push_back(k), born_of[j].push_back(k);
      ++stats.merged;
      return true;
    }
    return false;
  }

  ResampleStats finish(std::vector<std::int32_t>* origin = nullptr) {
    std::vector<char> alive(p.size(), 1);
    for (int i = 0; i < n_old; ++i) alive[i] = !removed[i];
    if (origin) {
      origin->clear();
      for (int i = 0; i < p.size(); ++i)
        if (alive[i]) origin->push_back(i < n_old ? i : -1);
    }
    p.keep(alive);
    return stats;
  }
};

}  // namespace

template <int Dim>
ResampleStats split_marked(SphParticles<Dim>& p, const NeighbourLists& nbrs, const Sizes& sizes,
                           const std::vector<char>& marked, const SolidTest<Dim>& solid,
                           std::mt19937_64& rng) {
  Pass<Dim> pass(p, nbrs, sizes, solid);
  const std::vector<Vec<Dim>> base = base_directions<Dim>();
  for (int i = 0; i < pass.n_old; ++i)
    if (marked[i] && p.level[i] > 0) pass.split(i, base, rng);
  return pass.finish();
}

template <int Dim>
ResampleStats merge_marked(SphParticles<Dim>& p, const NeighbourLists& nbrs, const Sizes& sizes,
                           const std::vector<char>& marked, int max_level, const SolidTest<Dim>& solid) {
  Pass<Dim> pass(p, nbrs, sizes, solid);
  for (int i = 0; i < pass.n_old; ++i)
    if (marked[i] && !pass.removed[i] && p.level[i] < max_level && !pass.merge(i, marked))
      ++pass.stats.merge_skipped;
  return pass.finish();
}

template <int Dim>
ResampleStats resample(SphParticles<Dim>& p, const NeighbourLists& nbrs, const Sizes& sizes,
                       const ResampleOptions& options, const SolidTest<Dim>& solid, std::mt19937_64& rng,
                       std::vector<std::int32_t>* origin) {
  LIQUID_VERIFY(options.alpha > 0.0 && options.beta > options.alpha,
                "resample: alpha = {} and beta = {} must satisfy 0 < alpha < beta", options.alpha,
                options.beta);
  Pass<Dim> pass(p, nbrs, sizes, solid);
  pass.now = options.now, pass.churn_window = options.churn_window;
  const int n = pass.n_old;
  std::vector<char> to_merge(n, 0);
  for (int i = 0; i < n; ++i) {
    to_merge[i] = p.elfs[i] > options.beta * p.radius[i] && p.level[i] < options.max_level;
    if (to_merge[i] &&
        made_within(p, i, SphParticles<Dim>::Birth::split, options.now, options.merge_min_age)) {
      to_merge[i] = 0;
      ++pass.stats.merge_waited;
    }
  }
  const std::vector<Vec<Dim>> base = base_directions<Dim>();
  for (int i = 0; i < n; ++i)
    if (p.level[i] > 0 && p.elfs[i] < options.alpha * p.radius[i]) pass.split(i, base, rng);
  for (int i = 0; i < n; ++i)
    if (to_merge[i] && !pass.removed[i] && !pass.merge(i, to_merge)) ++pass.stats.merge_skipped;
  return pass.finish(origin);
}

template ResampleStats resample<2>(SphParticles<2>&, const NeighbourLists&, const Sizes&,
                                   const ResampleOptions&, const SolidTest<2>&, std::mt19937_64&,
                                   std::vector<std::int32_t>*);
template ResampleStats resample<3>(SphParticles<3>&, const NeighbourLists&, const Sizes&,
                                   const ResampleOptions&, const SolidTest<3>&, std::mt19937_64&,
                                   std::vector<std::int32_t>*);
template ResampleStats split_marked<2>(SphParticles<2>&, const NeighbourLists&, const Sizes&,
                                       const std::vector<char>&, const SolidTest<2>&, std::mt19937_64&);
template ResampleStats split_marked<3>(SphParticles<3>&, const NeighbourLists&, const Sizes&,
                                       const std::vector<char>&, const SolidTest<3>&, std::mt19937_64&);
template ResampleStats merge_marked<2>(SphParticles<2>&, const NeighbourLists&, const Sizes&,
                                       const std::vector<char>&, int, const SolidTest<2>&);
template ResampleStats merge_marked<3>(SphParticles<3>&, const NeighbourLists&, const Sizes&,
                                       const std::vector<char>&, int, const SolidTest<3>&);

}  // namespace liquid::sph
