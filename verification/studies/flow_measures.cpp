#include "studies/flow_measures.hpp"

namespace liquid::verification {

namespace {

/// Each particle's raw share: its cell's volume over max(particles in the cell, 2^Dim).
template <int Dim>
std::vector<double> raw_shares(const CellGraph<Dim>& graph, std::span<const Vec<Dim>> x) {
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
  for (std::size_t i = 0; i < x.size(); ++i)
    out[i] = graph.cell_size(cell[i]).prod() / std::max(count[cell[i]], full);
  return out;
}

}  // namespace

template <int Dim>
std::vector<double> particle_volumes(const CellGraph<Dim>& graph, std::span<const Vec<Dim>> x,
                                     double volume) {
  std::vector<double> out = raw_shares(graph, x);
  double sum = 0.0;
  for (double v : out) sum += v;
  if (sum > 0.0)
    for (double& v : out) v *= volume / sum;
  return out;
}

template <int Dim>
double particle_liquid_volume(const CellGraph<Dim>& graph, std::span<const Vec<Dim>> x) {
  double sum = 0.0;
  for (double v : raw_shares(graph, x)) sum += v;
  return sum;
}

template std::vector<double> particle_volumes<2>(const CellGraph<2>&, std::span<const Vec<2>>, double);
template std::vector<double> particle_volumes<3>(const CellGraph<3>&, std::span<const Vec<3>>, double);
template double particle_liquid_volume<2>(const CellGraph<2>&, std::span<const Vec<2>>);
template double particle_liquid_volume<3>(const CellGraph<3>&, std::span<const Vec<3>>);

}  // namespace liquid::verification
