#pragma once
// Closest-source propagation over the particles' neighbour graph: the marches of the feature size
// (Sec. 4.1) and of the redistancing (Sec. 5.2). Seeds hold a value and are their own source; every
// other particle takes the least cost(j, s) over the sources s its neighbours hold, and passes its
// source on.
//
// Two orders, each ending at a fixed point (every particle holds the least cost over its neighbours'
// sources and its own): the paper's priority queue (serial, `march_serial`, the default), and rounds
// on all threads (`march_parallel`, see there), whose result does not depend on the thread count. A
// cost is not a sum along a path, so the fixed point is not unique and the two can settle on
// different sources, which changes which particles split and merge (docs/findings/sph.md).

#include <algorithm>
#include <cstdint>
#include <functional>
#include <limits>
#include <queue>
#include <utility>
#include <vector>

#include "liquid/core/parallel.hpp"
#include "liquid/sph/neighbours.hpp"

namespace liquid::sph {

/// How the marches run: the paper's priority queue on one thread, or rounds of relaxation on all.
enum class MarchOrder { serial, parallel };

struct MarchStats {
  long rounds = 0;   ///< relaxation rounds (parallel), or queue pops (serial)
  long updates = 0;  ///< times a particle took a better source
};

/// value[i] and source[i] hold the seeds (source[i] = i) and +inf / -1 elsewhere on entry, every
/// particle's least cost and its source on return. cost(j, s): what particle j would hold from source s.
template <class Cost>
MarchStats march_serial(const NeighbourLists& nbrs, std::vector<double>& value, std::vector<int>& source,
                        const Cost& cost) {
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  MarchStats stats;
  for (int i = 0; i < static_cast<int>(value.size()); ++i)
    if (source[i] >= 0) queue.push({value[i], i});
  while (!queue.empty()) {
    const auto [v, i] = queue.top();
    queue.pop();
    ++stats.rounds;
    if (v > value[i]) continue;
    const int s = source[i];
    for (int j : nbrs.of(i)) {
      const double c = cost(j, s);
      if (c < value[j]) {
        value[j] = c, source[j] = s;
        queue.push({c, j});
        ++stats.updates;
      }
    }
  }
  return stats;
}

/// As march_serial, in rounds on all threads. Each round takes the pending particles (their source
/// changed) whose value lies within `width` of the least pending value (the queue's order, a band at a
/// time, so that far fronts do not run ahead only to be overtaken), and offers every neighbour their
/// source; the offers are then applied, the least per particle (ties to the lower source index), so
/// the result does not depend on the thread count or the order of the offers.
template <class Cost>
MarchStats march_parallel(const NeighbourLists& nbrs, std::vector<double>& value, std::vector<int>& source,
                          const Cost& cost, double width) {
  const int n = static_cast<int>(value.size());
  std::vector<char> pending(n, 0);
  std::vector<int> waiting, front;
  for (int i = 0; i < n; ++i)
    if (source[i] >= 0) waiting.push_back(i), pending[i] = 1;
  struct Offer {
    int j, source;
    double value;
  };
  std::vector<Offer> offers;
  MarchStats stats;
  while (!waiting.empty()) {
    ++stats.rounds;
    double least = std::numeric_limits<double>::infinity();
    for (int i : waiting) least = std::min(least, value[i]);
    front.clear();
    std::size_t keep = 0;
    for (int i : waiting) {
      if (value[i] <= least + width)
        front.push_back(i), pending[i] = 0;
      else
        waiting[keep++] = i;
    }
    waiting.resize(keep);
    offers.clear();
    parallel_for(
        static_cast<long>(front.size()), [] { return std::vector<Offer>{}; },
        [&](std::vector<Offer>& mine, long k) {
          const int i = front[k], s = source[i];
          for (int j : nbrs.of(i)) {
            if (source[j] == s) continue;
            const double c = cost(j, s);
            if (c < value[j] || (c == value[j] && s < source[j])) mine.push_back({j, s, c});
          }
        },
        [&](std::vector<Offer>& mine) { offers.insert(offers.end(), mine.begin(), mine.end()); }, 64);
    for (const Offer& o : offers) {
      if (!(o.value < value[o.j] || (o.value == value[o.j] && o.source < source[o.j]))) continue;
      value[o.j] = o.value, source[o.j] = o.source;
      ++stats.updates;
      if (!pending[o.j]) pending[o.j] = 1, waiting.push_back(o.j);
    }
  }
  return stats;
}

/// `width`: the parallel order's band; callers pass half the smallest support radius (why:
/// docs/findings/sph.md).
template <class Cost>
MarchStats march(MarchOrder order, const NeighbourLists& nbrs, std::vector<double>& value,
                 std::vector<int>& source, const Cost& cost, double width) {
  return order == MarchOrder::serial ? march_serial(nbrs, value, source, cost)
                                     : march_parallel(nbrs, value, source, cost, width);
}

}  // namespace liquid::sph
