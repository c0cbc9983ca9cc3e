#pragma once
// Cell classification and the narrow band of the adaptive PIC step (paper Secs. 4 and 5.2), as
// functions over plain arrays indexed by cell id.
//
// A fluid cell holds particles. An empty cell whose face neighbours are all fluid (walls count as
// fluid) is fluid too: a hole that a step of advection opened inside the liquid or against a wall
// is refilled by reseeding, never turned into an air bubble. A surface cell is a fluid cell with a
// non-fluid cell among its face neighbours.

#include <cstdint>
#include <span>
#include <vector>

#include "liquid/particles/bins.hpp"
#include "liquid/tree/cell_graph.hpp"

namespace liquid::pic {

enum class CellType : std::uint8_t { air = 0, fluid = 1 };

struct Classification {
  std::vector<CellType> type;   ///< per cell id
  std::vector<CellId> fluid;    ///< fluid cells, ascending
  std::vector<CellId> surface;  ///< surface cells (fluid with a non-fluid face neighbour), ascending
  std::vector<CellId> filled;   ///< empty cells classified fluid (holes), ascending
  bool is_fluid(CellId c) const { return type[c] == CellType::fluid; }
  /// True when a face has a fluid cell on either side: the faces the projection sets.
  bool wet(const GraphFace& g) const {
    return (g.cell[0] != no_cell && is_fluid(g.cell[0])) || (g.cell[1] != no_cell && is_fluid(g.cell[1]));
  }
};

/// Classifies every cell from the particle bins.
template <int Dim>
void classify_cells(const CellGraph<Dim>& graph, const CellBins& bins, Classification& out);

/// Narrow-band marks: cells within `band` face hops of a surface cell go to fine_level, the others
/// to coarse_level (split when coarser than their target, merge when finer). `marks` is cleared first.
template <int Dim>
void mark_band(const CellGraph<Dim>& graph, const Classification& cls, int band, int coarse_level,
               int fine_level, MarkList& marks);

}  // namespace liquid::pic
