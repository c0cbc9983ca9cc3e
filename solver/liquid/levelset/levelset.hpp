#pragma once
// Level-set functions (negative inside) and the interface crossings that second-order Dirichlet
// boundaries need: where does the zero set cut the segment between two stencil nodes?

#include <functional>
#include <optional>

#include "liquid/core/types.hpp"

namespace liquid::levelset {

/// A level-set function: phi(x) < 0 inside, > 0 outside, zero set the interface.
template <int Dim>
using Function = std::function<double(const Vec<Dim>&)>;

/// Signed distance to a sphere (circle in 2D).
template <int Dim>
Function<Dim> sphere(const Vec<Dim>& centre, double radius);

/// Signed distance to an axis-aligned box (exact outside and inside).
template <int Dim>
Function<Dim> box(const Box<Dim>& b);

/// CSG on level sets: union = min, intersection = max, difference a \ b = max(a, -b).
template <int Dim>
Function<Dim> unite(Function<Dim> a, Function<Dim> b);
template <int Dim>
Function<Dim> intersect(Function<Dim> a, Function<Dim> b);
template <int Dim>
Function<Dim> subtract(Function<Dim> a, Function<Dim> b);

/// The gradient of phi at x by central differences of the given step along each axis.
template <int Dim>
Vec<Dim> gradient(const Function<Dim>& phi, const Vec<Dim>& x, double step);

/// Where the interface cuts the segment a -> b.
template <int Dim>
struct Crossing {
  double theta = 0.0;  ///< fraction of the way from a to b, in [0, 1]
  Vec<Dim> point;      ///< a + theta (b - a)
};

/// The crossing on [a, b] given phi(a) = phi_a and phi(b) = phi_b of opposite signs (a zero at an
/// end counts as a crossing there). Brent's method (GSL) to |b - a| * tolerance; nullopt when the
/// signs do not differ. Throws liquid::Error naming the segment if phi is not finite there.
template <int Dim>
std::optional<Crossing<Dim>> crossing(const Function<Dim>& phi, const Vec<Dim>& a, const Vec<Dim>& b,
                                      double phi_a, double phi_b, double tolerance = 1e-12);

}  // namespace liquid::levelset
