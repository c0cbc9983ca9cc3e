#include "liquid/rbf/weight_cache.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <numeric>

#include "liquid/core/error.hpp"

namespace liquid::rbf {

template <int Dim>
WeightCache<Dim>::WeightCache(double quantum) : quantum_(quantum), shards_(new Shard[n_shards]) {
  LIQUID_VERIFY(quantum > 0.0 && quantum < 1.0, "weight cache quantum must be in (0, 1), got {}", quantum);
}

template <int Dim>
std::size_t WeightCache<Dim>::KeyHash::operator()(const Key& k) const {
  std::uint64_t h = 0x9E3779B97F4A7C15ull;
  for (std::int64_t w : k.words) {
    h ^= static_cast<std::uint64_t>(w) + 0x9E3779B97F4A7C15ull + (h << 6) + (h >> 2);
    h *= 0xBF58476D1CE4E5B9ull;
  }
  return static_cast<std::size_t>(h ^ (h >> 31));
}

template <int Dim>
typename WeightCache<Dim>::Key WeightCache<Dim>::make_key(std::span<const Vec<Dim>> nodes, const Vec<Dim>& at,
                                                          double h, const Config& config) const {
  Key key;
  key.words.reserve(6 + Dim * nodes.size());
  key.words.push_back(config.exponent);
  key.words.push_back(config.degree);
  key.words.push_back(std::bit_cast<std::int64_t>(config.rank_tolerance));
  key.words.push_back(std::bit_cast<std::int64_t>(config.max_condition));
  key.words.push_back(std::bit_cast<std::int64_t>(config.coincidence_tolerance));
  key.words.push_back(static_cast<std::int64_t>(nodes.size()));
  for (const auto& x : nodes) {
    for (int k = 0; k < Dim; ++k) {
      const double steps = (x[k] - at[k]) / (h * quantum_);
      const double word = std::round(steps);
      // Off the quantum by more than round-off: the key's offsets would not be this stencil's.
      if (std::abs(steps - word) > 1e-3) return Key{};
      key.words.push_back(static_cast<std::int64_t>(word));
    }
  }
  return key;
}

template <int Dim>
Status WeightCache<Dim>::weights(std::span<const Vec<Dim>> nodes, const Vec<Dim>& at, double h,
                                 const Operator<Dim>& op, const Config& config, std::vector<double>& out) {
  out.clear();
  LIQUID_VERIFY(h > 0.0 && std::isfinite(h), "weight cache needs a positive cell size, got {}", h);
  for (const auto& x : nodes)
    if (!x.allFinite()) return rbf::weights<Dim>(nodes, at, op, config, out);  // reports non_finite

  const Key key = make_key(nodes, at, h, config);
  if (key.words.empty()) {
    bypassed_.fetch_add(1, std::memory_order_relaxed);
    return rbf::weights<Dim>(nodes, at, op, config, out);
  }
  Shard& shard = shards_[KeyHash{}(key) % n_shards];
  std::shared_ptr<const BasisWeights<Dim>> entry;
  {
    std::shared_lock lock(shard.mutex);
    auto it = shard.map.find(key);
    if (it != shard.map.end()) entry = it->second;
  }
  if (entry) {
    hits_.fetch_add(1, std::memory_order_relaxed);
  } else {
    misses_.fetch_add(1, std::memory_order_relaxed);
    // The offsets in units of h, read back from the key: a function of the key alone.
    std::vector<Vec<Dim>> unit(nodes.size());
    const std::size_t first = key.words.size() - Dim * nodes.size();
    for (std::size_t j = 0; j < nodes.size(); ++j)
      for (int k = 0; k < Dim; ++k)
        unit[j][k] = static_cast<double>(key.words[first + Dim * j + k]) * quantum_;
    auto computed =
        std::make_shared<const BasisWeights<Dim>>(basis_weights<Dim>(unit, Vec<Dim>::Zero(), config));
    std::unique_lock lock(shard.mutex);
    entry = shard.map.emplace(key, std::move(computed)).first->second;
  }

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
  std::size_t n = 0;
  for (int i = 0; i < n_shards; ++i) {
    std::shared_lock lock(shards_[i].mutex);
    n += shards_[i].map.size();
  }
  return n;
}

template <int Dim>
void WeightCache<Dim>::clear() {
  for (int i = 0; i < n_shards; ++i) {
    std::unique_lock lock(shards_[i].mutex);
    shards_[i].map.clear();
  }
  hits_ = 0;
  misses_ = 0;
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
