#include "liquid/transfer/extrapolate.hpp"

#include <algorithm>
#include <array>

#include "liquid/core/error.hpp"
#include "liquid/core/parallel.hpp"
#include "liquid/transfer/face_stencil.hpp"
#include "liquid/transfer/regular.hpp"

namespace liquid::transfer {

// A layer's candidates, found by two parallel sweeps instead of walking the graph from each face: a
// face of axis a can be filled exactly when one of the cells within a face-hop of its cells holds a
// known face of axis a (the neighbourhood relation being symmetric). Each cell keeps two bit sets
// over the axes: `holds` (it has a known face of that axis) and `near` (it or a face neighbour
// does). A sweep over the cells updates `near`; a sweep over the faces lists the unknown faces whose
// cells' `near` has their axis, in face-id order (which keeps the means' reads close together).
// Each sweep reads a few bytes per cell or face, so it costs little beside the means; only the
// listing (a pass over the face flags) and the commit of the values run on one thread. A layer so
// costs O(cells + faces) rather than O(the faces it fills): cheaper at the default four layers, where
// the band the layers fill is a large share of the tree (docs/findings/table1-scale.md), dearer with
// many layers over a wide air region. The values are those of the plain Jacobi sweep; each mean's
// sum runs over the known faces in a fixed order, so the result does not depend on the thread count.

template <int Dim>
ExtrapolationReport extrapolate_faces(const tree::CellGraph<Dim>& graph, int layers, std::span<double> value,
                                      std::span<std::uint8_t> known, tree::CellAdjacency<Dim>* adjacency) {
  LIQUID_VERIFY(layers >= 0, "extrapolate_faces: {} layers", layers);
  LIQUID_VERIFY(static_cast<int>(value.size()) >= graph.face_capacity() && known.size() == value.size(),
                "extrapolate_faces: {} values and {} flags for {} face ids", value.size(), known.size(),
                graph.face_capacity());
  ExtrapolationReport report;
  tree::CellAdjacency<Dim> own;
  tree::CellAdjacency<Dim>& adj = adjacency != nullptr ? *adjacency : own;
  adj.bind(graph);
  const long n_cells = graph.cell_capacity();
  const long n_faces = graph.face_capacity();
  const auto bit = [&](tree::FaceId f) { return static_cast<std::uint8_t>(1u << graph.face(f).axis); };
  // holds[c]: the axes of c's known faces; near[c]: those of c's and its face neighbours'.
  std::vector<std::uint8_t> holds(n_cells, 0), near(n_cells, 0), flag(n_faces, 0);
  parallel_for(
      n_cells,
      [&](long c) {
        if (!graph.alive(static_cast<tree::CellId>(c))) return;
        std::uint8_t h = 0;
        for (int a = 0; a < Dim; ++a)
          for (const auto& side : adj.of(static_cast<tree::CellId>(c), a))
            if (known[side.face]) h |= static_cast<std::uint8_t>(1u << a);
        holds[c] = h;
      },
      2048);
  long unknown_count = 0;
  for (tree::FaceId f = 0; f < n_faces; ++f) unknown_count += graph.face_alive(f) && !known[f];
  std::vector<tree::FaceId> candidates;
  std::vector<double> next;
  std::vector<std::uint8_t> filled;
  struct Scratch {
    std::vector<tree::CellId> cells;
  };
  for (int layer = 0; layer < layers && unknown_count > 0; ++layer) {
    parallel_for(
        n_cells,
        [&](long cl) {
          const auto c = static_cast<tree::CellId>(cl);
          if (!graph.alive(c)) return;
          std::uint8_t m = holds[c];
          for (const auto& side : adj.of(c))
            if (side.other != tree::no_cell) m |= holds[side.other];
          near[c] = m;
        },
        2048);
    parallel_for(
        n_faces,
        [&](long fl) {
          const auto f = static_cast<tree::FaceId>(fl);
          flag[f] = 0;
          if (known[f] || !graph.face_alive(f)) return;
          const tree::GraphFace& g = graph.face(f);
          std::uint8_t m = 0;
          for (tree::CellId c : g.cell)
            if (c != tree::no_cell) m |= near[c];
          flag[f] = (m >> g.axis) & 1u;
        },
        4096);
    candidates.clear();
    for (tree::FaceId f = 0; f < n_faces; ++f)
      if (flag[f]) candidates.push_back(f);
    next.assign(candidates.size(), 0.0);
    filled.assign(candidates.size(), 0);
    parallel_for(
        static_cast<long>(candidates.size()), [] { return Scratch{}; },
        [&](Scratch& s, long i) {
          const tree::FaceId f = candidates[i];
          const int axis = graph.face(f).axis;
          const auto want = static_cast<std::uint8_t>(1u << axis);
          face_neighbourhood<Dim>(graph, adj, f, s.cells);
          // Each face once: a face is counted from the lower-id cell holding it among s.cells.
          double sum = 0.0;
          long n = 0;
          for (tree::CellId c : s.cells) {
            if (!(holds[c] & want)) continue;  // no known face of this axis
            for (const auto& side : adj.of(c, axis)) {
              if (!known[side.face]) continue;
              if (side.other != tree::no_cell && side.other < c &&
                  std::binary_search(s.cells.begin(), s.cells.end(), side.other))
                continue;
              sum += value[side.face];
              ++n;
            }
          }
          filled[i] = n > 0;
          next[i] = n > 0 ? sum / static_cast<double>(n) : 0.0;
        },
        [](Scratch&) {}, 512);
    long count = 0;
    for (std::size_t i = 0; i < candidates.size(); ++i) {
      // Every candidate has a known neighbour by construction; the test keeps the rule explicit.
      if (!filled[i]) continue;
      const tree::FaceId f = candidates[i];
      value[f] = next[i];
      known[f] = 1;
      for (tree::CellId c : graph.face(f).cell)
        if (c != tree::no_cell) holds[c] |= bit(f);
      ++count;
    }
    unknown_count -= count;
    report.filled.push_back(count);
    if (count == 0) break;
  }
  report.left_unknown = unknown_count;
  return report;
}

namespace {

/// The same-axis faces in the neighbourhood of a lattice face of axis `axis`, as offsets: the axis
/// faces of the two cells beside it and of their face neighbours. Along the axis: -2 .. 2; one step
/// across along another axis: -1 .. 1 along the axis. A wall drops exactly the offsets that leave
/// the lattice (the cells that would hold them are outside the domain).
template <int Dim>
struct LatticeNeighbourhood {
  static constexpr int size = 5 + 6 * (Dim - 1);
  std::array<IVec<Dim>, size> step;
  explicit LatticeNeighbourhood(int axis) {
    int i = 0;
    for (int m = -2; m <= 2; ++m) {
      IVec<Dim> d = IVec<Dim>::Zero();
      d[axis] = m;
      step[i++] = d;
    }
    for (int j = 0; j < Dim; ++j) {
      if (j == axis) continue;
      for (int side : {-1, 1})
        for (int m = -1; m <= 1; ++m) {
          IVec<Dim> d = IVec<Dim>::Zero();
          d[j] = side;
          d[axis] = m;
          step[i++] = d;
        }
    }
  }
};

/// Faces of one axis in lattice order: the flat indices of a face's neighbours inside the lattice.
template <int Dim>
struct AxisFaces {
  IVec<Dim> extent;
  std::array<long, Dim> stride{};
  LatticeNeighbourhood<Dim> nb;
  AxisFaces(const RegularLattice<Dim>& lattice, int axis) : nb(axis) {
    long s = 1;
    for (int j = 0; j < Dim; ++j) extent[j] = lattice.extent(axis, j), stride[j] = s, s *= extent[j];
  }
  /// Calls visit(flat) for each neighbour of the face at `flat` inside the lattice, in a fixed order.
  template <class Visit>
  void for_each_neighbour(long flat, Visit&& visit) const {
    IVec<Dim> a;
    long rest = flat;
    for (int j = 0; j < Dim; ++j) a[j] = rest % extent[j], rest /= extent[j];
    for (const IVec<Dim>& d : nb.step) {
      long g = flat;
      bool inside = true;
      for (int j = 0; j < Dim; ++j) {
        const long x = a[j] + d[j];
        inside = inside && x >= 0 && x < extent[j];
        g += d[j] * stride[j];
      }
      if (inside && visit(g)) return;
    }
  }
};

}  // namespace

template <int Dim>
ExtrapolationReport extrapolate_lattice(const RegularLattice<Dim>& lattice, int layers,
                                        std::span<double> value, std::span<std::uint8_t> known) {
  LIQUID_VERIFY(layers >= 0, "extrapolate_lattice: {} layers", layers);
  LIQUID_VERIFY(known.size() == value.size(), "extrapolate_lattice: {} values and {} flags", value.size(),
                known.size());
  ExtrapolationReport report;
  // The axes fill independently: each one's counts per layer, merged below into the report.
  std::array<std::vector<long>, Dim> per_axis;
  long unknown_count = 0;
  for (int k = 0; k < Dim; ++k) {
    const AxisFaces<Dim> axis(lattice, k);
    const long n = lattice.face_count(k);
    // This axis' flags and values in lattice order, so neighbours are strided reads.
    std::vector<std::uint8_t> kn(static_cast<std::size_t>(n));
    std::vector<double> val(static_cast<std::size_t>(n));
    for (long g = 0; g < n; ++g) {
      const tree::FaceId f = lattice.face_at(k, g);
      LIQUID_VERIFY(f >= 0 && static_cast<std::size_t>(f) < value.size(),
                    "extrapolate_lattice: face {} outside the {} values", f, value.size());
      kn[g] = known[f];
      val[g] = value[f];
    }
    // The first layer's candidates: every unknown face with a known one in its neighbourhood.
    std::vector<std::uint8_t> listed(static_cast<std::size_t>(n), 0);
    parallel_for(
        n,
        [&](long g) {
          if (kn[g]) return;
          axis.for_each_neighbour(g, [&](long h) { return kn[h] ? (listed[g] = 1, true) : false; });
        },
        4096);
    std::vector<long> candidates;
    long unknown = 0;
    for (long g = 0; g < n; ++g) {
      unknown += kn[g] == 0;
      if (listed[g]) candidates.push_back(g);
    }
    std::vector<double> next;
    std::vector<std::uint8_t> filled;
    for (int layer = 0; layer < layers && unknown > 0; ++layer) {
      if (layer > 0) {
        // The next candidates: unknown faces beside the faces just filled (the relation is
        // symmetric; a candidate with no known neighbour is simply not filled).
        std::vector<long> grown;
        for (std::size_t i = 0; i < candidates.size(); ++i) {
          if (!filled[i]) continue;
          axis.for_each_neighbour(candidates[i], [&](long h) {
            if (!listed[h] && !kn[h]) listed[h] = 1, grown.push_back(h);
            return false;
          });
        }
        candidates.swap(grown);
      }
      for (long g : candidates) listed[g] = 0;
      next.assign(candidates.size(), 0.0);
      filled.assign(candidates.size(), 0);
      parallel_for(
          static_cast<long>(candidates.size()),
          [&](long i) {
            double sum = 0.0;
            long count = 0;
            axis.for_each_neighbour(candidates[i], [&](long h) {
              if (kn[h]) sum += val[h], ++count;
              return false;
            });
            filled[i] = count > 0;
            next[i] = count > 0 ? sum / static_cast<double>(count) : 0.0;
          },
          512);
      long count = 0;
      for (std::size_t i = 0; i < candidates.size(); ++i) {
        if (!filled[i]) continue;
        kn[candidates[i]] = 1;
        val[candidates[i]] = next[i];
        const tree::FaceId f = lattice.face_at(k, candidates[i]);
        value[f] = next[i];
        known[f] = 1;
        ++count;
      }
      unknown -= count;
      if (count == 0) break;
      per_axis[k].push_back(count);
    }
    unknown_count += unknown;
  }
  // As the all-axes sweep reports: a count per layer while faces stay unknown, ending at the first
  // layer that fills nothing.
  long left = unknown_count;
  for (int k = 0; k < Dim; ++k)
    for (long c : per_axis[k]) left += c;
  for (int layer = 0; layer < layers && left > 0; ++layer) {
    long count = 0;
    for (int k = 0; k < Dim; ++k)
      if (layer < static_cast<int>(per_axis[k].size())) count += per_axis[k][layer];
    report.filled.push_back(count);
    left -= count;
    if (count == 0) break;
  }
  report.left_unknown = unknown_count;
  return report;
}

template ExtrapolationReport extrapolate_faces<2>(const tree::CellGraph<2>&, int, std::span<double>,
                                                  std::span<std::uint8_t>, tree::CellAdjacency<2>*);
template ExtrapolationReport extrapolate_faces<3>(const tree::CellGraph<3>&, int, std::span<double>,
                                                  std::span<std::uint8_t>, tree::CellAdjacency<3>*);
template ExtrapolationReport extrapolate_lattice<2>(const RegularLattice<2>&, int, std::span<double>,
                                                    std::span<std::uint8_t>);
template ExtrapolationReport extrapolate_lattice<3>(const RegularLattice<3>&, int, std::span<double>,
                                                    std::span<std::uint8_t>);

}  // namespace liquid::transfer
