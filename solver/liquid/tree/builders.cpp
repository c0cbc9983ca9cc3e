#include "liquid/tree/builders.hpp"

#include <algorithm>
#include <cmath>

#include "liquid/core/error.hpp"
#include "liquid/core/hash.hpp"

namespace liquid::tree {

namespace {

template <int Dim>
double finest_size(const Box<Dim>& domain, int level) {
  return std::ldexp(domain.size().maxCoeff(), -level);
}

/// Lower bound of |phi| over the node, for a phi that is a distance.
template <int Dim>
double distance_bound(const TreeNode<Dim>& node, const levelset::Function<Dim>& phi) {
  return std::abs(phi(node.box.centre())) - 0.5 * node.box.size().norm();
}

template <int Dim>
void check_levels(int a, int b, const char* what) {
  LIQUID_VERIFY(a >= 0 && a <= b && b <= morton::max_level<Dim>,
                "tree::{}: levels must satisfy 0 <= {} <= {} <= {}", what, a, b, morton::max_level<Dim>);
}

}  // namespace

template <int Dim>
CellGraph<Dim> uniform(const Box<Dim>& domain, int level, const CellGraphOptions<Dim>& options) {
  check_levels<Dim>(level, level, "uniform");
  return CellGraph<Dim>::build(
      domain, [level](const TreeNode<Dim>& n) { return n.level < level; }, options);
}

template <int Dim>
CellGraph<Dim> banded(const Box<Dim>& domain, const levelset::Function<Dim>& phi, int level, double band,
                      const CellGraphOptions<Dim>& options) {
  check_levels<Dim>(level, level + 2, "banded");
  LIQUID_VERIFY(band > 0.0, "tree::banded: the band width must be positive (got {})", band);
  const double h = finest_size(domain, level + 2);
  return CellGraph<Dim>::build(
      domain,
      [&, level, h](const TreeNode<Dim>& n) {
        if (n.level < level) return true;
        if (n.level >= level + 2) return false;
        const double dist = distance_bound(n, phi);
        return n.level == level ? dist < 2.0 * band * h : dist < band * h;
      },
      options);
}

template <int Dim>
bool narrow_band_refines(const TreeNode<Dim>& node, const levelset::Function<Dim>& phi, int coarse_level,
                         int fine_level, double band, double fine_size) {
  if (node.level < coarse_level) return true;
  if (node.level >= fine_level) return false;
  return distance_bound(node, phi) < band * fine_size;
}

template <int Dim>
CellGraph<Dim> narrow_band(const Box<Dim>& domain, const levelset::Function<Dim>& phi, int coarse_level,
                           int fine_level, double band, const CellGraphOptions<Dim>& options) {
  check_levels<Dim>(coarse_level, fine_level, "narrow_band");
  LIQUID_VERIFY(band > 0.0, "tree::narrow_band: the band width must be positive (got {})", band);
  const double h = finest_size(domain, fine_level);
  return CellGraph<Dim>::build(
      domain,
      [&, coarse_level, fine_level, band, h](const TreeNode<Dim>& n) {
        return narrow_band_refines(n, phi, coarse_level, fine_level, band, h);
      },
      options);
}

template <int Dim>
Mark narrow_band_mark(const CellGraph<Dim>& graph, CellId c, const levelset::Function<Dim>& phi,
                      int coarse_level, int fine_level, double band, double fine_size) {
  const TreeNode<Dim> node{graph.level(c), graph.address(c), graph.box(c)};
  if (narrow_band_refines(node, phi, coarse_level, fine_level, band, fine_size)) return Mark::split;
  if (node.level == 0) return Mark::keep;
  TreeNode<Dim> parent;
  parent.level = node.level - 1;
  parent.address = node.address;
  for (int d = 0; d < Dim; ++d) {
    parent.address[d] >>= 1;
    const double s = 2.0 * graph.cell_size(c)[d];
    parent.box.lo[d] = graph.domain().lo[d] + static_cast<double>(parent.address[d]) * s;
    parent.box.hi[d] = parent.box.lo[d] + s;
  }
  return narrow_band_refines(parent, phi, coarse_level, fine_level, band, fine_size) ? Mark::keep
                                                                                     : Mark::merge;
}

template <int Dim>
void mark_narrow_band(const CellGraph<Dim>& graph, const levelset::Function<Dim>& phi, int coarse_level,
                      int fine_level, double band, std::vector<Mark>& marks) {
  check_levels<Dim>(coarse_level, fine_level, "mark_narrow_band");
  const double h = finest_size(graph.domain(), fine_level);
  marks.assign(static_cast<std::size_t>(graph.cell_capacity()), Mark::keep);
  const long n = graph.cell_capacity();
#pragma omp parallel for schedule(static) if (n > detail::parallel_min)
  for (long i = 0; i < n; ++i) {
    const auto c = static_cast<CellId>(i);
    if (graph.alive(c)) marks[c] = narrow_band_mark<Dim>(graph, c, phi, coarse_level, fine_level, band, h);
  }
}

template <int Dim>
CellGraph<Dim> refined(const CellGraph<Dim>& base, int extra, CellGraphOptions<Dim> options) {
  LIQUID_VERIFY(extra >= 0, "tree::refined: the number of extra levels must be non-negative (got {})", extra);
  const int finest = base.deepest_level();
  LIQUID_VERIFY(finest + extra <= morton::max_level<Dim>,
                "tree::refined: level {} + {} exceeds the maximum {}", finest, extra, morton::max_level<Dim>);
  options.max_jump = std::max(options.max_jump, base.options().max_jump);
  options.max_level = std::max(options.max_level, finest + extra);
  // A node larger than the base leaves it covers is split; a node inside a base leaf is split until
  // it is `extra` levels finer than that leaf. The node's centre finds the leaf (O(log n)).
  return CellGraph<Dim>::build(
      base.domain(),
      [&base, extra](const TreeNode<Dim>& n) {
        return n.level < base.level(base.locate(n.box.centre())) + extra;
      },
      options);
}

template <int Dim>
CellGraph<Dim> random(const Box<Dim>& domain, std::uint64_t seed, int min_level, int max_level,
                      double split_probability, CellGraphOptions<Dim> options) {
  check_levels<Dim>(min_level, max_level, "random");
  LIQUID_VERIFY(split_probability >= 0.0 && split_probability <= 1.0,
                "tree::random: the split probability must be in [0, 1] (got {})", split_probability);
  options.max_level = std::max(options.max_level, max_level);
  const std::uint64_t salt = mix64(seed);
  return CellGraph<Dim>::build(
      domain,
      [=](const TreeNode<Dim>& n) {
        if (n.level < min_level) return true;
        if (n.level >= max_level) return false;
        const std::uint64_t h = mix64(salt ^ mix64(morton::key<Dim>(n.level, n.address)));
        return unit_interval(h) < split_probability;
      },
      options);
}

#define LIQUID_TREE_BUILDERS(D)                                                                            \
  template CellGraph<D> uniform<D>(const Box<D>&, int, const CellGraphOptions<D>&);                        \
  template CellGraph<D> banded<D>(const Box<D>&, const levelset::Function<D>&, int, double,                \
                                  const CellGraphOptions<D>&);                                             \
  template bool narrow_band_refines<D>(const TreeNode<D>&, const levelset::Function<D>&, int, int, double, \
                                       double);                                                            \
  template Mark narrow_band_mark<D>(const CellGraph<D>&, CellId, const levelset::Function<D>&, int, int,   \
                                    double, double);                                                       \
  template CellGraph<D> narrow_band<D>(const Box<D>&, const levelset::Function<D>&, int, int, double,      \
                                       const CellGraphOptions<D>&);                                        \
  template void mark_narrow_band<D>(const CellGraph<D>&, const levelset::Function<D>&, int, int, double,   \
                                    std::vector<Mark>&);                                                   \
  template CellGraph<D> refined<D>(const CellGraph<D>&, int, CellGraphOptions<D>);                         \
  template CellGraph<D> random<D>(const Box<D>&, std::uint64_t, int, int, double, CellGraphOptions<D>);
LIQUID_TREE_BUILDERS(2)
LIQUID_TREE_BUILDERS(3)
#undef LIQUID_TREE_BUILDERS

}  // namespace liquid::tree
