#pragma once
// Tree builders for the verification cases and benchmarks. Every builder takes its levels as
// integers, so the next row of a convergence study is the same call with every level + 1 (band
// widths are given in cells of the finest level, so they halve with it).
//
// Distances: a level-set function phi is taken as (close to) a signed distance; a cell is "near"
// the zero set when |phi(centre)| minus the cell's half diagonal is below the band width. With a
// phi that is not a distance the bands are only approximate.

#include <cstdint>
#include <functional>
#include <vector>

#include "liquid/levelset/levelset.hpp"
#include "liquid/tree/cell_graph.hpp"

namespace liquid::tree {

/// Every cell at `level` (2^(Dim*level) leaves). options.max_jump is kept for later changes.
template <int Dim>
CellGraph<Dim> uniform(const Box<Dim>& domain, int level, const CellGraphOptions<Dim>& options = {});

/// Level `level` everywhere, level + 1 within 2 * band finest cells of phi's zero set and level + 2
/// within band finest cells (finest = level + 2; band > 0).
template <int Dim>
CellGraph<Dim> banded(const Box<Dim>& domain, const levelset::Function<Dim>& phi, int level,
                      double band = 3.0, const CellGraphOptions<Dim>& options = {});

/// Level `fine_level` within `band` cells of that level around phi's zero set, as coarse as the
/// level jump allows elsewhere but never coarser than `coarse_level` (coarse_level <= fine_level).
template <int Dim>
CellGraph<Dim> narrow_band(const Box<Dim>& domain, const levelset::Function<Dim>& phi, int coarse_level,
                           int fine_level, double band = 2.0, const CellGraphOptions<Dim>& options = {});

/// The refinement rule of narrow_band() for one node (true: split it).
template <int Dim>
bool narrow_band_refines(const TreeNode<Dim>& node, const levelset::Function<Dim>& phi, int coarse_level,
                         int fine_level, double band, double fine_size);

/// What the narrow-band rule asks of leaf c: split when it refines c, merge when it would not
/// refine c's parent, else keep (fine_size: the cell size at fine_level along the longest axis).
template <int Dim>
Mark narrow_band_mark(const CellGraph<Dim>& graph, CellId c, const levelset::Function<Dim>& phi,
                      int coarse_level, int fine_level, double band, double fine_size);

/// Marks an existing graph towards narrow_band(phi, coarse_level, fine_level, band): split where
/// the rule refines a leaf, merge where it would not refine the leaf's parent. Visits every cell;
/// `marks` (out) is resized to graph.cell_capacity() and reset first. Uses OpenMP. To re-adapt at
/// a cost proportional to the band instead, see NarrowBandTracker (band_tracker.hpp).
template <int Dim>
void mark_narrow_band(const CellGraph<Dim>& graph, const levelset::Function<Dim>& phi, int coarse_level,
                      int fine_level, double band, std::vector<Mark>& marks);

/// `base` with every leaf split `extra` times: the tree of the next rows of a convergence study in
/// which "every level shifts by one per row" (the paper's recursive subdivision). Level jumps are
/// those of `base`; the refined region stays the same region of space, so every T-junction of row
/// k sits where it sat in row 0 and local truncation errors scale with h. options.max_jump must be
/// at least base's largest jump (it is raised to it when lower).
template <int Dim>
CellGraph<Dim> refined(const CellGraph<Dim>& base, int extra, CellGraphOptions<Dim> options = {});

/// A seeded random, generally non-graded tree: every node between min_level and max_level is split
/// with probability `split_probability` (a hash of seed and node, so the tree does not depend on
/// the thread count), then the level jump options.max_jump is enforced.
template <int Dim>
CellGraph<Dim> random(const Box<Dim>& domain, std::uint64_t seed, int min_level, int max_level,
                      double split_probability, CellGraphOptions<Dim> options = {});

}  // namespace liquid::tree
