#include "liquid/transfer/extrapolate.hpp"

#include <algorithm>

#include "liquid/core/error.hpp"
#include "liquid/core/parallel.hpp"

namespace liquid::transfer {

// Which faces can be filled in a layer, without visiting every unknown face: a face of axis a is
// filled exactly when one of the cells within a face-hop of its cells holds a known face of axis a
// (the neighbourhood relation is symmetric, face adjacency being so). Each cell keeps two bit sets
// over the axes: `holds` (it has a known face of that axis) and `near` (a cell within one hop
// does). A layer's candidates are the unknown faces of the cells whose `near` gained a bit in the
// previous update, for the axes gained; any other unknown face has no known neighbour, since a
// cell's bits only grow and every face under an older bit was filled when that bit arrived. So the
// work per layer is proportional to the band the layer fills, not to the air around the liquid.
// The values are those of the plain Jacobi sweep (the same sums in the same order).

template <int Dim>
ExtrapolationReport extrapolate_faces(const tree::CellGraph<Dim>& graph, int layers, std::span<double> value,
                                      std::span<std::uint8_t> known) {
  LIQUID_VERIFY(layers >= 0, "extrapolate_faces: {} layers", layers);
  LIQUID_VERIFY(static_cast<int>(value.size()) >= graph.face_capacity() && known.size() == value.size(),
                "extrapolate_faces: {} values and {} flags for {} face ids", value.size(), known.size(),
                graph.face_capacity());
  ExtrapolationReport report;
  const int n_cells = graph.cell_capacity();
  std::vector<std::uint8_t> holds(n_cells, 0), near(n_cells, 0), in_grown(n_cells, 0);
  // Flags instead of sorting: a face listed once as a candidate (the lists' order is free, each
  // candidate's value depending on the known faces alone).
  std::vector<std::uint8_t> listed(graph.face_capacity(), 0);
  // Cells whose `holds` gained bits since the last update.
  std::vector<tree::CellId> grown;
  std::vector<tree::FaceId> unknown;
  auto hold = [&](tree::FaceId f) {
    const tree::GraphFace& gf = graph.face(f);
    const auto bit = static_cast<std::uint8_t>(1u << gf.axis);
    for (tree::CellId c : gf.cell) {
      if (c == tree::no_cell || (holds[c] & bit)) continue;
      if (!in_grown[c]) in_grown[c] = 1, grown.push_back(c);
      holds[c] |= bit;
    }
  };
  graph.for_each_face([&](tree::FaceId f) {
    if (known[f])
      hold(f);
    else
      unknown.push_back(f);
  });
  long unknown_count = static_cast<long>(unknown.size());
  // Where the unknown faces are the fewer (an adaptive tree's narrow band of air), the first layer
  // asks each of them instead: a face is a candidate when a cell within a hop of its cells holds a
  // known face of its axis. The later layers spread from the faces the first one filled; `near`
  // then starts empty, which only adds candidates that can be filled anyway.
  const bool ask_first = 2 * unknown.size() < grown.size();
  std::vector<std::uint8_t> gained(n_cells, 0);
  std::vector<tree::CellId> ring, touched;
  std::vector<tree::FaceId> candidates;
  std::vector<double> next;
  std::vector<std::uint8_t> filled;
  struct Scratch {
    std::vector<tree::CellId> ring, cells;
  };
  // Spread the grown cells' bits one hop; the candidates are the unknown faces of the cells whose
  // `near` gained an axis, for the axes gained.
  auto spread = [&] {
    touched.clear();
    for (tree::CellId c : grown) {
      in_grown[c] = 0;
      graph.k_ring(c, 1, ring);
      for (tree::CellId x : ring) {
        const auto add = static_cast<std::uint8_t>(holds[c] & ~near[x]);
        if (!add) continue;
        if (!gained[x]) touched.push_back(x);
        gained[x] |= add;
        near[x] |= add;
      }
    }
    grown.clear();
    candidates.clear();
    for (tree::CellId x : touched) {
      for (tree::FaceId f : graph.faces(x))
        if (!known[f] && !listed[f] && (gained[x] >> graph.face(f).axis & 1u))
          listed[f] = 1, candidates.push_back(f);
      gained[x] = 0;
    }
    for (tree::FaceId f : candidates) listed[f] = 0;
  };
  // The first layer by asking the unknown faces (see ask_first).
  auto ask = [&] {
    std::vector<std::uint8_t> asked(unknown.size(), 0);
    parallel_for(
        static_cast<long>(unknown.size()), [] { return std::vector<tree::CellId>{}; },
        [&](std::vector<tree::CellId>& cells, long i) {
          const tree::GraphFace& gf = graph.face(unknown[i]);
          for (tree::CellId c : gf.cell) {
            if (c == tree::no_cell) continue;
            graph.k_ring(c, 1, cells);
            for (tree::CellId x : cells)
              if (holds[x] >> gf.axis & 1u) {
                asked[i] = 1;
                return;
              }
          }
        },
        [](std::vector<tree::CellId>&) {}, 256);
    for (tree::CellId c : grown) in_grown[c] = 0;
    grown.clear();
    candidates.clear();
    for (std::size_t i = 0; i < unknown.size(); ++i)
      if (asked[i]) candidates.push_back(unknown[i]);
  };
  for (int layer = 0; layer < layers && unknown_count > 0; ++layer) {
    if (layer == 0 && ask_first)
      ask();
    else
      spread();
    next.assign(candidates.size(), 0.0);
    filled.assign(candidates.size(), 0);
    parallel_for(
        static_cast<long>(candidates.size()), [] { return Scratch{}; },
        [&](Scratch& s, long i) {
          const tree::FaceId f = candidates[i];
          const int axis = graph.face(f).axis;
          s.cells.clear();
          for (tree::CellId c : graph.face(f).cell) {
            if (c == tree::no_cell) continue;
            graph.k_ring(c, 1, s.ring);
            s.cells.insert(s.cells.end(), s.ring.begin(), s.ring.end());
          }
          std::sort(s.cells.begin(), s.cells.end());
          s.cells.erase(std::unique(s.cells.begin(), s.cells.end()), s.cells.end());
          // Each face once: a face is counted from the lower-id cell holding it among s.cells.
          double sum = 0.0;
          long n = 0;
          for (tree::CellId c : s.cells)
            for (tree::FaceId g : graph.faces(c)) {
              const tree::GraphFace& gf = graph.face(g);
              if (gf.axis != axis || !known[g]) continue;
              const tree::CellId other = gf.cell[0] == c ? gf.cell[1] : gf.cell[0];
              if (other != tree::no_cell && other < c &&
                  std::binary_search(s.cells.begin(), s.cells.end(), other))
                continue;
              sum += value[g];
              ++n;
            }
          filled[i] = n > 0;
          next[i] = n > 0 ? sum / static_cast<double>(n) : 0.0;
        },
        [](Scratch&) {}, 128);
    long count = 0;
    for (std::size_t i = 0; i < candidates.size(); ++i) {
      // Every candidate has a known neighbour by construction; the test keeps the rule explicit.
      if (!filled[i]) continue;
      value[candidates[i]] = next[i];
      known[candidates[i]] = 1;
      hold(candidates[i]);
      ++count;
    }
    unknown_count -= count;
    report.filled.push_back(count);
    if (count == 0) break;
  }
  report.left_unknown = unknown_count;
  return report;
}

template ExtrapolationReport extrapolate_faces<2>(const tree::CellGraph<2>&, int, std::span<double>,
                                                  std::span<std::uint8_t>);
template ExtrapolationReport extrapolate_faces<3>(const tree::CellGraph<3>&, int, std::span<double>,
                                                  std::span<std::uint8_t>);

}  // namespace liquid::transfer
