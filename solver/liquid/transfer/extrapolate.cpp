#include "liquid/transfer/extrapolate.hpp"

#include <algorithm>

#include "liquid/core/error.hpp"
#include "liquid/core/parallel.hpp"

namespace liquid::transfer {

template <int Dim>
ExtrapolationReport extrapolate_faces(const tree::CellGraph<Dim>& graph, int layers, std::span<double> value,
                                      std::span<std::uint8_t> known) {
  LIQUID_VERIFY(layers >= 0, "extrapolate_faces: {} layers", layers);
  LIQUID_VERIFY(static_cast<int>(value.size()) >= graph.face_capacity() && known.size() == value.size(),
                "extrapolate_faces: {} values and {} flags for {} face ids", value.size(), known.size(),
                graph.face_capacity());
  ExtrapolationReport report;
  std::vector<tree::FaceId> unknown;
  graph.for_each_face([&](tree::FaceId f) {
    if (!known[f]) unknown.push_back(f);
  });
  std::vector<double> next(unknown.size());
  std::vector<std::uint8_t> filled(unknown.size());
  struct Scratch {
    std::vector<tree::CellId> ring, cells;
  };
  for (int layer = 0; layer < layers && !unknown.empty(); ++layer) {
    parallel_for(
        static_cast<long>(unknown.size()), [] { return Scratch{}; },
        [&](Scratch& s, long i) {
          const tree::FaceId f = unknown[i];
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
    std::size_t keep = 0;
    for (std::size_t i = 0; i < unknown.size(); ++i) {
      if (filled[i]) {
        value[unknown[i]] = next[i];
        known[unknown[i]] = 1;
        ++count;
      } else {
        unknown[keep] = unknown[i];
        ++keep;
      }
    }
    unknown.resize(keep);
    next.resize(keep);
    filled.resize(keep);
    report.filled.push_back(count);
    if (count == 0) break;
  }
  report.left_unknown = static_cast<long>(unknown.size());
  return report;
}

template ExtrapolationReport extrapolate_faces<2>(const tree::CellGraph<2>&, int, std::span<double>,
                                                  std::span<std::uint8_t>);
template ExtrapolationReport extrapolate_faces<3>(const tree::CellGraph<3>&, int, std::span<double>,
                                                  std::span<std::uint8_t>);

}  // namespace liquid::transfer
