#pragma once
// Neighbourhoods of multi-level particles (Adams et al. 2007, Sec. 3): p_j is a neighbour of p_i when
// |x_i - x_j| < max(r_i, r_j) (strict: the kernels vanish at the support's edge), a symmetric
// relation, found with a k-d tree (nanoflann) or a cell list. PointTree also answers the radius and
// nearest-point queries of the surface and the feature-size estimate.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include "liquid/core/types.hpp"

namespace liquid::sph {

/// A k-d tree over a fixed set of points (the points are copied).
template <int Dim>
class PointTree {
 public:
  PointTree();
  explicit PointTree(std::span<const Vec<Dim>> points);
  ~PointTree();
  PointTree(PointTree&&) noexcept;
  PointTree& operator=(PointTree&&) noexcept;

  /// Rebuilds the tree over `points`.
  void build(std::span<const Vec<Dim>> points);
  int size() const;
  /// Indices of the points with |p - x| < radius, with their squared distances, in no fixed order.
  void within(const Vec<Dim>& x, double radius, std::vector<std::pair<std::uint32_t, double>>& out) const;
  /// The index of the point nearest x and its distance; (-1, inf) for an empty tree.
  std::pair<int, double> nearest(const Vec<Dim>& x) const;
  /// Every point's index, in the order of the tree's leaves: points that follow each other are close
  /// in space, so queries made in this order find the tree's nodes and the points still in cache.
  std::span<const std::uint32_t> leaf_order() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Points binned into a uniform grid of cells `width` wide (a counting sort by cell, no tree): every
/// point within `width` of x lies in the 3^Dim cells around x's own, which `candidates` visits. The
/// points are referred to, not copied: they must outlive the grid and not move while it is used.
template <int Dim>
class CellGrid {
 public:
  using Cell = Eigen::Matrix<std::int64_t, Dim, 1>;

  /// Bins `points` (all finite; `width` > 0). Throws when the grid would need 2^31 cells or more.
  void build(std::span<const Vec<Dim>> points, double width);
  double width() const { return width_; }

  /// Calls f(j) for every point j in the 3^Dim cells around x (x anywhere; cells outside the grid
  /// are skipped), j itself included when x is a point's position: the caller filters by distance.
  template <class F>
  void candidates(const Vec<Dim>& x, F&& f) const {
    const Cell c = cell(x);
    Cell o = Cell::Constant(-1);
    while (true) {
      const Cell q = c + o;
      if ((q.array() >= 0).all() && (q.array() < dims_.array()).all()) {
        const std::int64_t at = flat(q);
        for (std::int32_t k = cell_begin_[at]; k < cell_begin_[at + 1]; ++k) f(order_[k]);
      }
      int d = 0;
      while (d < Dim && ++o[d] > 1) o[d] = -1, ++d;
      if (d == Dim) break;
    }
  }

 private:
  Cell cell(const Vec<Dim>& x) const {
    Cell c;
    for (int d = 0; d < Dim; ++d) {
      // Far outside (or not a number): a cell two away from the grid, whose neighbours are all outside.
      const double t = std::floor((x[d] - lo_[d]) / width_);
      if (!(t >= -1.0))
        c[d] = -2;
      else if (t > static_cast<double>(dims_[d]))
        c[d] = dims_[d] + 1;
      else
        c[d] = static_cast<std::int64_t>(t);
    }
    return c;
  }
  std::int64_t flat(const Cell& c) const {
    std::int64_t f = 0;
    for (int d = Dim - 1; d >= 0; --d) f = f * dims_[d] + c[d];
    return f;
  }

  Vec<Dim> lo_ = Vec<Dim>::Zero();
  double width_ = 1.0;
  Cell dims_ = Cell::Zero();
  std::vector<std::int32_t> cell_begin_{0}, order_;
};

/// Symmetric neighbour lists in compressed rows: the neighbours of i (never i itself) are
/// index[begin[i] .. end of row i), in ascending index order. Packed (`end` empty), row i ends where
/// row i+1 begins. With room to grow (as AdaptiveSph keeps them, so that a few rows can be rewritten
/// in place), row i ends at end[i], its storage at room[i], and rows need not lie in index order:
/// index may hold unused stretches.
struct NeighbourLists {
  std::vector<std::int64_t> begin{0};
  std::vector<std::int64_t> end;   ///< empty: packed rows
  std::vector<std::int64_t> room;  ///< where each row's storage ends (with `end` only)
  std::vector<std::int32_t> index;

  int n_particles() const { return static_cast<int>(begin.size()) - 1; }
  bool packed() const { return end.empty(); }
  std::int64_t end_of(int i) const { return end.empty() ? begin[i + 1] : end[i]; }
  std::span<const std::int32_t> of(int i) const {
    return {index.data() + begin[i], static_cast<std::size_t>(end_of(i) - begin[i])};
  }
  long n_pairs() const;
};

/// Finds every pair with |x_i - x_j| < max(r_i, r_j). `tree` must hold exactly the points x. OpenMP.
template <int Dim>
NeighbourLists find_neighbours(const PointTree<Dim>& tree, std::span<const Vec<Dim>> x,
                               std::span<const double> radius);

/// The same lists from a uniform cell list of cells as wide as the largest radius (each particle
/// scans the 3^Dim cells around its own): no tree to build, two passes (count, fill). OpenMP.
template <int Dim>
NeighbourLists find_neighbours_cells(std::span<const Vec<Dim>> x, std::span<const double> radius);

/// automatic: the k-d tree for adaptive particles in 3D, the cell list otherwise (in 3D, cells as
/// wide as the largest radius hold many candidates for the smallest particles). Multi-level cell
/// lists and per-radius grids were no faster. Why: docs/findings/sph.md.
enum class NeighbourSearch { automatic, cell_list, kd_tree };
const char* to_string(NeighbourSearch search);

}  // namespace liquid::sph
