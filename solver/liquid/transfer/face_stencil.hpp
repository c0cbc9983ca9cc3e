#pragma once
// The face stencil of the face -> point transfers, shared by faces_to_points and FaceVelocityField:
// per axis k, the axis-k faces of the cells within `rings` face hops of a cell.

#include <algorithm>
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "liquid/rbf/interpolant_cache.hpp"
#include "liquid/tree/cell_adjacency.hpp"
#include "liquid/tree/cell_graph.hpp"

namespace liquid::transfer {

template <int Dim>
struct FaceStencil {
  std::array<std::vector<Vec<Dim>>, Dim> nodes;  ///< per axis: face centres
  std::array<std::vector<double>, Dim> values;   ///< per axis: the face values there
  std::vector<tree::CellId> ring;                // scratch
  std::vector<tree::FaceId> faces;               // scratch
};

/// Fills `out` for cell c: faces of the cells within `rings` hops of c, each once, in ascending id,
/// skipping faces with known[f] == 0 (known empty: all are known), with their values u[f].
template <int Dim>
void gather_face_stencil(const tree::CellGraph<Dim>& graph, tree::CellId c, int rings,
                         std::span<const double> u, std::span<const std::uint8_t> known,
                         FaceStencil<Dim>& out);

/// The cells of face f and their face neighbours (the 1-rings of its cells), each once, in ascending
/// id: the neighbourhood the extrapolation and the tents read.
template <int Dim>
void face_neighbourhood(const tree::CellGraph<Dim>& graph, tree::FaceId f, std::vector<tree::CellId>& out) {
  out.clear();
  for (tree::CellId c : graph.face(f).cell) {
    if (c == tree::no_cell) continue;
    out.push_back(c);
    for (tree::FaceId e : graph.faces(c)) {
      const tree::GraphFace& g = graph.face(e);
      const tree::CellId o = g.cell[0] == c ? g.cell[1] : g.cell[0];
      if (o != tree::no_cell) out.push_back(o);
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

/// The same cells, read from an adjacency bound to the graph (no face records loaded).
template <int Dim>
void face_neighbourhood(const tree::CellGraph<Dim>& graph, const tree::CellAdjacency<Dim>& adjacency,
                        tree::FaceId f, std::vector<tree::CellId>& out) {
  out.clear();
  for (tree::CellId c : graph.face(f).cell) {
    if (c == tree::no_cell) continue;
    out.push_back(c);
    for (const auto& side : adjacency.of(c))
      if (side.other != tree::no_cell) out.push_back(side.other);
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

/// The RBF interpolant of `nodes` (one axis of cell c's stencil) fitted to `values`: through
/// `cache` when given (shared factors, the values taken in its node order), else factorised for
/// these nodes alone. Left unfitted when its status is not usable.
template <int Dim>
rbf::Interpolant<Dim> fitted_interpolant(const tree::CellGraph<Dim>& graph, tree::CellId c,
                                         std::span<const Vec<Dim>> nodes, std::span<const double> values,
                                         const rbf::Config& config, rbf::InterpolantCache<Dim>* cache);

}  // namespace liquid::transfer
