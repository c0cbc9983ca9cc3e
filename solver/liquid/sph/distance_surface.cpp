#include "liquid/sph/distance_surface.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "liquid/core/error.hpp"
#include "liquid/sph/kernels.hpp"

namespace liquid::sph {

const char* to_string(SurfaceModel model) {
  switch (model) {
    case SurfaceModel::distance:
      return "distance";
    case SurfaceModel::zhu_bridson:
      return "zhu-bridson";
    case SurfaceModel::blobby:
      return "blobby";
  }
  return "?";
}

namespace {
/// More distinct radii than this are not levels: one tree, searched within the largest.
constexpr std::size_t kMaxGroups = 16;
/// The integral of the surface weight over its support: pi r^2 / 4 (2D), 64 pi r^3 / 315 (3D).
template <int Dim>
double weight_integral(double r) {
  return Dim == 2 ? std::numbers::pi * r * r / 4.0 : 64.0 * std::numbers::pi * r * r * r / 315.0;
}
}  // namespace

template <int Dim>
SurfaceField<Dim>::SurfaceField(const PointTree<Dim>& tree, std::span<const Vec<Dim>> x,
                                std::span<const double> radius, std::span<const double> distance,
                                SurfaceModel model, double spacing_ratio)
    : tree_(tree), x_(x), radius_(radius), distance_(distance), model_(model), spacing_ratio_(spacing_ratio) {
  LIQUID_VERIFY(tree.size() == static_cast<int>(x.size()) && radius.size() == x.size(),
                "SurfaceField: {} points in the tree, {} positions, {} radii", tree.size(), x.size(),
                radius.size());
  LIQUID_VERIFY(model != SurfaceModel::distance || distance.size() == x.size(),
                "SurfaceField: the distance model needs one distance per particle ({} for {})",
                distance.size(), x.size());
  std::vector<double> radii;
  for (double r : radius) {
    max_radius_ = std::max(max_radius_, r);
    if (radii.size() <= kMaxGroups && std::find(radii.begin(), radii.end(), r) == radii.end())
      radii.push_back(r);
  }
  if (radii.size() < 2 || radii.size() > kMaxGroups) return;
  std::sort(radii.begin(), radii.end());
  groups_.resize(radii.size());
  for (std::size_t g = 0; g < radii.size(); ++g) groups_[g].radius = radii[g];
  for (std::size_t i = 0; i < radius.size(); ++i) {
    const auto g = std::lower_bound(radii.begin(), radii.end(), radius[i]) - radii.begin();
    groups_[g].index.push_back(static_cast<std::int32_t>(i));
  }
  std::vector<Vec<Dim>> points;
  for (Group& group : groups_) {
    points.clear();
    for (std::int32_t i : group.index) points.push_back(x[i]);
    group.tree.build(points);
  }
}

template <int Dim>
double SurfaceField<Dim>::value(const Vec<Dim>& y) const {
  return value_gradient(y).first;
}

template <int Dim>
std::pair<double, Vec<Dim>> SurfaceField<Dim>::value_gradient(const Vec<Dim>& y) const {
  thread_local std::vector<std::pair<std::uint32_t, double>> hits;
  using Mat = Eigen::Matrix<double, Dim, Dim>;
  double W = 0.0, D = 0.0;
  Vec<Dim> A = Vec<Dim>::Zero(), gW = Vec<Dim>::Zero(), gD = Vec<Dim>::Zero();
  Mat gA = Mat::Zero();  // gA(k, l) = d(sum w_i x_i,k) / d y_l
  const auto add = [&](std::size_t j, double d2) {
    const double r = radius_[j], q = std::sqrt(d2);
    if (q >= r) return;
    const double w = surface_weight(q, r);
    const Vec<Dim> gw = q > 0.0 ? Vec<Dim>((surface_weight_slope(q, r) / q) * (y - x_[j])) : Vec<Dim>::Zero();
    if (model_ == SurfaceModel::blobby) {
      const double s = r / spacing_ratio_, scale = std::pow(s, Dim) / weight_integral<Dim>(r);
      W += scale * w, gW += scale * gw;
      return;
    }
    const double d = model_ == SurfaceModel::distance ? distance_[j] : 0.5 * r;
    W += w, gW += gw;
    D += w * d, gD += d * gw;
    A += w * x_[j], gA += x_[j] * gw.transpose();
  };
  if (groups_.empty()) {
    tree_.within(y, max_radius_, hits);
    for (const auto& [j, d2] : hits) add(j, d2);
  } else {
    for (const Group& group : groups_) {
      group.tree.within(y, group.radius, hits);
      for (const auto& [k, d2] : hits) add(static_cast<std::size_t>(group.index[k]), d2);
    }
  }
  if (model_ == SurfaceModel::blobby) return {W - 0.5, gW};
  if (W <= 0.0) return {-max_radius_, Vec<Dim>::Zero()};
  const double dbar = D / W;
  const Vec<Dim> a = A / W;
  const Vec<Dim> gdbar = (gD - dbar * gW) / W;
  const Mat ga = (gA - a * gW.transpose()) / W;
  const Vec<Dim> e = a - y;
  const double len = e.norm();
  Vec<Dim> glen = Vec<Dim>::Zero();
  if (len > 0.0) glen = (ga - Mat::Identity()).transpose() * e / len;
  return {dbar - len, gdbar - glen};
}

template <int Dim>
RedistanceStats redistance(SphParticles<Dim>& p, const NeighbourLists& nbrs, const PointTree<Dim>& tree,
                           int bisections, double disk, MarchOrder order) {
  const int n = p.size();
  LIQUID_VERIFY(nbrs.n_particles() == n && tree.size() == n,
                "redistance: {} particles, neighbour lists for {}, a tree of {}", n, nbrs.n_particles(),
                tree.size());
  const SurfaceField<Dim> phi(tree, p.x, p.radius, p.distance, SurfaceModel::distance);
  std::vector<char> on_surface(n, 0);
  std::vector<Vec<Dim>> centre(n), normal(n);  // footpoint disks, normals pointing out of the liquid
  long failed = 0;
#pragma omp parallel for schedule(dynamic, 64) reduction(+ : failed)
  for (int i = 0; i < n; ++i) {
    if (!(p.distance[i] < p.radius[i])) continue;
    const auto [f0, g0] = phi.value_gradient(p.x[i]);
    const double gn = g0.norm();
    if (!(gn > 0.0)) {
      ++failed;
      continue;
    }
    // Towards decreasing phi from inside, increasing from outside: towards the zero set.
    const Vec<Dim> dir = (f0 >= 0.0 ? -1.0 : 1.0) / gn * g0;
    double s0 = 0.0, s1 = p.radius[i], v0 = f0, v1 = phi.value(p.x[i] + s1 * dir);
    for (int k = 0; k <= bisections; ++k) {
      const double sm = 0.5 * (s0 + s1), vm = phi.value(p.x[i] + sm * dir);
      if ((v0 > 0.0) != (vm > 0.0))
        s1 = sm, v1 = vm;
      else if ((vm > 0.0) != (v1 > 0.0))
        s0 = sm, v0 = vm;
      else
        break;  // no sign change on the ray (checked below)
    }
    if ((v0 > 0.0) == (v1 > 0.0)) {
      ++failed;
      continue;
    }
    const double s = s0 + (s1 - s0) * v0 / (v0 - v1);
    const Vec<Dim> y = p.x[i] + s * dir;
    const Vec<Dim> gy = phi.value_gradient(y).second;
    const double gyn = gy.norm();
    if (!(gyn > 0.0)) {
      ++failed;
      continue;
    }
    on_surface[i] = 1;
    centre[i] = y;
    normal[i] = -gy / gyn;
  }
  // The march: each particle keeps the nearest disk among those its neighbours were reached from.
  std::vector<double> dist(n, SphParticles<Dim>::infinity);
  std::vector<int> source(n, -1);
  RedistanceStats stats;
  stats.failed = failed;
  for (int i = 0; i < n; ++i)
    if (on_surface[i]) {
      dist[i] = (p.x[i] - centre[i]).norm(), source[i] = i;
      ++stats.projected;
    }
  const double band = n > 0 ? 0.5 * *std::min_element(p.radius.begin(), p.radius.end()) : 0.0;
  march(
      order, nbrs, dist, source,
      [&](int j, int s) {
        return (p.x[j] - closest_on_disk<Dim>(p.x[j], centre[s], normal[s], disk * p.radius[s])).norm();
      },
      band);
  long unreached = 0, propagated = 0;
#pragma omp parallel for schedule(static) reduction(+ : unreached, propagated)
  for (int i = 0; i < n; ++i) {
    if (source[i] < 0) {
      ++unreached;
      continue;
    }
    if (!on_surface[i]) ++propagated;
    p.distance[i] = dist[i];
    p.foot[i] = source[i] == i ? centre[i]
                               : closest_on_disk<Dim>(p.x[i], centre[source[i]], normal[source[i]],
                                                      disk * p.radius[source[i]]);
  }
  stats.unreached = unreached, stats.propagated = propagated;
  return stats;
}

template class SurfaceField<2>;
template class SurfaceField<3>;
template RedistanceStats redistance<2>(SphParticles<2>&, const NeighbourLists&, const PointTree<2>&, int,
                                       double, MarchOrder);
template RedistanceStats redistance<3>(SphParticles<3>&, const NeighbourLists&, const PointTree<3>&, int,
                                       double, MarchOrder);

}  // namespace liquid::sph
