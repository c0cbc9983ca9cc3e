#include "liquid/rbf/weight_cache.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

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

template <int Dim>
void canonical_order(std::span<const Vec<Dim>> nodes, const Vec<Dim>& at, double h, std::vector<int>& order) {
  using Key = std::array<std::int64_t, Dim + 1>;
  thread_local std::vector<Key> keys;
  keys.resize(nodes.size());
  for (std::size_t j = 0; j < nodes.size(); ++j) {
    Key& k = keys[j];
    k.fill(0);
    for (int d = 0; d < Dim; ++d) {
      k[d + 1] = std::llround((nodes[j][d] - at[d]) / h * 0x1p16);
      k[0] += k[d + 1] * k[d + 1];
    }
  }
  order.resize(nodes.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return keys[a] < keys[b]; });
}

template class WeightCache<2>;
template class WeightCache<3>;
template void canonical_order<2>(std::span<const Vec<2>>, const Vec<2>&, double, std::vector<int>&);
template void canonical_order<3>(std::span<const Vec<3>>, const Vec<3>&, double, std::vector<int>&);

}  // namespace liquid::rbf
