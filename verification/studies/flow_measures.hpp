#pragma once
// Measures of a particle flow shared by the flow cases (kinetic-energy, vorticity).

#include <span>
#include <vector>

#include "liquid/pic/adaptive_pic.hpp"
#include "liquid/tree/cell_graph.hpp"

namespace liquid::verification {

/// One method of a flow study: the adaptive tree or a uniform one, and the transfer.
struct FlowMethod {
  const char* name;
  bool adaptive;
  PicTransfer transfer;
};
/// The flow studies' methods, side by side: the paper's adaptive RBF, the same transfer on the
/// uniform tree, and the regular baselines PIC, FLIP and APIC.
inline const FlowMethod kFlowMethods[] = {{"adaptive-rbf", true, PicTransfer::rbf},
                                          {"regular-rbf", false, PicTransfer::rbf},
                                          {"regular-pic", false, PicTransfer::pic},
                                          {"regular-flip", false, PicTransfer::flip},
                                          {"regular-apic", false, PicTransfer::apic}};

/// The volume each particle at `x` stands for, all scaled to sum to `volume`: its cell's volume
/// over the cell's particles, or over 2^Dim (what a full cell is seeded with) when the cell holds
/// fewer (a surface cell, partly liquid). Seeding and reseeding count particles per cell whatever
/// its level, so on an adaptive tree a particle in a coarse cell stands for more liquid than one in
/// the band: equal shares would weigh the band 2^Dim times too much per level. On a uniform tree
/// with every cell at its seeded count the shares are equal.
template <int Dim>
std::vector<double> particle_volumes(const CellGraph<Dim>& graph, std::span<const Vec<Dim>> x, double volume);

}  // namespace liquid::verification
