// CellGraph <-> CellGraphState: the graph as plain arrays for checkpoints. The face lists of the
// cells are not stored: each face's slots give its position in its cells' lists, so the lists come
// back in their original order, and with them every loop over a cell's faces.
#include <fmt/format.h>

#include <algorithm>

#include "liquid/core/error.hpp"
#include "liquid/tree/cell_graph.hpp"

namespace liquid::tree {

template <int Dim>
CellGraphState<Dim> CellGraph<Dim>::state() const {
  LIQUID_VERIFY(!in_change_, "CellGraph::state(): called during a change");
  CellGraphState<Dim> s;
  s.domain = domain_;
  s.options = options_;
  const int nc = cell_capacity(), nf = face_capacity();
  s.level.resize(nc);
  s.address.resize(static_cast<std::size_t>(nc) * Dim);
  for (CellId c = 0; c < nc; ++c) {
    s.level[c] = cells_[c].alive ? cells_[c].level : -1;
    for (int d = 0; d < Dim; ++d) s.address[static_cast<std::size_t>(c) * Dim + d] = cells_[c].address[d];
  }
  constexpr int rec = CellGraphState<Dim>::face_record;
  s.faces.resize(static_cast<std::size_t>(nf) * rec);
  for (FaceId f = 0; f < nf; ++f) {
    const GraphFace& g = faces_[f];
    std::int32_t* r = &s.faces[static_cast<std::size_t>(f) * rec];
    r[0] = g.cell[0], r[1] = g.cell[1], r[2] = g.side_level[0], r[3] = g.side_level[1];
    r[4] = g.axis, r[5] = g.boundary, r[6] = g.slot[0], r[7] = g.slot[1];
  }
  s.face_alive = face_alive_;
  s.free_cells = free_cells_;
  s.free_faces = free_faces_;
  return s;
}

template <int Dim>
CellGraph<Dim> CellGraph<Dim>::from_state(const CellGraphState<Dim>& s) {
  constexpr int rec = CellGraphState<Dim>::face_record;
  const auto nc = static_cast<CellId>(s.level.size());
  const auto nf = static_cast<FaceId>(s.face_alive.size());
  LIQUID_VERIFY(s.address.size() == static_cast<std::size_t>(nc) * Dim,
                "graph state: {} addresses for {} cells (need {} per cell)", s.address.size(), nc, Dim);
  LIQUID_VERIFY(s.faces.size() == static_cast<std::size_t>(nf) * rec,
                "graph state: {} face entries for {} faces (need {} per face)", s.faces.size(), nf, rec);
  CellGraph g;
  g.domain_ = s.domain;
  g.options_ = s.options;
  g.init_levels();
  g.cells_.resize(nc);
  g.cell_birth_.assign(nc, 0);
  g.cell_log_index_.assign(nc, -1);
  for (CellId c = 0; c < nc; ++c) {
    CellData& cell = g.cells_[c];
    for (int d = 0; d < Dim; ++d)
      cell.address[d] = static_cast<int>(s.address[static_cast<std::size_t>(c) * Dim + d]);
    if (s.level[c] < 0) continue;
    LIQUID_VERIFY(s.level[c] <= morton::max_level<Dim>, "graph state: cell {} has level {}", c, s.level[c]);
    for (int d = 0; d < Dim; ++d)
      LIQUID_VERIFY(cell.address[d] >= 0 && cell.address[d] < (1 << s.level[c]),
                    "graph state: cell {} has address {} outside level {}", c, cell.address[d], s.level[c]);
    cell.level = static_cast<std::int8_t>(s.level[c]);
    cell.key = morton::key<Dim>(cell.level, cell.address);
    cell.alive = true;
    ++g.n_cells_;
    ++g.n_at_level_[cell.level];
    g.deepest_ = std::max(g.deepest_, static_cast<int>(cell.level));
  }
  LIQUID_VERIFY(g.n_cells_ > 0, "graph state: no alive cell");

  g.faces_.resize(nf);
  g.face_alive_ = s.face_alive;
  g.face_birth_.assign(nf, 0);
  g.face_log_index_.assign(nf, -1);
  std::vector<int> list_size(nc, 0);
  for (FaceId f = 0; f < nf; ++f) {
    const std::int32_t* r = &s.faces[static_cast<std::size_t>(f) * rec];
    GraphFace& face = g.faces_[f];
    face.cell = {r[0], r[1]};
    face.side_level = {static_cast<std::int8_t>(r[2]), static_cast<std::int8_t>(r[3])};
    face.axis = static_cast<std::int8_t>(r[4]);
    face.boundary = static_cast<std::int8_t>(r[5]);
    face.slot = {r[6], r[7]};
    if (!g.face_alive_[f]) continue;
    ++g.n_faces_;
    for (int side = 0; side < 2; ++side) {
      const CellId c = face.cell[side];
      if (c == no_cell) continue;
      LIQUID_VERIFY(c >= 0 && c < nc && g.cells_[c].alive && face.slot[side] >= 0,
                    "graph state: face {} names cell {} (slot {}), which is not an alive cell", f, c,
                    face.slot[side]);
      list_size[c] = std::max(list_size[c], face.slot[side] + 1);
    }
  }
  for (CellId c = 0; c < nc; ++c) {
    g.cells_[c].faces.reserve(list_size[c]);
    for (int k = 0; k < list_size[c]; ++k) g.cells_[c].faces.push_back(no_face);
  }
  for (FaceId f = 0; f < nf; ++f) {
    if (!g.face_alive_[f]) continue;
    const GraphFace& face = g.faces_[f];
    for (int side = 0; side < 2; ++side)
      if (face.cell[side] != no_cell) g.cells_[face.cell[side]].faces[face.slot[side]] = f;
  }
  for (CellId c = 0; c < nc; ++c)
    for (FaceId f : g.cells_[c].faces)
      LIQUID_VERIFY(f != no_face, "graph state: cell {} has a gap in its face list", c);

  // The tree index: every ancestor of a leaf is interior; keys ascending put parents first.
  std::vector<std::uint64_t> interior;
  for (CellId c = 0; c < nc; ++c)
    if (g.cells_[c].alive)
      for (std::uint64_t k = g.cells_[c].key; k > 1;) {
        k = morton::parent_key<Dim>(k);
        interior.push_back(k);
      }
  std::sort(interior.begin(), interior.end());
  interior.erase(std::unique(interior.begin(), interior.end()), interior.end());
  if (interior.empty()) {
    LIQUID_VERIFY(g.n_cells_ == 1, "graph state: {} cells but no interior node", g.n_cells_);
    for (CellId c = 0; c < nc; ++c)
      if (g.cells_[c].alive) g.nodes_.reset(c);
  } else {
    g.nodes_.reset(detail::NodeIndex<Dim>::absent);
    std::array<std::int32_t, n_children> none;
    none.fill(detail::NodeIndex<Dim>::absent);
    for (std::uint64_t k : interior) g.nodes_.split(k, none);
    for (CellId c = 0; c < nc; ++c)
      if (g.cells_[c].alive) g.nodes_.set_leaf(g.cells_[c].key, c);
  }
  g.free_cells_ = s.free_cells;
  g.free_faces_ = s.free_faces;
  for (CellId c : g.free_cells_)
    LIQUID_VERIFY(c >= 0 && c < nc && !g.cells_[c].alive,
                  "graph state: free cell id {} is alive or out of range", c);
  for (FaceId f : g.free_faces_)
    LIQUID_VERIFY(f >= 0 && f < nf && !g.face_alive_[f],
                  "graph state: free face id {} is alive or out of range", f);
  const InvariantReport check = g.check_invariants();
  LIQUID_VERIFY(check.ok(), "graph state: the restored graph breaks its invariants: {}", check.text(3));
  return g;
}

template CellGraphState<2> CellGraph<2>::state() const;
template CellGraphState<3> CellGraph<3>::state() const;
template CellGraph<2> CellGraph<2>::from_state(const CellGraphState<2>&);
template CellGraph<3> CellGraph<3>::from_state(const CellGraphState<3>&);

}  // namespace liquid::tree
