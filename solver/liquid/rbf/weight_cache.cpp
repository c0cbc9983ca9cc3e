#include "liquid/rbf/weight_cache.hpp"

#include <algorithm>
#include <cmath>

#include "liquid/core/error.hpp"

namespace liquid::rbf {

template <int Dim>
WeightCache<Dim>::WeightCache(double quantum, std::size_t max_entries)
    : quantum_(quantum), map_(max_entries) {
  LIQUID_VERIFY(quantum > 0.0 && quantum < 1.0, "weight cache quantum must be in (0, 1), got {}", quantum);
}

template <int Dim>
Status WeightCache<Dim>::weights(std::span<const Vec<Dim>> nodes, const Vec<Dim>& at, double h,
                                 const Operator<Dim>& op, const Config& config, std::vector<double>& out) {
  out.clear();
  LIQUID_VERIFY(h > 0.0 && std::isfinite(h), "weight cache needs a positive cell size, got {}", h);
  for (const auto& x : nodes)
    if (!x.allFinite()) return rbf::weights<Dim>(nodes, at, op, config, out);  // reports non_finite

  const ShapeKey key = shape_key<Dim>(nodes, at, h, quantum_, config);
  if (key.empty()) {
    bypassed_.fetch_add(1, std::memory_order_relaxed);
    return rbf::weights<Dim>(nodes, at, op, config, out);
  }
  const std::shared_ptr<const BasisWeights<Dim>> entry = map_.template find_or_make<Dim>(
      key, static_cast<int>(nodes.size()), quantum_, [&](std::span<const Vec<Dim>> unit) {
        return std::make_shared<const BasisWeights<Dim>>(basis_weights<Dim>(unit, Vec<Dim>::Zero(), config));
      });

  Status status = entry->status;
  if (!status.usable()) return status;
  if (op.laplacian != 0.0 && !status.laplacian_defined) {
    status.info = Info::singular_system;
    return status;
  }
  // The entry holds weights for h = 1: scale the operator instead of the weights.
  Operator<Dim> scaled{op.value, op.gradient / h, op.laplacian / (h * h)};
  entry->combine(scaled, out);
  return status;
}

template <int Dim>
std::size_t WeightCache<Dim>::size() const {
  return map_.size();
}

template <int Dim>
void WeightCache<Dim>::clear() {
  map_.clear();
  bypassed_ = 0;
}

template class WeightCache<2>;
template class WeightCache<3>;

}  // namespace liquid::rbf
