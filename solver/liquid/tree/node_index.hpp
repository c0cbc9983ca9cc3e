#pragma once
// The tree behind a CellGraph: every node by key (see core/morton.hpp), leaves and interior ones.
// Children of an interior node are stored together in a block of 2^Dim entries; an entry is a leaf
// cell id (>= 0) or an interior node (-2 - its own children's block). A hash map takes an interior
// node's key to its block, so any node is found in O(1) (one probe for the parent, one block read);
// descending from the root by a point's Morton code needs no hashing at all.

#include <array>
#include <cstdint>
#include <vector>

#include "liquid/core/morton.hpp"
#include "liquid/tree/key_map.hpp"

namespace liquid::tree::detail {

/// Index of the j-th child (j in [0, 2^(Dim-1))) on side (axis, upper) of a node: bit `axis` is
/// `upper`, the other axes' bits are those of j in order.
template <int Dim>
inline int side_child(int axis, int upper, int j) {
  int idx = upper << axis;
  int bit = 0;
  for (int e = 0; e < Dim; ++e) {
    if (e == axis) continue;
    idx |= ((j >> bit) & 1) << e;
    ++bit;
  }
  return idx;
}

template <int Dim>
class NodeIndex {
 public:
  static constexpr int n_children = 1 << Dim;
  static constexpr std::int32_t absent = KeyMap::absent;  ///< find(): no such node
  static constexpr std::int32_t interior = -1;            ///< find(): an interior node
  using Block = std::array<std::int32_t, n_children>;

  /// The tree with one node, the root, as leaf `cell`.
  void reset(std::int32_t cell) {
    map_.clear();
    blocks_.clear();
    free_blocks_.clear();
    root_ = cell;
  }

  /// Leaf cell id, `interior`, or `absent`.
  std::int32_t find(std::uint64_t key) const {
    const std::int32_t e = entry(key);
    return e >= 0 || e == absent ? e : interior;
  }
  bool contains(std::uint64_t key) const { return entry(key) != absent; }

  /// Turns leaf `key` into an interior node whose children are the leaves `children`.
  void split(std::uint64_t key, const std::array<std::int32_t, n_children>& children) {
    std::int32_t b;
    if (!free_blocks_.empty()) {
      b = free_blocks_.back();
      free_blocks_.pop_back();
    } else {
      b = static_cast<std::int32_t>(blocks_.size());
      blocks_.emplace_back();
    }
    blocks_[b] = children;
    *entry_ptr(key) = -2 - b;
    map_.set(key, b);
  }

  /// Sets the entry of existing node `key` (its parent is interior) to leaf `cell`.
  void set_leaf(std::uint64_t key, std::int32_t cell) { *entry_ptr(key) = cell; }

  /// Turns interior `key`, whose children are all leaves, into leaf `cell`.
  void merge(std::uint64_t key, std::int32_t cell) {
    const std::int32_t b = map_.find(key);
    free_blocks_.push_back(b);
    map_.erase(key);
    *entry_ptr(key) = cell;
  }

  /// The leaf on the path given by `code`, the Morton code of a point's address at level `level`
  /// (which must be at least the depth of that leaf).
  std::int32_t descend(std::uint64_t code, int level) const {
    std::int32_t e = root_;
    for (int l = 0; e < 0; ++l) {
      const auto child = static_cast<int>((code >> (Dim * (level - l - 1))) & (n_children - 1));
      e = blocks_[-2 - e][child];
    }
    return e;
  }

  /// Number of leaf entries (for the invariant checker).
  long count_leaves() const {
    long n = root_ >= 0 ? 1 : 0;
    map_.for_each([&](std::uint64_t, std::int32_t b) {
      for (std::int32_t e : blocks_[b]) n += e >= 0 ? 1 : 0;
    });
    return n;
  }
  std::size_t n_interior() const { return map_.size(); }

  /// Bulk construction: root entry, blocks, and the (key, block) of every interior node.
  void assign(std::int32_t root, std::vector<Block> blocks, const std::vector<std::uint64_t>& interior_keys) {
    map_.clear();
    map_.reserve(interior_keys.size());
    for (std::size_t b = 0; b < interior_keys.size(); ++b)
      map_.set(interior_keys[b], static_cast<std::int32_t>(b));
    blocks_ = std::move(blocks);
    free_blocks_.clear();
    root_ = root;
  }
  std::int32_t root() const { return root_; }
  const Block& block(std::int32_t b) const { return blocks_[b]; }

 private:
  std::int32_t entry(std::uint64_t key) const {
    if (key == 1) return root_;
    const std::int32_t b = map_.find(key >> Dim);
    return b == absent ? absent : blocks_[b][key & (n_children - 1)];
  }
  std::int32_t* entry_ptr(std::uint64_t key) {
    if (key == 1) return &root_;
    return &blocks_[map_.find(key >> Dim)][key & (n_children - 1)];
  }

  KeyMap map_;  // interior key -> block of its children
  std::vector<Block> blocks_;
  std::vector<std::int32_t> free_blocks_;
  std::int32_t root_ = 0;
};

}  // namespace liquid::tree::detail
