#pragma once
// Morton (Z-order) address codes and tree keys.
//
// A cell of a quadtree/octree at level L has an integer address a (0 <= a_d < 2^L per axis) in the
// resolution pyramid of that level. Its Morton code interleaves the address bits, axis 0 in the
// lowest bit of each group of Dim bits. Its key is the code with a sentinel bit above it,
//   key = 2^(Dim*L) | morton(a),
// so keys of different levels never collide, the root's key is 1, the parent's key is key >> Dim,
// and child i (bit d of i = offset along axis d) has key (key << Dim) | i. Two cells are siblings
// when their keys share the parent key (the address-code test of the paper's Fig. 6).

#include <bit>
#include <cstdint>

#include "liquid/core/types.hpp"

namespace liquid::morton {

/// The deepest level whose keys fit in 64 bits (Dim * level + 1 <= 64, with margin).
template <int Dim>
inline constexpr int max_level = Dim == 2 ? 30 : 20;

namespace detail {
inline std::uint64_t spread2(std::uint64_t x) {
  x &= 0xffffffffULL;
  x = (x | (x << 16)) & 0x0000ffff0000ffffULL;
  x = (x | (x << 8)) & 0x00ff00ff00ff00ffULL;
  x = (x | (x << 4)) & 0x0f0f0f0f0f0f0f0fULL;
  x = (x | (x << 2)) & 0x3333333333333333ULL;
  x = (x | (x << 1)) & 0x5555555555555555ULL;
  return x;
}
inline std::uint64_t compact2(std::uint64_t x) {
  x &= 0x5555555555555555ULL;
  x = (x ^ (x >> 1)) & 0x3333333333333333ULL;
  x = (x ^ (x >> 2)) & 0x0f0f0f0f0f0f0f0fULL;
  x = (x ^ (x >> 4)) & 0x00ff00ff00ff00ffULL;
  x = (x ^ (x >> 8)) & 0x0000ffff0000ffffULL;
  x = (x ^ (x >> 16)) & 0x00000000ffffffffULL;
  return x;
}
inline std::uint64_t spread3(std::uint64_t x) {
  x &= 0x1fffffULL;
  x = (x | (x << 32)) & 0x001f00000000ffffULL;
  x = (x | (x << 16)) & 0x001f0000ff0000ffULL;
  x = (x | (x << 8)) & 0x100f00f00f00f00fULL;
  x = (x | (x << 4)) & 0x10c30c30c30c30c3ULL;
  x = (x | (x << 2)) & 0x1249249249249249ULL;
  return x;
}
inline std::uint64_t compact3(std::uint64_t x) {
  x &= 0x1249249249249249ULL;
  x = (x ^ (x >> 2)) & 0x10c30c30c30c30c3ULL;
  x = (x ^ (x >> 4)) & 0x100f00f00f00f00fULL;
  x = (x ^ (x >> 8)) & 0x001f0000ff0000ffULL;
  x = (x ^ (x >> 16)) & 0x001f00000000ffffULL;
  x = (x ^ (x >> 32)) & 0x00000000001fffffULL;
  return x;
}
}  // namespace detail

/// Morton code of a non-negative address (each component below 2^max_level<Dim>).
template <int Dim>
inline std::uint64_t encode(const IVec<Dim>& a) {
  static_assert(Dim == 2 || Dim == 3);
  if constexpr (Dim == 2) {
    return detail::spread2(static_cast<std::uint64_t>(a[0])) |
           (detail::spread2(static_cast<std::uint64_t>(a[1])) << 1);
  } else {
    return detail::spread3(static_cast<std::uint64_t>(a[0])) |
           (detail::spread3(static_cast<std::uint64_t>(a[1])) << 1) |
           (detail::spread3(static_cast<std::uint64_t>(a[2])) << 2);
  }
}

/// The address whose Morton code is `code` (the inverse of encode).
template <int Dim>
inline IVec<Dim> decode(std::uint64_t code) {
  IVec<Dim> a;
  for (int d = 0; d < Dim; ++d)
    a[d] = static_cast<std::int64_t>(Dim == 2 ? detail::compact2(code >> d) : detail::compact3(code >> d));
  return a;
}

/// Key of the cell at `level` with address `a`.
template <int Dim>
inline std::uint64_t key(int level, const IVec<Dim>& a) {
  return (std::uint64_t{1} << (Dim * level)) | encode<Dim>(a);
}

/// Level of a key (position of the sentinel bit divided by Dim).
template <int Dim>
inline int key_level(std::uint64_t key) {
  return (63 - std::countl_zero(key)) / Dim;
}

/// Address of a key (its Morton code without the sentinel bit).
template <int Dim>
inline IVec<Dim> key_address(std::uint64_t key) {
  const int level = key_level<Dim>(key);
  return decode<Dim>(key & ~(std::uint64_t{1} << (Dim * level)));
}

/// Parent, child and ancestor keys; `child` is in [0, 2^Dim), bit d = upper half along axis d.
template <int Dim>
inline std::uint64_t parent_key(std::uint64_t key) {
  return key >> Dim;
}
template <int Dim>
inline std::uint64_t child_key(std::uint64_t key, int child) {
  return (key << Dim) | static_cast<std::uint64_t>(child);
}
template <int Dim>
inline int child_index(std::uint64_t key) {
  return static_cast<int>(key & ((std::uint64_t{1} << Dim) - 1));
}
/// The ancestor of `key` `up` levels higher (up = 0 is the key itself).
template <int Dim>
inline std::uint64_t ancestor_key(std::uint64_t key, int up) {
  return key >> (Dim * up);
}

/// The sibling test by address code: same level and same parent in the resolution pyramid.
template <int Dim>
inline bool siblings(std::uint64_t a, std::uint64_t b) {
  return a != 1 && (a >> Dim) == (b >> Dim);
}

}  // namespace liquid::morton
