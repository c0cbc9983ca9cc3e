#include "studies/flow_measures.hpp"

namespace liquid::verification {

template <int Dim>
std::vector<double> particle_volumes(const CellGraph<Dim>& graph, std::span<const Vec<Dim>> x,
                                     double volume) {
  std::vector<CellId> cell(x.size());
  std::vector<int> count(graph.cell_capacity(), 0);
  CellId hint = no_cell;
  for (std::size_t i = 0; i < x.size(); ++i) {
    hint = hint == no_cell ? graph.locate(x[i]) : graph.locate(x[i], hint);
    cell[i] = hint;
    ++count[hint];
  }
  const int full = 1 << Dim;  // particles a full cell is seeded with
  std::vector<double> out(x.size());
  double sum = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    out[i] = graph.cell_size(cell[i]).prod() / std::max(count[cell[i]], full);
    sum += out[i];
  }
  if (sum > 0.0)
    for (double& v : out) v *= volume / sum;
  return out;
}

template std::vector<double> particle_volumes<2>(const CellGraph<2>&, std::span<const Vec<2>>, double);
template std::vector<double> particle_volumes<3>(const CellGraph<3>&, std::span<const Vec<3>>, double);

}  // namespace liquid::verification
