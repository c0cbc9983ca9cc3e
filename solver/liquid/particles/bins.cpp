#include "liquid/particles/bins.hpp"

#include <algorithm>
#include <utility>

#include "liquid/core/error.hpp"
#include "liquid/core/parallel.hpp"

namespace liquid::particles {

namespace {

/// True when c holds x by the same rule as CellGraph::locate: half-open [lo, hi) on every axis,
/// closed at the domain's upper side, positions clamped onto the domain.
template <int Dim>
bool holds(const tree::CellGraph<Dim>& graph, tree::CellId c, const Vec<Dim>& x) {
  if (!graph.alive(c)) return false;
  const Box<Dim> b = graph.box(c);
  const Box<Dim>& d = graph.domain();
  for (int k = 0; k < Dim; ++k) {
    const double y = std::clamp(x[k], d.lo[k], d.hi[k]);
    if (y < b.lo[k]) return false;
    if (y >= b.hi[k] && !(b.hi[k] >= d.hi[k])) return false;
  }
  return true;
}

}  // namespace

void CellBins::sort(int cell_capacity) {
  begin.assign(static_cast<std::size_t>(cell_capacity) + 1, 0);
  for (tree::CellId c : cell) {
    LIQUID_ASSERT(c >= 0 && c < cell_capacity, "CellBins::sort: cell id {} out of range", c);
    ++begin[c + 1];
  }
  for (int c = 0; c < cell_capacity; ++c) begin[c + 1] += begin[c];
  index.resize(cell.size());
  std::vector<std::int32_t> next(begin.begin(), begin.end() - 1);
  for (std::size_t i = 0; i < cell.size(); ++i) index[next[cell[i]]++] = static_cast<std::int32_t>(i);
}

template <int Dim>
void bin_particles(const tree::CellGraph<Dim>& graph, std::span<const Vec<Dim>> x, CellBins& bins) {
  bins.cell.resize(x.size());
  graph.locate(x, bins.cell);
  bins.sort(graph.cell_capacity());
}

template <int Dim>
BinStats rebin(const tree::CellGraph<Dim>& graph, std::span<const Vec<Dim>> x, CellBins& bins,
               const tree::AdaptReport* report) {
  bins.cell.resize(x.size(), tree::no_cell);
  // (removed cell, cell that replaced part of it), sorted: O(changed cells log changed cells).
  std::vector<std::pair<tree::CellId, tree::CellId>> replaced;
  if (report) {
    const tree::Origins& o = report->cell_origins;
    for (std::size_t n = 0; n < report->new_cells.size(); ++n)
      for (int k = o.begin[n]; k < o.begin[n + 1]; ++k)
        replaced.emplace_back(o.source[k], report->new_cells[n]);
    std::sort(replaced.begin(), replaced.end());
  }
  struct Counts {
    BinStats s;
  };
  BinStats total;
  parallel_for(
      static_cast<long>(x.size()), [] { return Counts{}; },
      [&](Counts& t, long i) {
        const Vec<Dim>& xi = x[i];
        LIQUID_VERIFY(xi.allFinite(), "rebin: particle {} has a non-finite position", i);
        const tree::CellId old = bins.cell[i];
        if (old != tree::no_cell && holds(graph, old, xi)) {
          ++t.s.stayed;
          return;
        }
        if (old != tree::no_cell && !replaced.empty()) {
          auto it = std::lower_bound(replaced.begin(), replaced.end(),
                                     std::pair<tree::CellId, tree::CellId>{old, tree::no_cell});
          bool was_replaced = false;
          for (; it != replaced.end() && it->first == old; ++it) {
            was_replaced = true;
            if (holds(graph, it->second, xi)) {
              bins.cell[i] = it->second;
              ++t.s.remapped;
              return;
            }
          }
          if (was_replaced) {  // the particle also moved: search around what replaced its cell
            bins.cell[i] = graph.locate(xi);
            ++t.s.located;
            return;
          }
        }
        bins.cell[i] = graph.locate(xi);
        ++t.s.located;
      },
      [&](Counts& t) {
        total.stayed += t.s.stayed;
        total.remapped += t.s.remapped;
        total.located += t.s.located;
      },
      1024);
  bins.sort(graph.cell_capacity());
  return total;
}

#define LIQUID_BINS(D)                                                                           \
  template void bin_particles<D>(const tree::CellGraph<D>&, std::span<const Vec<D>>, CellBins&); \
  template BinStats rebin<D>(const tree::CellGraph<D>&, std::span<const Vec<D>>, CellBins&,      \
                             const tree::AdaptReport*);
LIQUID_BINS(2)
LIQUID_BINS(3)
#undef LIQUID_BINS

}  // namespace liquid::particles
