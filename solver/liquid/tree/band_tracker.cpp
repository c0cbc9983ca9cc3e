#include "liquid/tree/band_tracker.hpp"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cmath>

#include "liquid/core/error.hpp"

namespace liquid::tree {

namespace {

/// Concatenates per-thread lists into `out` (cleared first).
void concat(std::vector<std::vector<CellId>>& parts, std::vector<CellId>& out) {
  out.clear();
  std::size_t n = 0;
  for (const auto& p : parts) n += p.size();
  out.reserve(n);
  for (auto& p : parts) {
    out.insert(out.end(), p.begin(), p.end());
    p.clear();
  }
}

}  // namespace

template <int Dim>
void mark_narrow_band(const CellGraph<Dim>& graph, const levelset::Function<Dim>& phi, int coarse_level,
                      int fine_level, double band, std::span<const CellId> cells, MarkList& marks) {
  LIQUID_VERIFY(coarse_level >= 0 && coarse_level <= fine_level && fine_level <= morton::max_level<Dim>,
                "tree::mark_narrow_band: levels must satisfy 0 <= {} <= {} <= {}", coarse_level, fine_level,
                morton::max_level<Dim>);
  const double h = std::ldexp(graph.domain().size().maxCoeff(), -fine_level);
  const long n = static_cast<long>(cells.size());
  const int n_threads = n > detail::parallel_min ? omp_get_max_threads() : 1;
  std::vector<std::vector<CellId>> split(n_threads), merge(n_threads);
#pragma omp parallel num_threads(n_threads)
  {
    const int t = omp_get_thread_num();
#pragma omp for schedule(static)
    for (long i = 0; i < n; ++i) {
      const CellId c = cells[i];
      if (!graph.alive(c)) continue;
      const Mark m = narrow_band_mark<Dim>(graph, c, phi, coarse_level, fine_level, band, h);
      if (m == Mark::split) split[t].push_back(c);
      if (m == Mark::merge) merge[t].push_back(c);
    }
  }
  concat(split, marks.split);
  concat(merge, marks.merge);
}

template void mark_narrow_band<2>(const CellGraph<2>&, const levelset::Function<2>&, int, int, double,
                                  std::span<const CellId>, MarkList&);
template void mark_narrow_band<3>(const CellGraph<3>&, const levelset::Function<3>&, int, int, double,
                                  std::span<const CellId>, MarkList&);

template <int Dim>
NarrowBandTracker<Dim>::NarrowBandTracker(const CellGraph<Dim>& graph, int coarse_level, int fine_level,
                                          double band, double max_motion)
    : coarse_(coarse_level), fine_(fine_level), band_(band) {
  LIQUID_VERIFY(coarse_level >= 0 && coarse_level <= fine_level && fine_level <= morton::max_level<Dim>,
                "NarrowBandTracker: levels must satisfy 0 <= {} <= {} <= {}", coarse_level, fine_level,
                morton::max_level<Dim>);
  LIQUID_VERIFY(band > 0.0 && max_motion >= 0.0,
                "NarrowBandTracker: band ({}) must be positive and max_motion ({}) non-negative", band,
                max_motion);
  // A coarse cell that must split lies within (band + motion) fine cells of the old zero set plus
  // half its diagonal less half its shortest side (its distance bound subtracts the half
  // diagonal; the far point is off a face). Every coarse block within that reach, n blocks along
  // the shortest side, is at most Dim * n face steps away. Cells are anisotropic on a box that
  // is not a cube, hence the sizes per axis.
  const Vec<Dim> coarse_size = graph.domain().size() * std::ldexp(1.0, -coarse_level);
  const double fine_size = std::ldexp(graph.domain().size().maxCoeff(), -fine_level);
  const double shortest = coarse_size.minCoeff();
  const double reach = (band + max_motion) * fine_size + 0.5 * (coarse_size.norm() - shortest);
  hops_ = Dim * std::max(1, static_cast<int>(std::ceil(reach / shortest)));
  graph.for_each_cell([&](CellId c) {
    if (graph.level(c) != coarse_) refined_.push_back(c);
  });
  is_refined_.assign(static_cast<std::size_t>(graph.cell_capacity()), 0);
  for (CellId c : refined_) is_refined_[c] = 1;
}

template <int Dim>
void NarrowBandTracker<Dim>::update(const CellGraph<Dim>& graph, const AdaptReport& report) {
  if (is_refined_.size() < static_cast<std::size_t>(graph.cell_capacity()))
    is_refined_.resize(static_cast<std::size_t>(graph.cell_capacity()), 0);
  for (CellId c : report.removed_cells) is_refined_[c] = 0;
  for (CellId c : report.new_cells) {
    if (graph.level(c) == coarse_) {
      // Born at the coarse level (a coarser cell was split): the zero set may cross it while no
      // refined cell is near, so the next round visits it once.
      born_coarse_.push_back(c);
    } else if (!is_refined_[c]) {
      is_refined_[c] = 1;
      refined_.push_back(c);
    }
  }
}

template <int Dim>
bool NarrowBandTracker<Dim>::claim(CellId c) {
  std::atomic_ref<std::uint32_t> s(stamp_[c]);
  std::uint32_t seen = s.load(std::memory_order_relaxed);
  while (seen != round_)
    if (s.compare_exchange_weak(seen, round_, std::memory_order_relaxed)) return true;
  return false;
}

template <int Dim>
void NarrowBandTracker<Dim>::gather(const CellGraph<Dim>& graph) {
  if (++round_ == 0) {
    std::fill(stamp_.begin(), stamp_.end(), 0u);
    round_ = 1;
  }
  if (stamp_.size() < static_cast<std::size_t>(graph.cell_capacity()))
    stamp_.resize(static_cast<std::size_t>(graph.cell_capacity()), 0u);
  // Drop the ids that died or were reused by a coarse cell, and the repeats (an id that died and
  // came back refined is listed twice).
  std::size_t kept = 0;
  for (CellId c : refined_)
    if (graph.alive(c) && is_refined_[c] && stamp_[c] != round_) {
      stamp_[c] = round_;
      refined_[kept++] = c;
    }
  refined_.resize(kept);
  candidates_ = refined_;
  for (CellId c : born_coarse_)
    if (graph.alive(c) && graph.level(c) == coarse_ && stamp_[c] != round_) {
      stamp_[c] = round_;
      candidates_.push_back(c);
    }
  born_coarse_.clear();

  // Breadth-first through coarse leaves, `hops_` face steps out of the refined set. Only refined
  // cells within the level jump of the coarse level can touch a coarse cell: with a bounded jump
  // the finest levels of the band, most of its cells, are skipped.
  const int n_threads = omp_get_max_threads();
  std::vector<std::vector<CellId>> parts(n_threads);
  const long jump = graph.max_jump();
  if (jump < unlimited_jump) {
    frontier_.clear();
    for (CellId c : refined_)
      if (graph.level(c) <= coarse_ + jump) frontier_.push_back(c);
  } else {
    frontier_ = refined_;
  }
  const std::vector<CellId>* from = &frontier_;
  for (int step = 0; step < hops_; ++step) {
    const long n = static_cast<long>(from->size());
#pragma omp parallel num_threads(n > detail::parallel_min ? n_threads : 1)
    {
      auto& mine = parts[omp_get_thread_num()];
#pragma omp for schedule(static)
      for (long i = 0; i < n; ++i) {
        const CellId c = (*from)[i];
        for (FaceId f : graph.faces(c)) {
          const GraphFace& face = graph.face(f);
          const CellId o = face.cell[0] == c ? face.cell[1] : face.cell[0];
          if (o != no_cell && graph.level(o) == coarse_ && claim(o)) mine.push_back(o);
        }
      }
    }
    tree::concat(parts, next_);
    candidates_.insert(candidates_.end(), next_.begin(), next_.end());
    frontier_.swap(next_);
    from = &frontier_;
    if (frontier_.empty()) break;
  }
}

template <int Dim>
void NarrowBandTracker<Dim>::mark(const CellGraph<Dim>& graph, const levelset::Function<Dim>& phi,
                                  MarkList& marks) {
  if (first_) {
    first_ = false;
    candidates_ = graph.cell_ids();
    born_coarse_.clear();
  } else {
    gather(graph);
  }
  tree::mark_narrow_band<Dim>(graph, phi, coarse_, fine_, band_, candidates_, marks);
}

template class NarrowBandTracker<2>;
template class NarrowBandTracker<3>;

}  // namespace liquid::tree
