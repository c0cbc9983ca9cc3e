#include "liquid/sph/feature_size.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "liquid/core/error.hpp"

namespace liquid::sph {

template <int Dim>
FeatureStats feature_size(SphParticles<Dim>& p, const NeighbourLists& nbrs, double gamma_degrees,
                          std::vector<char>* medial_out, MarchOrder order) {
  const int n = p.size();
  LIQUID_VERIFY(nbrs.n_particles() == n, "feature_size: {} particles, neighbour lists for {}", n,
                nbrs.n_particles());
  const double cos_gamma = std::cos(gamma_degrees * std::numbers::pi / 180.0);
  std::vector<Vec<Dim>> dir(n);
  std::vector<char> has_dir(n, 0);
  for (int i = 0; i < n; ++i) {
    const Vec<Dim> e = p.foot[i] - p.x[i];
    const double len = e.norm();
    if (len > 0.0 && std::isfinite(len)) dir[i] = e / len, has_dir[i] = 1;
  }
  std::vector<char> across(n, 0), medial(n, 0);
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i) {
    if (!has_dir[i]) continue;
    for (int j : nbrs.of(i))
      if (has_dir[j] && dir[i].dot(dir[j]) < cos_gamma &&
          (p.foot[i] - p.foot[j]).squaredNorm() > (p.x[i] - p.x[j]).squaredNorm()) {
        across[i] = 1;
        break;
      }
  }
  std::vector<Vec<Dim>> axis;
  FeatureStats stats;
  for (int i = 0; i < n; ++i) {
    const auto row = nbrs.of(i);
    if (row.empty()) {
      medial[i] = 1;
    } else if (across[i]) {
      long k = 0;
      for (int j : row) k += across[j];
      medial[i] = 2 * k >= static_cast<long>(row.size());
    }
    if (medial[i]) axis.push_back(p.x[i]), ++stats.medial;
  }
  const PointTree<Dim> axis_tree(axis);
  // The nearest medial particle of each footpoint near the surface, then the march from them: each
  // carries its footpoint and that footpoint's lfs.
  std::vector<double> lfs(n, SphParticles<Dim>::infinity);
#pragma omp parallel for schedule(dynamic, 256)
  for (int i = 0; i < n; ++i)
    if ((p.x[i] - p.foot[i]).norm() < p.radius[i]) lfs[i] = axis_tree.nearest(p.foot[i]).second;
  std::vector<double> elfs(n, SphParticles<Dim>::infinity);
  std::vector<int> source(n, -1);
  for (int i = 0; i < n; ++i) {
    const double d = (p.x[i] - p.foot[i]).norm();
    if (!(d < p.radius[i])) continue;
    elfs[i] = d + lfs[i], source[i] = i;
    ++stats.near_surface;
  }
  const double band = n > 0 ? 0.5 * *std::min_element(p.radius.begin(), p.radius.end()) : 0.0;
  march(
      order, nbrs, elfs, source, [&](int j, int s) { return (p.x[j] - p.foot[s]).norm() + lfs[s]; }, band);
  std::copy(elfs.begin(), elfs.end(), p.elfs.begin());
  for (int i = 0; i < n; ++i) stats.unreached += !std::isfinite(p.elfs[i]);
  if (medial_out) *medial_out = std::move(medial);
  return stats;
}

template FeatureStats feature_size<2>(SphParticles<2>&, const NeighbourLists&, double, std::vector<char>*,
                                      MarchOrder);
template FeatureStats feature_size<3>(SphParticles<3>&, const NeighbourLists&, double, std::vector<char>*,
                                      MarchOrder);

}  // namespace liquid::sph
