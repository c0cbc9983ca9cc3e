#pragma once
// The face stencil of the face -> point transfers, shared by faces_to_points and FaceVelocityField:
// per axis k, the axis-k faces of the cells within `rings` face hops of a cell.

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "liquid/tree/cell_graph.hpp"

namespace liquid::transfer {

template <int Dim>
struct FaceStencil {
  std::array<std::vector<Vec<Dim>>, Dim> nodes;  ///< per axis: face centres
  std::array<std::vector<double>, Dim> values;   ///< per axis: the face values there
  std::vector<CellId> ring;                      // scratch
  std::vector<FaceId> faces;                     // scratch
};

/// Fills `out` for cell c: faces of the cells within `rings` hops of c, each once, in ascending id,
/// skipping faces with known[f] == 0 (known empty: all are known), with their values u[f].
template <int Dim>
void gather_face_stencil(const CellGraph<Dim>& graph, CellId c, int rings, std::span<const double> u,
                         std::span<const std::uint8_t> known, FaceStencil<Dim>& out);

}  // namespace liquid::transfer
