#include "liquid/pic/classify.hpp"

#include <algorithm>

#include "liquid/core/error.hpp"
#include "liquid/core/parallel.hpp"

namespace liquid::pic {

template <int Dim>
void classify_cells(const tree::CellGraph<Dim>& graph, const particles::CellBins& bins,
                    std::span<const std::uint8_t> solid, Classification& out) {
  const int cap = graph.cell_capacity();
  LIQUID_VERIFY(solid.empty() || solid.size() >= static_cast<std::size_t>(cap),
                "classify_cells: solid mask has {} entries for {} cell ids", solid.size(), cap);
  out.type.assign(cap, CellType::air);
  out.fluid.clear(), out.surface.clear(), out.filled.clear();
  graph.for_each_cell([&](tree::CellId c) {
    if (!solid.empty() && solid[c])
      out.type[c] = CellType::solid;
    else if (bins.count(c) > 0)
      out.type[c] = CellType::fluid;
  });
  // Holes: empty cells surrounded by fluid (or walls, or solid).
  graph.for_each_cell([&](tree::CellId c) {
    if (out.type[c] != CellType::air) return;
    bool enclosed = true;
    for (tree::FaceId f : graph.faces(c)) {
      const tree::GraphFace& g = graph.face(f);
      const tree::CellId n = g.cell[0] == c ? g.cell[1] : g.cell[0];
      if (n != tree::no_cell && out.type[n] == CellType::air) {
        enclosed = false;
        break;
      }
    }
    if (enclosed) out.filled.push_back(c);
  });
  for (tree::CellId c : out.filled) out.type[c] = CellType::fluid;
  graph.for_each_cell([&](tree::CellId c) {
    if (out.type[c] != CellType::fluid) return;
    out.fluid.push_back(c);
    for (tree::FaceId f : graph.faces(c)) {
      const tree::GraphFace& g = graph.face(f);
      const tree::CellId n = g.cell[0] == c ? g.cell[1] : g.cell[0];
      if (n != tree::no_cell && out.type[n] == CellType::air) {
        out.surface.push_back(c);
        break;
      }
    }
  });
}

template <int Dim>
void mark_band(const tree::CellGraph<Dim>& graph, std::span<const tree::CellId> centres, int band,
               int coarse_level, int fine_level, tree::MarkList& marks) {
  LIQUID_VERIFY(band >= 0 && coarse_level >= 0 && coarse_level <= fine_level,
                "mark_band: band {} and levels {} <= {} are not valid", band, coarse_level, fine_level);
  marks.clear();
  // Breadth first from the surface, `band` hops deep.
  std::vector<std::uint8_t> near(graph.cell_capacity(), 0);
  std::vector<tree::CellId> frontier, next;
  for (tree::CellId c : centres)
    if (!near[c]) near[c] = 1, frontier.push_back(c);
  for (int hop = 0; hop < band && !frontier.empty(); ++hop) {
    next.clear();
    for (tree::CellId c : frontier)
      for (tree::FaceId f : graph.faces(c)) {
        const tree::GraphFace& g = graph.face(f);
        const tree::CellId n = g.cell[0] == c ? g.cell[1] : g.cell[0];
        if (n != tree::no_cell && !near[n]) {
          near[n] = 1;
          next.push_back(n);
        }
      }
    frontier.swap(next);
  }
  graph.for_each_cell([&](tree::CellId c) {
    const int target = near[c] ? fine_level : coarse_level;
    if (graph.level(c) < target)
      marks.split.push_back(c);
    else if (graph.level(c) > target)
      marks.merge.push_back(c);
  });
}

template void classify_cells<2>(const tree::CellGraph<2>&, const particles::CellBins&,
                                std::span<const std::uint8_t>, Classification&);
template void classify_cells<3>(const tree::CellGraph<3>&, const particles::CellBins&,
                                std::span<const std::uint8_t>, Classification&);
template void mark_band<2>(const tree::CellGraph<2>&, std::span<const tree::CellId>, int, int, int,
                           tree::MarkList&);
template void mark_band<3>(const tree::CellGraph<3>&, std::span<const tree::CellId>, int, int, int,
                           tree::MarkList&);

}  // namespace liquid::pic
