#pragma once
// What a Poisson problem knows beyond its unknowns: a Dirichlet interface (the zero set of a level
// set, unknowns where it is negative), or unknowns given cell by cell with the other cells as
// Dirichlet nodes at their centres (the paper's air cells); Dirichlet or Neumann values on the
// domain's walls.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

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
  /// Unknowns given cell by cell (per cell id, nonzero: an unknown) instead of by the level set's
  /// sign. Without a level set every other cell is an air cell: a Dirichlet node at its own centre
  /// carrying `dirichlet` there (the paper's free surface, p = 0 in the air; first order in the
  /// position of the surface). With a level set, edges towards the other cells are cut at its zero
  /// set as usual.
  std::vector<std::uint8_t> unknown_cells;

  bool air_cells() const { return !unknown_cells.empty() && !levelset; }

  /// dp/dn at wall point x of the wall normal to `axis` on side `dir` (-1 low, +1 high).
  double flux(const Vec<Dim>& x, int axis, int dir) const {
    if (!wall_flux) return 0.0;
    Vec<Dim> n = Vec<Dim>::Zero();
    n[axis] = dir;
    return wall_flux(x, n);
  }
};

/// The ghost-fluid face (Gibou et al. 2002) from centre `a` (an unknown) towards centre `b` outside
/// the level set: the crossing on the segment a -> b at theta of the way (at least 1e-3; 1 where no
/// crossing is found), `distance` = theta times the centres' distance along `axis`, `value` the
/// Dirichlet value there. The outward gradient is (value - p_a) / distance: the projection's face
/// gradient and the flux rows' term, one formula for both.
struct GhostFace {
  double distance = 0.0, value = 0.0;
};
template <int Dim>
GhostFace ghost_face(const Boundary<Dim>& boundary, const Vec<Dim>& a, const Vec<Dim>& b, int axis) {
  const auto cut =
      levelset::crossing<Dim>(boundary.levelset, a, b, boundary.levelset(a), boundary.levelset(b));
  const double theta = cut ? std::max(cut->theta, 1e-3) : 1.0;
  return {theta * std::abs(b[axis] - a[axis]), boundary.dirichlet(cut ? cut->point : b)};
}

}  // namespace liquid::mac
