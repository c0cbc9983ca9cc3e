// CellGraph::check_invariants. Geometry is checked exactly, in integer coordinates of the deepest
// level D (a cell of level l and address a spans [a * 2^(D-l), (a + 1) * 2^(D-l)) per axis).
//
// Checked: every alive cell has a valid level and address, its key encodes them and maps back to
// it, all its ancestors are interior nodes and it has no descendants (so leaves never overlap);
// leaf volumes add up to the domain; the point location of its centre finds it; every face in its
// list points back to it at the right slot, and the faces on each of its 2*Dim sides add up to the
// side's area; every alive face joins alive cells (two for an interior face) that touch across
// the face's plane, the finer side lying within the coarser one, with the recorded levels and a
// level jump within the limit; a boundary face lies on the domain side it names; the counts agree.
#include <fmt/format.h>

#include "liquid/core/error.hpp"
#include "liquid/tree/cell_graph.hpp"

namespace liquid::tree {

template <int Dim>
InvariantReport CellGraph<Dim>::check_invariants() const {
  InvariantReport r;
  const auto fail = [&](std::string what) {
    ++r.n_failures;
    if (r.failures.size() < 200) r.failures.push_back(std::move(what));
  };
  const int D = deepest_;
  __extension__ typedef unsigned __int128 U;
  const auto lo = [&](CellId c, int d) { return cells_[c].address[d] << (D - cells_[c].level); };
  const auto hi = [&](CellId c, int d) { return (cells_[c].address[d] + 1) << (D - cells_[c].level); };

  long n_alive = 0;
  std::vector<long> per_level(n_at_level_.size(), 0);
  U volume = 0;
  const long n_leaf_entries = nodes_.count_leaves();

  for (CellId c = 0; c < cell_capacity(); ++c) {
    const CellData& cell = cells_[c];
    if (!cell.alive) continue;
    ++n_alive;
    const int l = cell.level;
    if (l < 0 || l > options_.max_level || l > D) {
      fail(fmt::format("cell {} has level {} outside [0, {}]", c, l, std::min(D, options_.max_level)));
      continue;
    }
    ++per_level[l];
    volume += U{1} << (Dim * (D - l));
    bool address_ok = true;
    for (int d = 0; d < Dim; ++d)
      address_ok = address_ok && cell.address[d] >= 0 && cell.address[d] < (std::int64_t{1} << l);
    if (!address_ok) {
      fail(fmt::format("cell {} (level {}) has an address outside its level's pyramid", c, l));
      continue;
    }
    if (cell.key != morton::key<Dim>(l, cell.address))
      fail(fmt::format("cell {}: key does not encode its level and address", c));
    if (nodes_.find(cell.key) != c) fail(fmt::format("cell {}: its key does not map back to it", c));
    for (int up = 1; up <= l; ++up)
      if (nodes_.find(morton::ancestor_key<Dim>(cell.key, up)) != detail::NodeIndex<Dim>::interior)
        fail(fmt::format("cell {}: its ancestor {} levels up is not an interior node (overlapping leaves)", c,
                         up));
    for (int i = 0; i < n_children; ++i)
      if (nodes_.contains(morton::child_key<Dim>(cell.key, i)))
        fail(fmt::format("cell {} has a descendant in the tree", c));
    const Box<Dim> b = box(c);
    for (int d = 0; d < Dim; ++d)
      if (b.lo[d] < domain_.lo[d] || b.hi[d] > domain_.hi[d] || !(b.lo[d] < b.hi[d]))
        fail(fmt::format("cell {}: box outside the domain along axis {}", c, d));
    if (locate(centre(c)) != c)
      fail(fmt::format("cell {}: locating its centre finds cell {}", c, locate(centre(c))));

    // Face list: back references, and the faces of each side tile it.
    std::array<U, n_sides> side_area{};
    for (int i = 0; i < cell.faces.size(); ++i) {
      const FaceId f = cell.faces[i];
      if (!face_alive(f)) {
        fail(fmt::format("cell {} lists dead face {}", c, f));
        continue;
      }
      const GraphFace& g = faces_[f];
      int s = -1;
      for (int k = 0; k < 2; ++k)
        if (g.cell[k] == c && g.slot[k] == i) s = k;
      if (s < 0) {
        fail(fmt::format("cell {} lists face {} which does not point back to it", c, f));
        continue;
      }
      const int fl = g.level();
      if (fl >= l && fl <= D) side_area[2 * g.axis + (s == 0 ? 1 : 0)] += U{1} << ((Dim - 1) * (D - fl));
    }
    for (int side = 0; side < n_sides; ++side)
      if (side_area[side] != (U{1} << ((Dim - 1) * (D - l))))
        fail(fmt::format("cell {} (level {}): faces on side {} do not tile it", c, l, side));
  }
  if (n_alive != n_cells_) fail(fmt::format("n_cells() is {} but {} cells are alive", n_cells_, n_alive));
  if (n_leaf_entries != n_alive)
    fail(fmt::format("the key map holds {} leaves for {} alive cells", n_leaf_entries, n_alive));
  for (std::size_t l = 0; l < per_level.size(); ++l)
    if (per_level[l] != n_at_level_[l])
      fail(fmt::format("level {} counts {} cells, {} recorded", l, per_level[l], n_at_level_[l]));
  if (n_alive > 0 && volume != (U{1} << (Dim * D))) fail("leaf volumes do not add up to the domain");
  if (n_alive > 0 && n_at_level_[D] == 0) fail(fmt::format("deepest level {} holds no cell", D));

  long n_alive_faces = 0;
  for (FaceId f = 0; f < face_capacity(); ++f) {
    if (!face_alive_[f]) continue;
    ++n_alive_faces;
    const GraphFace& g = faces_[f];
    const int ax = g.axis;
    if (ax < 0 || ax >= Dim) {
      fail(fmt::format("face {} has axis {}", f, ax));
      continue;
    }
    bool sides_ok = true;
    for (int s = 0; s < 2; ++s) {
      const CellId c = g.cell[s];
      if (c == no_cell) {
        if (g.side_level[s] != -1) fail(fmt::format("face {}: outside side {} has a level", f, s));
        continue;
      }
      if (!alive(c)) {
        fail(fmt::format("face {}: side {} is dead cell {}", f, s, c));
        sides_ok = false;
        continue;
      }
      if (g.side_level[s] != cells_[c].level)
        fail(fmt::format("face {}: side {} level {} but cell {} has level {}", f, s, g.side_level[s], c,
                         cells_[c].level));
      const auto& list = cells_[c].faces;
      if (g.slot[s] < 0 || g.slot[s] >= static_cast<std::int32_t>(list.size()) || list[g.slot[s]] != f)
        fail(fmt::format("face {}: not at its slot in cell {}'s face list", f, c));
    }
    if (!sides_ok) continue;
    const CellId m = g.cell[0], p = g.cell[1];
    if (m == no_cell && p == no_cell) {
      fail(fmt::format("face {} has no cell on either side", f));
      continue;
    }
    if (m == no_cell || p == no_cell) {
      const int s_in = m == no_cell ? 1 : 0;
      const CellId c = g.cell[s_in];
      const int expect = 2 * ax + (s_in == 1 ? 0 : 1);
      if (g.boundary != expect)
        fail(fmt::format("face {}: boundary side {} but expected {}", f, g.boundary, expect));
      const bool on_side = s_in == 1 ? lo(c, ax) == 0 : hi(c, ax) == (std::int64_t{1} << D);
      if (!on_side)
        fail(fmt::format("face {}: boundary face of cell {} is not on the domain boundary", f, c));
      continue;
    }
    if (g.boundary != -1) fail(fmt::format("face {}: interior face marked as boundary {}", f, g.boundary));
    if (hi(m, ax) != lo(p, ax))
      fail(fmt::format("face {}: cells {} and {} do not touch along axis {}", f, m, p, ax));
    const CellId fine = cells_[m].level >= cells_[p].level ? m : p;
    const CellId coarse = fine == m ? p : m;
    for (int d = 0; d < Dim; ++d)
      if (d != ax && (lo(fine, d) < lo(coarse, d) || hi(fine, d) > hi(coarse, d)))
        fail(fmt::format("face {}: finer cell {} is not within cell {}'s side along axis {}", f, fine, coarse,
                         d));
    const int jump = std::abs(cells_[m].level - cells_[p].level);
    if (jump > options_.max_jump)
      fail(fmt::format("face {}: level jump {} between cells {} and {} exceeds {}", f, jump, m, p,
                       options_.max_jump));
  }
  if (n_alive_faces != n_faces_)
    fail(fmt::format("n_faces() is {} but {} faces are alive", n_faces_, n_alive_faces));
  return r;
}

template InvariantReport CellGraph<2>::check_invariants() const;
template InvariantReport CellGraph<3>::check_invariants() const;

}  // namespace liquid::tree
