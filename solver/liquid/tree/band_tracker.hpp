#pragma once
// NarrowBandTracker: re-adapts a narrow-band tree (tree::narrow_band) as its level set moves, at a
// cost proportional to the band rather than to the whole tree.
//
// The tracker keeps the list of cells off the coarse level (level != coarse_level, nearly all of
// them finer), updated from each change report. Marking visits those cells, the cells born at the
// coarse level by the last change, and the coarse cells within `hops` face steps of them: a
// coarse cell that must split after the zero set moved by at most `max_motion` fine cells touches
// (through a face, an edge or a corner) a block of the coarse grid that the zero set crossed
// before, and that block was refined, so Dim face steps through coarse leaves reach a refined one
// (more when the band plus the motion exceeds a coarse cell). Cells far from the band are never
// visited. The first call visits every cell, so the tracker can start from any graph.
//
//   NarrowBandTracker<3> band(graph, coarse, fine, 1.0);
//   MarkList marks;
//   for (each step) {
//     band.mark(graph, phi, marks);
//     const AdaptReport r = graph.adapt(marks);
//     band.update(graph, r);
//     remap fields with r ...
//   }

#include <cstdint>
#include <span>
#include <vector>

#include "liquid/tree/builders.hpp"

namespace liquid::tree {

/// Sparse marks towards narrow_band(phi, coarse_level, fine_level, band) for the cells listed in
/// `cells` (dead ids skipped): split where the rule refines a leaf, merge where it would not refine
/// the leaf's parent. `marks` (out) is cleared first. Uses OpenMP.
template <int Dim>
void mark_narrow_band(const CellGraph<Dim>& graph, const levelset::Function<Dim>& phi, int coarse_level,
                      int fine_level, double band, std::span<const CellId> cells, MarkList& marks);

template <int Dim>
class NarrowBandTracker {
 public:
  /// `max_motion`: how far (in cells of fine_level) the zero set may move between two mark() calls.
  NarrowBandTracker(const CellGraph<Dim>& graph, int coarse_level, int fine_level, double band,
                    double max_motion = 1.0);

  /// Marks the graph towards the narrow band of `phi` (marks is cleared first). Visits candidates()
  /// only, except on the first call, which visits every cell.
  void mark(const CellGraph<Dim>& graph, const levelset::Function<Dim>& phi, MarkList& marks);
  /// Takes in what a change did (call it after every adapt, split or merge of the graph).
  void update(const CellGraph<Dim>& graph, const AdaptReport& report);

  /// The cells the last mark() call visited.
  std::span<const CellId> candidates() const { return candidates_; }
  /// Cells off the coarse level (level != coarse_level) known to the tracker.
  long n_refined() const { return static_cast<long>(refined_.size()); }
  int hops() const { return hops_; }

 private:
  void gather(const CellGraph<Dim>& graph);
  bool claim(CellId c);

  int coarse_ = 0, fine_ = 0;
  double band_ = 0.0;
  int hops_ = Dim;
  bool first_ = true;
  std::vector<CellId> refined_;  // may hold stale ids between update() and mark()
  std::vector<std::uint8_t> is_refined_;
  std::vector<std::uint32_t> stamp_;  // == round_ when the cell is a candidate of this round
  std::uint32_t round_ = 0;
  std::vector<CellId> born_coarse_;  // cells born at the coarse level since the last mark()
  std::vector<CellId> candidates_, frontier_, next_;
};

extern template class NarrowBandTracker<2>;
extern template class NarrowBandTracker<3>;

}  // namespace liquid::tree
