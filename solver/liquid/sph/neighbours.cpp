#include "liquid/sph/neighbours.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
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

long NeighbourLists::n_pairs() const {
  if (packed()) return static_cast<long>(index.size()) / 2;
  const int n = n_particles();
  long entries = 0;
#pragma omp parallel for schedule(static) reduction(+ : entries)
  for (int i = 0; i < n; ++i) entries += static_cast<long>(end[i] - begin[i]);
  return entries / 2;
}

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
std::span<const std::uint32_t> PointTree<Dim>::leaf_order() const {
  if (!impl_->index) return {};
  return impl_->index->vAcc;
}

template <int Dim>
NeighbourLists find_neighbours(const PointTree<Dim>& tree, std::span<const Vec<Dim>> x,
                               std::span<const double> radius) {
  const int n = static_cast<int>(x.size());
  LIQUID_VERIFY(tree.size() == n && static_cast<int>(radius.size()) == n,
                "find_neighbours: the tree holds {} points, the particles are {} with {} radii", tree.size(),
                n, radius.size());
  // Each particle's own query finds the pairs within its radius; a pair beyond the smaller radius
  // is found by the larger particle only, and is added to the smaller one's row afterwards. The hits
  // are kept per block of particles (one buffer each, not one per particle), and every pass runs in
  // parallel: the added pairs are counted and placed with atomic counters, then each row is sorted,
  // so the lists do not depend on the threads' timing.
  constexpr int kBlock = 1024;
  const int n_blocks = (n + kBlock - 1) / kBlock;
  std::vector<std::vector<std::int32_t>> hits_of_block(n_blocks);
  std::vector<std::int32_t> own(n, 0), added(n, 0);
  // Queries in the tree's leaf order: neighbouring queries walk the same nodes and points.
  const std::span<const std::uint32_t> order = tree.leaf_order();
  auto larger_only = [&](int i, int j) { return (x[j] - x[i]).squaredNorm() >= radius[j] * radius[j]; };
#pragma omp parallel
  {
    std::vector<std::pair<std::uint32_t, double>> hits;
#pragma omp for schedule(dynamic, 1)
    for (int b = 0; b < n_blocks; ++b) {
      auto& out = hits_of_block[b];
      for (int k = b * kBlock; k < std::min(n, (b + 1) * kBlock); ++k) {
        const int i = static_cast<int>(order[k]);
        tree.within(x[i], radius[i], hits);
        for (const auto& [j, d2] : hits)
          if (static_cast<int>(j) != i) out.push_back(static_cast<std::int32_t>(j)), ++own[i];
      }
    }
#pragma omp for schedule(dynamic, 1)
    for (int b = 0; b < n_blocks; ++b) {
      const std::int32_t* h = hits_of_block[b].data();
      for (int k = b * kBlock; k < std::min(n, (b + 1) * kBlock); ++k) {
        const int i = static_cast<int>(order[k]);
        for (const std::int32_t* end = h + own[i]; h != end; ++h)
          if (larger_only(i, *h))
            std::atomic_ref<std::int32_t>(added[*h]).fetch_add(1, std::memory_order_relaxed);
      }
    }
  }
  NeighbourLists lists;
  lists.begin.assign(n + 1, 0);
  for (int i = 0; i < n; ++i) lists.begin[i + 1] = lists.begin[i] + own[i] + added[i];
  lists.index.resize(lists.begin[n]);
  std::vector<std::int32_t> placed(n, 0);
#pragma omp parallel
  {
#pragma omp for schedule(dynamic, 1)
    for (int b = 0; b < n_blocks; ++b) {
      const std::int32_t* h = hits_of_block[b].data();
      for (int k = b * kBlock; k < std::min(n, (b + 1) * kBlock); ++k) {
        const int i = static_cast<int>(order[k]);
        std::copy(h, h + own[i], lists.index.begin() + lists.begin[i]);
        for (const std::int32_t* end = h + own[i]; h != end; ++h)
          if (larger_only(i, *h)) {
            const std::int32_t slot =
                std::atomic_ref<std::int32_t>(placed[*h]).fetch_add(1, std::memory_order_relaxed);
            lists.index[lists.begin[*h] + own[*h] + slot] = i;
          }
      }
    }
#pragma omp for schedule(static)
    for (int i = 0; i < n; ++i)
      std::sort(lists.index.begin() + lists.begin[i], lists.index.begin() + lists.begin[i + 1]);
  }
  return lists;
}

const char* to_string(NeighbourSearch search) {
  return search == NeighbourSearch::automatic   ? "automatic"
         : search == NeighbourSearch::cell_list ? "cell-list"
                                                : "kd-tree";
}

