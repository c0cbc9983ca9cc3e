#include "liquid/pic/surface.hpp"

#include <cmath>

#include "liquid/core/error.hpp"

namespace liquid::pic {

template <int Dim>
ParticleSurface<Dim>::ParticleSurface(const tree::CellGraph<Dim>& graph, const Classification& cls,
                                      std::span<const Vec<Dim>> x, int fine_level, double radius)
    : graph_(&graph), cls_(&cls), fine_level_(fine_level) {
  LIQUID_VERIFY(radius > 0.0 && radius < 2.0, "particle surface: radius {} h is outside (0, 2)", radius);
  h_ = std::ldexp(graph.domain().size().minCoeff(), -fine_level);
  support_ = 2.0 * h_;
  radius_ = radius * h_;
  for (const Vec<Dim>& p : x) buckets_[bucket_key(bucket_of(p))].push_back(p);
}

template <int Dim>
IVec<Dim> ParticleSurface<Dim>::bucket_of(const Vec<Dim>& x) const {
  IVec<Dim> b;
  for (int d = 0; d < Dim; ++d)
    b[d] = static_cast<int>(std::floor((x[d] - graph_->domain().lo[d]) / support_));
  return b;
}

template <int Dim>
std::uint64_t ParticleSurface<Dim>::bucket_key(const IVec<Dim>& b) const {
  std::uint64_t key = 0;
  for (int d = 0; d < Dim; ++d) key = key * 2097152u + static_cast<std::uint64_t>(b[d] + 1048576);
  return key;
}

template <int Dim>
double ParticleSurface<Dim>::operator()(const Vec<Dim>& x) const {
  const tree::CellId c = graph_->locate(x);
  if (cls_->is_fluid(c) && graph_->level(c) < fine_level_) return -0.5 * graph_->cell_size(c).minCoeff();
  const IVec<Dim> b = bucket_of(x);
  Vec<Dim> sum = Vec<Dim>::Zero();
  double weight = 0.0;
  const double r2 = support_ * support_;
  for (int corner = 0; corner < (Dim == 2 ? 9 : 27); ++corner) {
    IVec<Dim> q = b;
    for (int d = 0, code = corner; d < Dim; ++d, code /= 3) q[d] += code % 3 - 1;
    const auto it = buckets_.find(bucket_key(q));
    if (it == buckets_.end()) continue;
    for (const Vec<Dim>& p : it->second) {
      const double s2 = (p - x).squaredNorm() / r2;
      if (s2 >= 1.0) continue;
      const double k = (1.0 - s2) * (1.0 - s2) * (1.0 - s2);
      sum += k * p;
      weight += k;
    }
  }
  if (weight <= 0.0) return support_;
  return (x - sum / weight).norm() - radius_;
}

template class ParticleSurface<2>;
template class ParticleSurface<3>;

}  // namespace liquid::pic
