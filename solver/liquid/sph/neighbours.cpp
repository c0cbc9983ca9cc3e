#include "liquid/sph/neighbours.hpp"

#include <algorithm>
#include <limits>

#include <nanoflann.hpp>

#include "liquid/core/error.hpp"

namespace liquid::sph {

namespace {
/// nanoflann's dataset interface over a vector of points.
template <int Dim>
struct Cloud {
  std::vector<Vec<Dim>> points;
  std::size_t kdtree_get_point_count() const { return points.size(); }
  double kdtree_get_pt(std::size_t i, std::size_t d) const { return points[i][static_cast<int>(d)]; }
  template <class B>
  bool kdtree_get_bbox(B&) const {
    return false;
  }
};
}  // namespace

template <int Dim>
struct PointTree<Dim>::Impl {
  using Index = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Cloud<Dim>>,
                                                    Cloud<Dim>, Dim, std::uint32_t>;
  Cloud<Dim> cloud;
  std::unique_ptr<Index> index;
};

template <int Dim>
PointTree<Dim>::PointTree() : impl_(std::make_unique<Impl>()) {}
template <int Dim>
PointTree<Dim>::PointTree(std::span<const Vec<Dim>> points) : PointTree() {
  build(points);
}
template <int Dim>
PointTree<Dim>::~PointTree() = default;
template <int Dim>
PointTree<Dim>::PointTree(PointTree&&) noexcept = default;
template <int Dim>
PointTree<Dim>& PointTree<Dim>::operator=(PointTree&&) noexcept = default;

template <int Dim>
void PointTree<Dim>::build(std::span<const Vec<Dim>> points) {
  impl_->cloud.points.assign(points.begin(), points.end());
  impl_->index = std::make_unique<typename Impl::Index>(Dim, impl_->cloud,
                                                        nanoflann::KDTreeSingleIndexAdaptorParams(16));
  impl_->index->buildIndex();
}

template <int Dim>
int PointTree<Dim>::size() const {
  return static_cast<int>(impl_->cloud.points.size());
}

template <int Dim>
void PointTree<Dim>::within(const Vec<Dim>& x, double radius,
                            std::vector<std::pair<std::uint32_t, double>>& out) const {
  out.clear();
  if (!impl_->index || impl_->cloud.points.empty()) return;
  nanoflann::SearchParams params(32, 0.0f, false);
  impl_->index->radiusSearch(x.data(), radius * radius, out, params);
}

template <int Dim>
std::pair<int, double> PointTree<Dim>::nearest(const Vec<Dim>& x) const {
  if (!impl_->index || impl_->cloud.points.empty()) return {-1, std::numeric_limits<double>::infinity()};
  std::uint32_t i = 0;
  double d2 = 0.0;
  impl_->index->knnSearch(x.data(), 1, &i, &d2);
  return {static_cast<int>(i), std::sqrt(d2)};
}

template <int Dim>
NeighbourLists find_neighbours(const PointTree<Dim>& tree, std::span<const Vec<Dim>> x,
                               std::span<const double> radius) {
  const int n = static_cast<int>(x.size());
  LIQUID_VERIFY(tree.size() == n && static_cast<int>(radius.size()) == n,
                "find_neighbours: the tree holds {} points, the particles are {} with {} radii", tree.size(),
                n, radius.size());
  // Each particle's own query finds the pairs within its radius; a pair beyond the smaller radius
  // is found by the larger particle only, and is added to the smaller one's row afterwards.
  std::vector<std::vector<std::int32_t>> rows(n);
#pragma omp parallel
  {
    std::vector<std::pair<std::uint32_t, double>> hits;
#pragma omp for schedule(dynamic, 256)
    for (int i = 0; i < n; ++i) {
      tree.within(x[i], radius[i], hits);
      auto& row = rows[i];
      row.clear();
      for (const auto& [j, d2] : hits)
        if (static_cast<int>(j) != i) row.push_back(static_cast<std::int32_t>(j));
    }
  }
  std::vector<std::vector<std::int32_t>> extra(n);
  for (int i = 0; i < n; ++i)
    for (std::int32_t j : rows[i])
      if ((x[j] - x[i]).squaredNorm() >= radius[j] * radius[j]) extra[j].push_back(i);
  NeighbourLists lists;
  lists.begin.assign(n + 1, 0);
  for (int i = 0; i < n; ++i) lists.begin[i + 1] = lists.begin[i] + rows[i].size() + extra[i].size();
  lists.index.resize(lists.begin[n]);
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i) {
    auto out = lists.index.begin() + lists.begin[i];
    auto mid = std::copy(rows[i].begin(), rows[i].end(), out);
    auto end = std::copy(extra[i].begin(), extra[i].end(), mid);
    std::sort(out, end);
  }
  return lists;
}

template class PointTree<2>;
template class PointTree<3>;
template NeighbourLists find_neighbours<2>(const PointTree<2>&, std::span<const Vec<2>>,
                                           std::span<const double>);
template NeighbourLists find_neighbours<3>(const PointTree<3>&, std::span<const Vec<3>>,
                                           std::span<const double>);

}  // namespace liquid::sph