template <int Dim>
void CellGrid<Dim>::build(std::span<const Vec<Dim>> points, double width) {
  LIQUID_VERIFY(width > 0.0 && std::isfinite(width), "CellGrid: the cells' width must be positive, not {}",
                width);
  const int n = static_cast<int>(points.size());
  width_ = width;
  Vec<Dim> hi = Vec<Dim>::Zero();
  lo_ = hi;
  if (n > 0) lo_ = hi = points[0];
  for (int i = 0; i < n; ++i) {
    LIQUID_VERIFY(points[i].allFinite(), "CellGrid: point {} has a position that is not finite", i);
    lo_ = lo_.cwiseMin(points[i]), hi = hi.cwiseMax(points[i]);
  }
  double cells = 1.0;
  for (int d = 0; d < Dim; ++d) cells *= std::floor((hi[d] - lo_[d]) / width) + 1.0;
  LIQUID_VERIFY(cells < 2147483647.0, "CellGrid: {:.3g} cells {} wide: the points spread too far", cells,
                width);
  for (int d = 0; d < Dim; ++d) dims_[d] = static_cast<std::int64_t>((hi[d] - lo_[d]) / width) + 1;
  // Counting sort of the points by cell (a point on the far edge rounds into the last cell).
  std::vector<std::int64_t> cell_of(n);
  cell_begin_.assign(static_cast<std::size_t>(dims_.prod()) + 1, 0);
  for (int i = 0; i < n; ++i) {
    Cell c = cell(points[i]);
    for (int d = 0; d < Dim; ++d) c[d] = std::clamp<std::int64_t>(c[d], 0, dims_[d] - 1);
    ++cell_begin_[static_cast<std::size_t>(cell_of[i] = flat(c)) + 1];
  }
  for (std::size_t c = 1; c < cell_begin_.size(); ++c) cell_begin_[c] += cell_begin_[c - 1];
  order_.resize(n);
  std::vector<std::int32_t> next(cell_begin_.begin(), cell_begin_.end() - 1);
  for (int i = 0; i < n; ++i) order_[next[cell_of[i]]++] = i;
}

template <int Dim>
NeighbourLists find_neighbours_cells(std::span<const Vec<Dim>> x, std::span<const double> radius) {
  const int n = static_cast<int>(x.size());
  LIQUID_VERIFY(static_cast<int>(radius.size()) == n, "find_neighbours_cells: {} particles, {} radii", n,
                radius.size());
  NeighbourLists lists;
  lists.begin.assign(n + 1, 0);
  if (n == 0) return lists;
  const double rmax = *std::max_element(radius.begin(), radius.end());
  LIQUID_VERIFY(rmax > 0.0, "find_neighbours_cells: every radius is zero");
  CellGrid<Dim> grid;
  grid.build(x, rmax);
  // Visits every j != i with |x_i - x_j| < max(r_i, r_j).
  auto visit = [&](int i, auto&& f) {
    grid.candidates(x[i], [&](int j) {
      if (j == i) return;
      const double r = std::max(radius[i], radius[j]);
      if ((x[i] - x[j]).squaredNorm() < r * r) f(j);
    });
  };
#pragma omp parallel for schedule(dynamic, 256)
  for (int i = 0; i < n; ++i) {
    std::int64_t count = 0;
    visit(i, [&](int) { ++count; });
    lists.begin[i + 1] = count;
  }
  for (int i = 0; i < n; ++i) lists.begin[i + 1] += lists.begin[i];
  lists.index.resize(lists.begin[n]);
#pragma omp parallel for schedule(dynamic, 256)
  for (int i = 0; i < n; ++i) {
    std::int64_t at = lists.begin[i];
    visit(i, [&](int j) { lists.index[at++] = j; });
    std::sort(lists.index.begin() + lists.begin[i], lists.index.begin() + lists.begin[i + 1]);
  }
  return lists;
}

template NeighbourLists find_neighbours_cells<2>(std::span<const Vec<2>>, std::span<const double>);
template NeighbourLists find_neighbours_cells<3>(std::span<const Vec<3>>, std::span<const double>);
template class CellGrid<2>;
template class CellGrid<3>;
template class PointTree<2>;
template class PointTree<3>;
template NeighbourLists find_neighbours<2>(const PointTree<2>&, std::span<const Vec<2>>,
                                           std::span<const double>);
template NeighbourLists find_neighbours<3>(const PointTree<3>&, std::span<const Vec<3>>,
                                           std::span<const double>);

}  // namespace liquid::sph
