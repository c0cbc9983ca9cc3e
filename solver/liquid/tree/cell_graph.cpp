// CellGraph: construction, geometry, id bookkeeping and the read-only queries (point location,
// k-ring, siblings). Topology changes are in cell_graph_change.cpp, the bulk build in
// cell_graph_build.cpp and the invariant checker in cell_graph_check.cpp.
#include "liquid/tree/cell_graph.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "liquid/core/error.hpp"

namespace liquid::tree {

std::string InvariantReport::text(int max_lines) const {
  if (ok()) return "all invariants hold";
  std::string out = fmt::format("{} invariant failure(s):", n_failures);
  for (int i = 0; i < static_cast<int>(failures.size()) && i < max_lines; ++i) out += "\n  " + failures[i];
  return out;
}

template <int Dim>
CellGraph<Dim>::CellGraph(const Box<Dim>& domain, const CellGraphOptions<Dim>& options)
    : domain_(domain), options_(options) {
  init_levels();
  const CellId root = new_cell(0, IVec<Dim>::Zero());
  nodes_.reset(root);
  for (int d = 0; d < Dim; ++d) {
    add_face(no_cell, root, d, 2 * d, -1, 0);
    add_face(root, no_cell, d, 2 * d + 1, 0, -1);
  }
}

template <int Dim>
void CellGraph<Dim>::init_levels() {
  LIQUID_VERIFY(domain_.valid(), "CellGraph: the domain box must have lo < hi on every axis");
  LIQUID_VERIFY(options_.max_jump >= 1, "CellGraph: max_jump must be at least 1 (got {})", options_.max_jump);
  LIQUID_VERIFY(options_.min_level >= 0 && options_.min_level <= options_.max_level &&
                    options_.max_level <= morton::max_level<Dim>,
                "CellGraph: levels must satisfy 0 <= min_level <= max_level <= {} (got {} and {})",
                morton::max_level<Dim>, options_.min_level, options_.max_level);
  level_size_.resize(morton::max_level<Dim> + 1);
  for (int l = 0; l <= morton::max_level<Dim>; ++l)
    for (int d = 0; d < Dim; ++d) level_size_[l][d] = std::ldexp(domain_.hi[d] - domain_.lo[d], -l);
  n_at_level_.assign(morton::max_level<Dim> + 1, 0);
}

template <int Dim>
double CellGraph<Dim>::face_area(FaceId f) const {
  const GraphFace& g = faces_[f];
  const Vec<Dim>& s = level_size_[g.level()];
  double area = 1.0;
  for (int d = 0; d < Dim; ++d)
    if (d != g.axis) area *= s[d];
  return area;
}

template <int Dim>
void CellGraph<Dim>::face_geometry(std::vector<Vec<Dim>>& centres, std::vector<double>& areas) const {
  centres.resize(faces_.size());
  areas.resize(faces_.size());
  const int n = face_capacity();
#pragma omp parallel for schedule(static) if (n > detail::parallel_min)
  for (FaceId f = 0; f < n; ++f) {
    if (!face_alive_[f]) continue;
    centres[f] = face_centre(f);
    areas[f] = face_area(f);
  }
}

template <int Dim>
void CellGraph<Dim>::side_faces(CellId c, int axis, int dir, std::vector<SideFace>& out) const {
  out.clear();
  for_each_side_face(c, axis, dir, [&](const SideFace& s) { out.push_back(s); });
}

template <int Dim>
std::vector<CellId> CellGraph<Dim>::cell_ids() const {
  std::vector<CellId> ids;
  ids.reserve(n_cells_);
  for_each_cell([&](CellId c) { ids.push_back(c); });
  return ids;
}

template <int Dim>
std::vector<FaceId> CellGraph<Dim>::face_ids() const {
  std::vector<FaceId> ids;
  ids.reserve(n_faces_);
  for_each_face([&](FaceId f) { ids.push_back(f); });
  return ids;
}

// ---- id bookkeeping

template <int Dim>
CellId CellGraph<Dim>::new_cell(int level, const IVec<Dim>& address) {
  CellId c;
  if (!free_cells_.empty()) {
    c = free_cells_.back();
    free_cells_.pop_back();
  } else {
    c = static_cast<CellId>(cells_.size());
    LIQUID_VERIFY(cells_.size() < static_cast<std::size_t>(INT32_MAX), "CellGraph: more than 2^31 cells");
    cells_.emplace_back();
    cell_birth_.push_back(0);
    cell_log_index_.push_back(-1);
  }
  CellData& cell = cells_[c];
  cell.address = address;
  cell.level = static_cast<std::int8_t>(level);
  cell.key = morton::key<Dim>(level, address);
  cell.alive = true;
  cell.faces.clear();
  cell_birth_[c] = epoch_;
  if (in_change_) {
    cell_log_index_[c] = static_cast<std::int32_t>(born_cells_.size());
    born_cells_.push_back(c);
    cell_origin_.emplace_back();
    cell_origin_count_.push_back(0);
  }
  ++n_cells_;
  ++n_at_level_[level];
  deepest_ = std::max(deepest_, level);
  return c;
}

template <int Dim>
void CellGraph<Dim>::kill_cell(CellId c) {
  CellData& cell = cells_[c];
  LIQUID_ASSERT(cell.alive, "CellGraph: cell {} killed twice", c);
  cell.alive = false;
  cell.faces.clear();
  --n_cells_;
  --n_at_level_[cell.level];
  while (deepest_ > 0 && n_at_level_[deepest_] == 0) --deepest_;
  if (in_change_) {
    if (cell_birth_[c] < epoch_) removed_cells_.push_back(c);
    pending_free_cells_.push_back(c);
  } else {
    free_cells_.push_back(c);
  }
}

template <int Dim>
FaceId CellGraph<Dim>::add_face(CellId minus, CellId plus, int axis, int boundary, int level_minus,
                                int level_plus) {
  FaceId f;
  if (!free_faces_.empty()) {
    f = free_faces_.back();
    free_faces_.pop_back();
  } else {
    f = static_cast<FaceId>(faces_.size());
    LIQUID_VERIFY(faces_.size() < static_cast<std::size_t>(INT32_MAX), "CellGraph: more than 2^31 faces");
    faces_.emplace_back();
    face_alive_.push_back(0);
    face_birth_.push_back(0);
    face_log_index_.push_back(-1);
  }
  GraphFace& g = faces_[f];
  g = GraphFace{};
  g.axis = static_cast<std::int8_t>(axis);
  g.boundary = static_cast<std::int8_t>(boundary);
  g.side_level = {static_cast<std::int8_t>(level_minus), static_cast<std::int8_t>(level_plus)};
  face_alive_[f] = 1;
  face_birth_[f] = epoch_;
  if (minus != no_cell) attach(f, 0, minus, level_minus);
  if (plus != no_cell) attach(f, 1, plus, level_plus);
  if (in_change_) {
    face_log_index_[f] = static_cast<std::int32_t>(born_faces_.size());
    born_faces_.push_back(f);
    face_origin_.emplace_back();
  }
  ++n_faces_;
  return f;
}

template <int Dim>
void CellGraph<Dim>::attach(FaceId f, int side, CellId c, int level) {
  GraphFace& g = faces_[f];
  auto& list = cells_[c].faces;
  g.cell[side] = c;
  g.side_level[side] = static_cast<std::int8_t>(level);
  g.slot[side] = static_cast<std::int32_t>(list.size());
  list.push_back(f);
}

template <int Dim>
void CellGraph<Dim>::detach(FaceId f, int side) {
  GraphFace& g = faces_[f];
  const CellId c = g.cell[side];
  if (c == no_cell) return;
  auto& list = cells_[c].faces;
  const std::int32_t i = g.slot[side];
  LIQUID_ASSERT(i >= 0 && i < static_cast<std::int32_t>(list.size()) && list[i] == f,
                "CellGraph: face {} slot broken", f);
  const FaceId last = list.back();
  list[i] = last;
  GraphFace& h = faces_[last];
  h.slot[h.cell[0] == c ? 0 : 1] = i;
  list.pop_back();
  g.slot[side] = -1;
}

template <int Dim>
void CellGraph<Dim>::kill_face(FaceId f) {
  LIQUID_ASSERT(face_alive_[f], "CellGraph: face {} killed twice", f);
  face_alive_[f] = 0;
  --n_faces_;
  if (in_change_) {
    if (face_birth_[f] < epoch_) removed_faces_.push_back(f);
    pending_free_faces_.push_back(f);
  } else {
    free_faces_.push_back(f);
  }
}

// ---- queries

template <int Dim>
CellId CellGraph<Dim>::covering_leaf(int level, const IVec<Dim>& address) const {
  const std::uint64_t k = morton::key<Dim>(level, address);
  for (int up = 0; up <= level; ++up) {
    const std::int32_t v = nodes_.find(morton::ancestor_key<Dim>(k, up));
    if (v == detail::NodeIndex<Dim>::absent) continue;
    return v >= 0 ? v : no_cell;  // interior: the region is refined finer than `level`
  }
  return no_cell;
}

template <int Dim>
CellId CellGraph<Dim>::locate(const Vec<Dim>& x) const {
  const int L = deepest_;
  const double n = std::ldexp(1.0, L);
  const std::int64_t top = (std::int64_t{1} << L) - 1;
  IVec<Dim> q;
  for (int d = 0; d < Dim; ++d) {
    LIQUID_VERIFY(std::isfinite(x[d]), "CellGraph::locate: coordinate {} of the point is not finite ({})", d,
                  x[d]);
    const double t = (x[d] - domain_.lo[d]) / (domain_.hi[d] - domain_.lo[d]) * n;
    q[d] = t <= 0.0 ? 0 : (t >= static_cast<double>(top) ? top : static_cast<std::int64_t>(t));
  }
  return nodes_.descend(morton::encode<Dim>(q), L);
}

template <int Dim>
CellId CellGraph<Dim>::locate(const Vec<Dim>& x, CellId hint) const {
  if (alive(hint) && box(hint).contains(x)) return hint;
  return locate(x);
}

template <int Dim>
void CellGraph<Dim>::locate(std::span<const Vec<Dim>> x, std::span<CellId> out) const {
  LIQUID_VERIFY(x.size() == out.size(), "CellGraph::locate: {} points but {} outputs", x.size(), out.size());
  const long n = static_cast<long>(x.size());
#pragma omp parallel for schedule(static) if (n > detail::parallel_min)
  for (long i = 0; i < n; ++i) out[i] = locate(x[i]);
}

template <int Dim>
CellId CellGraph<Dim>::find(int level, const IVec<Dim>& address) const {
  if (level < 0 || level > morton::max_level<Dim>) return no_cell;
  for (int d = 0; d < Dim; ++d)
    if (address[d] < 0 || address[d] >= (std::int64_t{1} << level)) return no_cell;
  const std::int32_t v = nodes_.find(morton::key<Dim>(level, address));
  return v >= 0 ? v : no_cell;
}

template <int Dim>
void CellGraph<Dim>::k_ring(CellId c, int k, std::vector<CellId>& out) const {
  LIQUID_VERIFY(alive(c), "CellGraph::k_ring: cell {} is not alive", c);
  // Per-thread visit stamps: O(result) per query, no clearing, no allocation once warm.
  thread_local std::vector<std::uint32_t> stamp;
  thread_local std::uint32_t current = 0;
  if (stamp.size() < cells_.size()) stamp.resize(cells_.size(), 0);
  if (++current == 0) {
    std::fill(stamp.begin(), stamp.end(), 0);
    current = 1;
  }
  out.clear();
  out.push_back(c);
  stamp[c] = current;
  std::size_t begin = 0;
  for (int ring = 0; ring < k; ++ring) {
    const std::size_t end = out.size();
    for (std::size_t i = begin; i < end; ++i) {
      const CellId x = out[i];
      for (FaceId f : cells_[x].faces) {
        const GraphFace& g = faces_[f];
        const CellId o = g.cell[0] == x ? g.cell[1] : g.cell[0];
        if (o == no_cell || stamp[o] == current) continue;
        stamp[o] = current;
        out.push_back(o);
      }
    }
    if (out.size() == end) break;
    begin = end;
  }
}

template <int Dim>
bool CellGraph<Dim>::are_siblings(std::span<const CellId> cells) const {
  if (static_cast<int>(cells.size()) != n_children) return false;
  int seen = 0;
  for (CellId c : cells) {
    if (!alive(c) || cells_[c].level == 0) return false;
    if (!morton::siblings<Dim>(cells_[c].key, cells_[cells[0]].key)) return false;
    seen |= 1 << morton::child_index<Dim>(cells_[c].key);
  }
  return seen == (1 << n_children) - 1;
}

template <int Dim>
std::optional<std::array<CellId, CellGraph<Dim>::n_children>> CellGraph<Dim>::siblings(CellId c) const {
  if (!alive(c) || cells_[c].level == 0) return std::nullopt;
  const std::uint64_t parent = morton::parent_key<Dim>(cells_[c].key);
  std::array<CellId, n_children> out;
  for (int i = 0; i < n_children; ++i) {
    const std::int32_t v = nodes_.find(morton::child_key<Dim>(parent, i));
    if (v < 0) return std::nullopt;
    out[i] = v;
  }
  return out;
}

template <int Dim>
bool CellGraph<Dim>::can_merge(CellId c) const {
  const auto group = siblings(c);
  return group && merge_allowed(*group);
}

template <int Dim>
bool CellGraph<Dim>::merge_allowed(const std::array<CellId, n_children>& children) const {
  const int l = cells_[children[0]].level;
  if (l - 1 < options_.min_level) return false;
  const std::uint64_t parent = morton::parent_key<Dim>(cells_[children[0]].key);
  for (CellId c : children) {
    for (FaceId f : cells_[c].faces) {
      const GraphFace& g = faces_[f];
      const int s = g.cell[0] == c ? 0 : 1;
      const CellId o = g.cell[1 - s];
      if (o == no_cell || morton::parent_key<Dim>(cells_[o].key) == parent) continue;
      if (g.side_level[1 - s] - (l - 1) > options_.max_jump) return false;
    }
  }
  return true;
}

template class CellGraph<2>;
template class CellGraph<3>;

}  // namespace liquid::tree
