#pragma once
// Velocity extrapolation over faces, breadth first, on any tree (non-graded included).
//
// Layer by layer: an unknown face whose neighbourhood holds known faces of the same axis gets their
// mean, and becomes known for the next layer only (a Jacobi sweep, so the result does not depend on
// the visiting order or the thread count). The neighbourhood of a face is the same-axis faces of its
// cells and of their face neighbours, which reaches sideways across T-junctions as well as along
// the axis.

#include <cstdint>
#include <span>
#include <vector>

#include "liquid/tree/cell_adjacency.hpp"
#include "liquid/tree/cell_graph.hpp"

namespace liquid::transfer {

template <int Dim>
class RegularLattice;

struct ExtrapolationReport {
  std::vector<long> filled;  ///< faces filled per layer
  long left_unknown = 0;     ///< alive faces still unknown after the last layer (value left 0)
};

/// Fills unknown faces (known[f] == 0) of `value` up to `layers` layers deep; known is updated.
/// `adjacency`, when given, is bound to the graph and kept for later calls on the same topology (a
/// step extrapolates twice on one graph); the values are the same bits with or without it.
template <int Dim>
ExtrapolationReport extrapolate_faces(const tree::CellGraph<Dim>& graph, int layers, std::span<double> value,
                                      std::span<std::uint8_t> known,
                                      tree::CellAdjacency<Dim>* adjacency = nullptr);

/// The same extrapolation on a uniform tree, through its lattice: the same neighbourhoods, layers
/// and report, the values equal up to the order of each mean's sum. The regular baselines' step
/// uses it; its work per layer is the layer's faces, with no graph walks.
template <int Dim>
ExtrapolationReport extrapolate_lattice(const RegularLattice<Dim>& lattice, int layers,
                                        std::span<double> value, std::span<std::uint8_t> known);

}  // namespace liquid::transfer
