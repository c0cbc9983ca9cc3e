#pragma once
// Scattered test stencils around the origin, shared by the RBF-FD verification case, the unit
// tests and the benchmarks. All are deterministic for a given seed.

#include <random>
#include <vector>

#include "liquid/core/types.hpp"

namespace liquid::support {

/// The integer offsets of a (2 * half + 1)^Dim block around the origin, axis 0 fastest.
template <int Dim>
std::vector<IVec<Dim>> block_offsets(int half) {
  const int side = 2 * half + 1;
  int n_total = 1;
  for (int k = 0; k < Dim; ++k) n_total *= side;
  std::vector<IVec<Dim>> out(n_total);
  for (int i = 0; i < n_total; ++i) {
    int rest = i;
    for (int k = 0; k < Dim; ++k, rest /= side) out[i][k] = rest % side - half;
  }
  return out;
}

/// A (2 * half + 1)^Dim grid of spacing h around the origin, every node but the centre moved by a
/// uniform random offset of at most `jitter * h` per axis.
template <int Dim>
std::vector<Vec<Dim>> jittered_stencil(int half, double h, double jitter, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-jitter, jitter);
  std::vector<Vec<Dim>> nodes;
  for (const IVec<Dim>& q : block_offsets<Dim>(half)) {
    Vec<Dim> x = h * q.template cast<double>();
    if (!q.isZero())
      for (int k = 0; k < Dim; ++k) x[k] += u(rng) * h;
    nodes.push_back(x);
  }
  return nodes;
}

/// Cell centres of a small non-graded tree around a centre cell of size h at the origin: a
/// (2 * half + 1)^Dim block of cells of size h, each neighbour kept (probability 1/2), split once
/// (1/3) or split twice (1/6), so the stencil has T-junctions with jumps of up to two levels. The
/// centre cell comes first.
template <int Dim>
std::vector<Vec<Dim>> quadtree_stencil(int half, double h, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> pick(0, 5);
  std::vector<Vec<Dim>> nodes{Vec<Dim>::Zero()};
  for (const IVec<Dim>& q : block_offsets<Dim>(half)) {
    if (q.isZero()) continue;
    const Vec<Dim> c = h * q.template cast<double>();
    const int r = pick(rng);
    const int splits = r < 3 ? 0 : (r < 5 ? 1 : 2);
    const int per_axis = 1 << splits;
    const double child = h / per_axis;
    int n_children = 1;
    for (int k = 0; k < Dim; ++k) n_children *= per_axis;
    for (int j = 0; j < n_children; ++j) {
      Vec<Dim> x;
      int rj = j;
      for (int k = 0; k < Dim; ++k) {
        x[k] = c[k] - 0.5 * h + (rj % per_axis + 0.5) * child;
        rj /= per_axis;
      }
      nodes.push_back(x);
    }
  }
  return nodes;
}

}  // namespace liquid::support
