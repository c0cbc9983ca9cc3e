#pragma once
// Carrying fields across a change of a CellGraph. A field is a plain array indexed by cell id (or
// face id), sized for the graph before the change. The AdaptReport says, for every new cell and
// face, which old entries it comes from and with which weights:
//   cells: a child inherits its old ancestor's value; a parent takes the mean of its old children;
//   faces: a part of an old face inherits its value; a face made of old faces takes their
//          area-weighted mean; a face inside a split cell takes the mean of that cell's two sides
//          along its axis (each side area-weighted).
// Removed ids are never reused within one change, so the remap works in place: new entries are
// written, old ones are only read. Entries of removed ids keep stale values.

#include <cstddef>
#include <vector>

#include "liquid/core/error.hpp"
#include "liquid/tree/cell_graph.hpp"

namespace liquid::tree::remap {

namespace detail {
template <class T>
void apply(const std::vector<std::int32_t>& new_ids, const Origins& origins, std::size_t capacity,
           std::vector<T>& field, const char* what) {
  LIQUID_VERIFY(origins.size() == new_ids.size(), "remap: the report's {} origins do not match its new ids",
                what);
  const std::size_t old_size = field.size();
  for (std::int32_t s : origins.source)
    LIQUID_VERIFY(static_cast<std::size_t>(s) < old_size,
                  "remap: the {} field has {} entries but the change reads entry {}; size it for the graph "
                  "before the change",
                  what, old_size, s);
  if (field.size() < capacity) field.resize(capacity, field.empty() ? T{} : field.front());
  const long n = static_cast<long>(new_ids.size());
#pragma omp parallel for schedule(static) if (n > ::liquid::tree::detail::parallel_min)
  for (long i = 0; i < n; ++i) {
    const std::int32_t b = origins.begin[i], e = origins.begin[i + 1];
    T value = origins.weight[b] * field[origins.source[b]];
    for (std::int32_t k = b + 1; k < e; ++k) value += origins.weight[k] * field[origins.source[k]];
    field[new_ids[i]] = value;
  }
}
}  // namespace detail

/// Remaps a cell field (in/out, indexed by cell id) across the change described by `report`;
/// grows it to graph.cell_capacity(). T: double, or any type with T * double and +=.
template <int Dim, class T>
void cell_field(const CellGraph<Dim>& graph, const AdaptReport& report, std::vector<T>& field) {
  detail::apply(report.new_cells, report.cell_origins, static_cast<std::size_t>(graph.cell_capacity()), field,
                "cell");
}

/// Remaps a face field (in/out, indexed by face id) across the change described by `report`;
/// grows it to graph.face_capacity().
template <int Dim, class T>
void face_field(const CellGraph<Dim>& graph, const AdaptReport& report, std::vector<T>& field) {
  detail::apply(report.new_faces, report.face_origins, static_cast<std::size_t>(graph.face_capacity()), field,
                "face");
}

}  // namespace liquid::tree::remap
