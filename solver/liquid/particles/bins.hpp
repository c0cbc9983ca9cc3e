#pragma once
// Particles binned by leaf cell: the cell of every particle, and the particles of every cell as one
// offset array (a counting sort by cell id). Within a cell, particles are in ascending index order,
// so a gather over a cell's particles sums in the same order on any number of threads.
//
// Rebinning starts from each particle's previous cell and costs O(particles + changed cells):
//   - a particle still inside its previous cell stays (one box test);
//   - a particle whose cell was split or merged by the last adapt is looked up among the cells
//     that replaced it (the adapt report's origins);
//   - only a particle that left its cell is located from the root (an O(depth) descent along its
//     Morton code; as fast as trying the face neighbours first, which in 3D means up to dozens of
//     box tests).
// BinStats counts each kind.

#include <cstdint>
#include <span>
#include <vector>

#include "liquid/tree/cell_graph.hpp"

namespace liquid::particles {

struct CellBins {
  std::vector<tree::CellId> cell;   ///< per particle: the leaf holding it
  std::vector<std::int32_t> begin;  ///< per cell id, plus one: [begin[c], begin[c+1]) in `index`
  std::vector<std::int32_t> index;  ///< particle indices grouped by cell, ascending within a cell

  /// The particles of cell c (empty for a dead or unknown id).
  std::span<const std::int32_t> of(tree::CellId c) const {
    if (c < 0 || c + 1 >= static_cast<tree::CellId>(begin.size())) return {};
    return {index.data() + begin[c], static_cast<std::size_t>(begin[c + 1] - begin[c])};
  }
  int count(tree::CellId c) const { return static_cast<int>(of(c).size()); }
  int n_particles() const { return static_cast<int>(cell.size()); }
  /// Rebuilds begin/index from `cell` (a counting sort), for a graph of `cell_capacity` ids.
  void sort(int cell_capacity);
};

/// How rebin() found each particle's cell.
struct BinStats {
  long stayed = 0;    ///< still in its previous cell
  long remapped = 0;  ///< its cell was split or merged; found among the replacing cells
  long located = 0;   ///< located from the root (new particles, and those that left their cell)
};

/// Bins every position from scratch (a root location per particle). Uses OpenMP.
template <int Dim>
void bin_particles(const tree::CellGraph<Dim>& graph, std::span<const Vec<Dim>> x, CellBins& bins);

/// Rebins after the particles moved and/or the graph changed. `bins.cell` holds the previous cells
/// and must have one entry per position (particles appended since carry no_cell and are located
/// from the root). `report` is the report of the change the graph went through since the last
/// binning, or nullptr when it did not change. Uses OpenMP; the result does not depend on the
/// thread count.
template <int Dim>
BinStats rebin(const tree::CellGraph<Dim>& graph, std::span<const Vec<Dim>> x, CellBins& bins,
               const tree::AdaptReport* report = nullptr);

}  // namespace liquid::particles
