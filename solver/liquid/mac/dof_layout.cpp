#include "liquid/mac/dof_layout.hpp"

#include <cmath>

#include <fmt/format.h>

#include "liquid/core/error.hpp"

namespace liquid::mac {

template <int Dim>
DofLayout<Dim> number_unknowns(const tree::CellGraph<Dim>& graph, const levelset::Function<Dim>& inside) {
  DofLayout<Dim> layout;
  layout.dof_of_cell.assign(graph.cell_capacity(), -1);
  graph.for_each_cell([&](tree::CellId c) {
    if (inside) {
      const Vec<Dim> x = graph.centre(c);
      const double phi = inside(x);
      LIQUID_VERIFY(std::isfinite(phi), "level set is {} at the centre ({:.6g}) of cell {}", phi,
                    fmt::join(x.data(), x.data() + Dim, ", "), c);
      if (!(phi < 0.0)) return;
    }
    layout.dof_of_cell[c] = static_cast<int>(layout.cell_of_dof.size());
    layout.cell_of_dof.push_back(c);
  });
  LIQUID_VERIFY(!layout.cell_of_dof.empty(),
                "the level set leaves no unknowns: no cell centre has phi < 0 ({} cells)", graph.n_cells());
  return layout;
}

template <int Dim>
DofLayout<Dim> number_unknowns(const tree::CellGraph<Dim>& graph, std::span<const std::uint8_t> mask) {
  LIQUID_VERIFY(static_cast<int>(mask.size()) >= graph.cell_capacity(),
                "number_unknowns: a mask of {} cells for a graph of {} cell ids", mask.size(),
                graph.cell_capacity());
  DofLayout<Dim> layout;
  layout.dof_of_cell.assign(graph.cell_capacity(), -1);
  graph.for_each_cell([&](tree::CellId c) {
    if (!mask[c]) return;
    layout.dof_of_cell[c] = static_cast<int>(layout.cell_of_dof.size());
    layout.cell_of_dof.push_back(c);
  });
  LIQUID_VERIFY(!layout.cell_of_dof.empty(), "the unknown-cell mask selects none of the {} cells",
                graph.n_cells());
  return layout;
}

template DofLayout<2> number_unknowns<2>(const tree::CellGraph<2>&, std::span<const std::uint8_t>);
template DofLayout<3> number_unknowns<3>(const tree::CellGraph<3>&, std::span<const std::uint8_t>);
template DofLayout<2> number_unknowns<2>(const tree::CellGraph<2>&, const levelset::Function<2>&);
template DofLayout<3> number_unknowns<3>(const tree::CellGraph<3>&, const levelset::Function<3>&);

}  // namespace liquid::mac
