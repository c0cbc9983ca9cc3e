#pragma once
// Cell classification and the narrow band of the adaptive PIC step (paper Secs. 4 and 5.2), as
// functions over plain arrays indexed by cell id.
//
// A solid cell has its centre inside an obstacle (the caller's mask). A fluid cell is not solid and
// holds particles. An empty cell whose face neighbours are all fluid (walls and solid cells count
// as fluid) is fluid too: a hole that a step of advection opened inside the liquid or against a
// wall is refilled by reseeding, never turned into an air bubble. A surface cell is a fluid cell
// with an air cell among its face neighbours.

#include <cstdint>
#include <span>
#include <vector>

#include "liquid/particles/bins.hpp"
#include "liquid/tree/cell_graph.hpp"

namespace liquid::pic {

enum class CellType : std::uint8_t { air = 0, fluid = 1, solid = 2 };

struct Classification {
  std::vector<CellType> type;         ///< per cell id
  std::vector<tree::CellId> fluid;    ///< fluid cells, ascending
  std::vector<tree::CellId> surface;  ///< surface cells (fluid with a non-fluid face neighbour), ascending
  std::vector<tree::CellId> filled;   ///< empty cells classified fluid (holes), ascending
  bool is_fluid(tree::CellId c) const { return type[c] == CellType::fluid; }
  bool is_solid(tree::CellId c) const { return type[c] == CellType::solid; }
  /// True when a face has a fluid cell on one side and no solid cell on either: the faces the
  /// projection sets (faces of solid cells keep the solid's velocity).
  bool wet(const tree::GraphFace& g) const {
    const auto is = [&](int s, CellType t) { return g.cell[s] != tree::no_cell && type[g.cell[s]] == t; };
    return (is(0, CellType::fluid) || is(1, CellType::fluid)) && !is(0, CellType::solid) &&
           !is(1, CellType::solid);
  }
  /// True when a face touches a solid cell.
  bool solid_face(const tree::GraphFace& g) const {
    return (g.cell[0] != tree::no_cell && is_solid(g.cell[0])) ||
           (g.cell[1] != tree::no_cell && is_solid(g.cell[1]));
  }
};

/// The total volume of `cells` (e.g. Classification::fluid: the liquid's volume as the grid sees it).
template <int Dim>
double volume_of(const tree::CellGraph<Dim>& graph, std::span<const tree::CellId> cells) {
  double v = 0.0;
  for (tree::CellId c : cells) v += graph.volume(c);
  return v;
}

/// Classifies every cell from the particle bins; `solid` (per cell id, or empty for no solid) marks
/// the solid cells.
template <int Dim>
void classify_cells(const tree::CellGraph<Dim>& graph, const particles::CellBins& bins,
                    std::span<const std::uint8_t> solid, Classification& out);

/// Narrow-band marks: cells within `band` face hops of a cell of `centres` (the surface cells, and
/// any other cell the caller wants fine) go to fine_level, the others to coarse_level (split when
/// coarser than their target, merge when finer). `marks` is cleared first.
template <int Dim>
void mark_band(const tree::CellGraph<Dim>& graph, std::span<const tree::CellId> centres, int band,
               int coarse_level, int fine_level, tree::MarkList& marks);

}  // namespace liquid::pic
