#pragma once
// Small fixed-size geometry shared by every module: points, vectors and axis-aligned boxes.

#include <Eigen/Core>

#include <array>
#include <cstdint>

namespace liquid {

/// A point or vector in Dim dimensions (Dim is 2 or 3).
template <int Dim>
using Vec = Eigen::Matrix<double, Dim, 1>;

/// Integer lattice coordinates (cell addresses at one tree level).
template <int Dim>
using IVec = Eigen::Matrix<std::int64_t, Dim, 1>;

/// An axis-aligned box [lo, hi].
template <int Dim>
struct Box {
  Vec<Dim> lo = Vec<Dim>::Zero();
  Vec<Dim> hi = Vec<Dim>::Ones();

  Vec<Dim> centre() const { return 0.5 * (lo + hi); }
  Vec<Dim> size() const { return hi - lo; }
  double volume() const { return size().prod(); }
  bool contains(const Vec<Dim>& x) const {
    return (x.array() >= lo.array()).all() && (x.array() <= hi.array()).all();
  }
  /// True when lo < hi along every axis.
  bool valid() const { return (lo.array() < hi.array()).all(); }
};

}  // namespace liquid
