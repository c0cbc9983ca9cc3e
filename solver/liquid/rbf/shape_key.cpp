#include "liquid/rbf/shape_key.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <numeric>

namespace liquid::rbf {

std::size_t ShapeKeyHash::of(std::span<const std::int64_t> words) {
  std::uint64_t h = 0x9E3779B97F4A7C15ull;
  for (std::int64_t w : words) {
    h ^= static_cast<std::uint64_t>(w) + 0x9E3779B97F4A7C15ull + (h << 6) + (h >> 2);
    h *= 0xBF58476D1CE4E5B9ull;
  }
  return static_cast<std::size_t>(h ^ (h >> 31));
}

namespace {
constexpr int n_header_words = 7;  // the kernel settings and the node count
}

template <int Dim>
ShapeKey shape_key(std::span<const Vec<Dim>> nodes, const Vec<Dim>& at, double h, double quantum,
                   const Config& config) {
  ShapeKey key;
  key.words.reserve(n_header_words + Dim * nodes.size());
  key.words.push_back(config.exponent);
  key.words.push_back(config.degree);
  key.words.push_back(std::bit_cast<std::int64_t>(config.rank_tolerance));
  key.words.push_back(std::bit_cast<std::int64_t>(config.max_condition));
  key.words.push_back(std::bit_cast<std::int64_t>(config.coincidence_tolerance));
  key.words.push_back(static_cast<std::int64_t>(config.condition_estimate));
  key.words.push_back(static_cast<std::int64_t>(nodes.size()));
  for (const auto& x : nodes) {
    for (int k = 0; k < Dim; ++k) {
      // Beyond 2^14 h the canonical order's squared offsets could overflow: no key.
      if (!(std::abs(x[k] - at[k]) <= 0x1p14 * h)) return ShapeKey{};
      const double steps = (x[k] - at[k]) / (h * quantum);
      const double word = std::round(steps);
      // Off the quantum by more than round-off: the key's offsets would not be this stencil's.
      if (!(std::abs(steps - word) <= 1e-3)) return ShapeKey{};
      key.words.push_back(static_cast<std::int64_t>(word));
    }
  }
  key.hash = ShapeKeyHash::of(key.words);
  return key;
}

template <int Dim>
void shape_offsets(const ShapeKey& key, int n_nodes, double quantum, std::vector<Vec<Dim>>& out) {
  out.resize(n_nodes);
  const std::size_t first = key.words.size() - static_cast<std::size_t>(Dim) * n_nodes;
  for (int j = 0; j < n_nodes; ++j)
    for (int k = 0; k < Dim; ++k)
      out[j][k] = static_cast<double>(key.words[first + static_cast<std::size_t>(Dim) * j + k]) * quantum;
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
      const double units = (nodes[j][d] - at[d]) / h;
      // Saturated, so that the squares below stay within 64 bits (Dim * 2^60).
      const double bounded = std::isfinite(units) ? std::clamp(units, -0x1p14, 0x1p14) : 0.0;
      k[d + 1] = std::llround(bounded * 0x1p16);
      k[0] += k[d + 1] * k[d + 1];
    }
  }
  order.resize(nodes.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return keys[a] < keys[b]; });
}

template void canonical_order<2>(std::span<const Vec<2>>, const Vec<2>&, double, std::vector<int>&);
template void canonical_order<3>(std::span<const Vec<3>>, const Vec<3>&, double, std::vector<int>&);
template ShapeKey shape_key<2>(std::span<const Vec<2>>, const Vec<2>&, double, double, const Config&);
template ShapeKey shape_key<3>(std::span<const Vec<3>>, const Vec<3>&, double, double, const Config&);
template void shape_offsets<2>(const ShapeKey&, int, double, std::vector<Vec<2>>&);
template void shape_offsets<3>(const ShapeKey&, int, double, std::vector<Vec<3>>&);

}  // namespace liquid::rbf
