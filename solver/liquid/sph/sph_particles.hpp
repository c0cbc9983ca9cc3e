#pragma once
// Multi-level SPH particles as a structure of arrays (Adams et al. 2007, Sec. 3). A particle of level
// l = 0, 1, 2, ... has mass 2^l m and support radius 2^(l/Dim) r: in 3D the paper's cube root of 2^l,
// in 2D the square root, so that in both the radius grows with the particle's volume. Its initial
// spacing to its neighbours is radius / h_ratio (the paper's h = 2.5).

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "liquid/core/types.hpp"

namespace liquid::sph {

/// The sizes of the particles of every level.
struct Sizes {
  double mass = 1.0;     ///< m: the mass of a level-0 particle
  double radius = 1.0;   ///< r: the support radius of a level-0 particle
  double h_ratio = 2.5;  ///< support radius / spacing (the paper's h)

  double mass_of(int level) const { return std::ldexp(mass, level); }
  template <int Dim>
  double radius_of(int level) const {
    return radius * std::pow(2.0, static_cast<double>(level) / Dim);
  }
  template <int Dim>
  double spacing_of(int level) const {
    return radius_of<Dim>(level) / h_ratio;
  }
};

template <int Dim>
struct SphParticles {
  static constexpr double infinity = std::numeric_limits<double>::infinity();

  std::vector<Vec<Dim>> x;         ///< position
  std::vector<Vec<Dim>> v;         ///< velocity (at the half step: leap-frog)
  std::vector<Vec<Dim>> a;         ///< acceleration of the last force evaluation
  std::vector<std::int8_t> level;  ///< 0 = the smallest
  std::vector<double> mass;
  std::vector<double> radius;    ///< support radius
  std::vector<double> density;   ///< rho_i: carried (continuity) or of the last force evaluation (summation)
  std::vector<double> drho;      ///< D rho_i / Dt of the last force evaluation (continuity)
  std::vector<double> pressure;  ///< P_i of the last force evaluation
  std::vector<double> distance;  ///< d_i: the carried particle-to-surface distance (>= 0)
  std::vector<Vec<Dim>> foot;    ///< y_i: the closest surface point found by the last redistancing
  std::vector<double> elfs;      ///< extended local feature size of the last estimate
  /// How the particle was made and when: by a split or a merge at step `born` (the resampling's
  /// clock), or seeded / emitted (born -1). Resampling reads it to count churn and, when asked, to
  /// keep a split's children from merging back at once.
  enum class Birth : std::int8_t { seeded = 0, split = 1, merge = 2 };
  std::vector<Birth> birth;
  std::vector<std::int64_t> born;

  int size() const { return static_cast<int>(x.size()); }

  /// Appends a particle of `level` at rest-state values; returns its index.
  int add(const Sizes& sizes, const Vec<Dim>& position, const Vec<Dim>& velocity, int level_, double dist,
          double rho = 0.0) {
    x.push_back(position);
    v.push_back(velocity);
    a.push_back(Vec<Dim>::Zero());
    level.push_back(static_cast<std::int8_t>(level_));
    mass.push_back(sizes.mass_of(level_));
    radius.push_back(sizes.radius_of<Dim>(level_));
    density.push_back(rho);
    drho.push_back(0.0);
    pressure.push_back(0.0);
    distance.push_back(dist);
    foot.push_back(position);
    elfs.push_back(infinity);
    birth.push_back(Birth::seeded);
    born.push_back(-1);
    return size() - 1;
  }

  /// Keeps the particles whose flag is true, in their order.
  void keep(const std::vector<char>& alive) {
    int n = 0;
    for (int i = 0; i < size(); ++i) {
      if (!alive[i]) continue;
      if (n != i) {
        x[n] = x[i], v[n] = v[i], a[n] = a[i], level[n] = level[i], mass[n] = mass[i];
        radius[n] = radius[i], density[n] = density[i], drho[n] = drho[i], pressure[n] = pressure[i];
        distance[n] = distance[i], foot[n] = foot[i], elfs[n] = elfs[i], birth[n] = birth[i],
        born[n] = born[i];
      }
      ++n;
    }
    x.resize(n), v.resize(n), a.resize(n), level.resize(n), mass.resize(n), radius.resize(n);
    density.resize(n), drho.resize(n), pressure.resize(n), distance.resize(n), foot.resize(n), elfs.resize(n);
    birth.resize(n), born.resize(n);
  }

  double total_mass() const {
    double m = 0.0;
    for (double mi : mass) m += mi;
    return m;
  }
  Vec<Dim> momentum() const {
    Vec<Dim> p = Vec<Dim>::Zero();
    for (int i = 0; i < size(); ++i) p += mass[i] * v[i];
    return p;
  }
};

}  // namespace liquid::sph
