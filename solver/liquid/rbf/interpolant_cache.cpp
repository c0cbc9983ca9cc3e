#include "liquid/rbf/interpolant_cache.hpp"

#include <cmath>

#include "liquid/core/error.hpp"

namespace liquid::rbf {

template <int Dim>
InterpolantCache<Dim>::InterpolantCache(double quantum, std::size_t max_entries)
    : quantum_(quantum), map_(max_entries) {
  LIQUID_VERIFY(quantum > 0.0 && quantum < 1.0, "interpolant cache quantum must be in (0, 1), got {}",
                quantum);
}

template <int Dim>
Interpolant<Dim> InterpolantCache<Dim>::interpolant(std::span<const Vec<Dim>> nodes, const Vec<Dim>& at,
                                                    double h, const Config& config, std::vector<int>& order) {
  LIQUID_VERIFY(h > 0.0 && std::isfinite(h), "interpolant cache needs a positive cell size, got {}", h);
  canonical_order<Dim>(nodes, at, h, order);
  thread_local std::vector<Vec<Dim>> sorted;
  sorted.resize(nodes.size());
  for (std::size_t j = 0; j < nodes.size(); ++j) sorted[j] = nodes[order[j]];
  const ShapeKey key = shape_key<Dim>(sorted, at, h, quantum_, config);
  if (key.empty()) {  // off the quantum, too far or not finite: factorised directly (which reports NaN)
    bypassed_.fetch_add(1, std::memory_order_relaxed);
    // In the entries' frame (offsets from `at` in units of h), so that cell_lebesgue() reads the cell.
    for (auto& x : sorted) x = (x - at) / h;
    return Interpolant<Dim>(Interpolant<Dim>::factorise(sorted, config), at, h);
  }
  auto entry = map_.template find_or_make<Dim>(
      key, static_cast<int>(nodes.size()), quantum_,
      [&](std::span<const Vec<Dim>> unit) { return Interpolant<Dim>::factorise(unit, config); });
  return Interpolant<Dim>(std::move(entry), at, h);
}

template class InterpolantCache<2>;
template class InterpolantCache<3>;

}  // namespace liquid::rbf
