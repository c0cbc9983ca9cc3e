#include "liquid/tree/cell_adjacency.hpp"

#include <array>

#include "liquid/core/parallel.hpp"

namespace liquid::tree {

template <int Dim>
void CellAdjacency<Dim>::bind(const CellGraph<Dim>& graph) {
  if (topology_ == graph.topology()) return;
  topology_ = graph.topology();
  const long n_cells = graph.cell_capacity();
  start_.assign(static_cast<std::size_t>(n_cells) * Dim + 1, 0);
  parallel_for(
      n_cells,
      [&](long cl) {
        const auto c = static_cast<CellId>(cl);
        if (!graph.alive(c)) return;
        for (FaceId f : graph.faces(c)) ++start_[static_cast<std::size_t>(cl) * Dim + graph.face(f).axis + 1];
      },
      2048, detail::parallel_min);
  for (std::size_t k = 1; k < start_.size(); ++k) start_[k] += start_[k - 1];
  sides_.resize(static_cast<std::size_t>(start_.back()));
  parallel_for(
      n_cells,
      [&](long cl) {
        const auto c = static_cast<CellId>(cl);
        if (!graph.alive(c)) return;
        std::array<long, Dim> at;
        for (int a = 0; a < Dim; ++a) at[a] = start_[static_cast<std::size_t>(cl) * Dim + a];
        for (FaceId f : graph.faces(c)) {
          const GraphFace& g = graph.face(f);
          sides_[at[g.axis]++] = {f, g.cell[0] == c ? g.cell[1] : g.cell[0]};
        }
      },
      2048, detail::parallel_min);
}

template class CellAdjacency<2>;
template class CellAdjacency<3>;

}  // namespace liquid::tree
