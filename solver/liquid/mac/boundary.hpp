#pragma once
// What a Poisson problem knows beyond its unknowns: a Dirichlet interface (the zero set of a level
// set, unknowns where it is negative), Dirichlet or Neumann values on the domain's walls.

#include <functional>

#include "liquid/core/types.hpp"
#include "liquid/levelset/levelset.hpp"

namespace liquid::mac {

template <int Dim>
struct Boundary {
  levelset::Function<Dim> levelset;                  ///< empty: every cell is an unknown
  std::function<double(const Vec<Dim>&)> dirichlet;  ///< p on {levelset = 0}, and on Dirichlet walls
  bool dirichlet_walls = false;                      ///< walls carry `dirichlet` (else Neumann)
  /// Neumann walls: dp/dn along the outward unit normal n at wall point x (a moving wall's flux, or
  /// a manufactured solution's). Empty: dp/dn = 0, the paper's resting solid walls.
  std::function<double(const Vec<Dim>& x, const Vec<Dim>& n)> wall_flux;

  /// dp/dn at wall point x of the wall normal to `axis` on side `dir` (-1 low, +1 high).
  double flux(const Vec<Dim>& x, int axis, int dir) const {
    if (!wall_flux) return 0.0;
    Vec<Dim> n = Vec<Dim>::Zero();
    n[axis] = dir;
    return wall_flux(x, n);
  }
};

}  // namespace liquid::mac
