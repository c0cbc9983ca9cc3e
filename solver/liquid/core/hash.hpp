#pragma once
// A well-mixed 64-bit hash (splitmix64's finaliser), for everything that must be pseudo-random yet
// reproducible on any thread count: random trees, seeding jitter.

#include <cstdint>

namespace liquid {

inline std::uint64_t mix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

/// A uniform double in [0, 1) from a hash.
inline double unit_interval(std::uint64_t h) {
  return static_cast<double>(h >> 11) * 0x1.0p-53;
}

}  // namespace liquid
