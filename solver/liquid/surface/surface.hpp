#pragma once
// Surface extraction from any level-set function (negative inside): marching squares in 2D (line
// segments), marching tetrahedra in 3D (triangles; every grid cube cut into the 6 tetrahedra around
// its main diagonal, the same cut in every cube, so neighbouring cubes agree on shared faces and the
// mesh is closed where the zero set is). The zero set is found on every grid edge (and, in 3D, on the
// cube and face diagonals the tetrahedra add) by linear interpolation of the node values; a vertex
// is shared by the elements that cut the same edge. Elements are oriented with their normal pointing
// out of the inside (2D: the outside is on the right of a segment a -> b). Ambiguous squares in 2D
// are resolved by the value at the square's centre.
//
// Marching tetrahedra rather than the marching cubes table of Lorensen and Cline: the same zero set
// on the same grid, about twice the triangles, no 256-case table to carry.

#include <array>
#include <functional>
#include <vector>

#include "liquid/core/types.hpp"

namespace liquid::surface {

template <int Dim>
using Function = std::function<double(const Vec<Dim>&)>;

template <int Dim>
struct Mesh {
  std::vector<Vec<Dim>> vertices;
  std::vector<std::array<int, Dim>> elements;  ///< segments (2D) or triangles (3D), vertex indices
  /// Total length (2D) or area (3D) of the elements.
  double measure() const;
};

/// The zero set of `phi` on a grid of cubes of side about `cell` covering `box` (node values are
/// evaluated in parallel with OpenMP; `phi` must be safe to call from several threads). Throws
/// liquid::Error when `phi` is not finite at a node (naming the node) or the grid would exceed
/// 2^31 nodes.
template <int Dim>
Mesh<Dim> extract(const Function<Dim>& phi, const Box<Dim>& box, double cell);

}  // namespace liquid::surface
