#pragma once
// CellGraph<Dim>: an adaptive, possibly non-graded quadtree (Dim = 2) or octree (Dim = 3) stored as
// its dual graph (the paper's "Cellgraph", section 5 of rbf-liquids-2020). Nodes are the leaf
// cells; edges are the faces shared by two leaves, plus faces to the outside on the domain
// boundary. The graph owns topology only: fields live in caller-owned arrays indexed by the stable
// cell and face ids (ids of removed cells and faces are recycled by later changes).
//
// Geometry. The root (level 0) is the whole box domain, which need not be a cube: cells are
// anisotropic when the domain is. A cell at level L with address a (0 <= a_d < 2^L) is the box
//   [lo + a * s / 2^L, lo + (a + 1) * s / 2^L],  s = domain size.
// A face lies on the side of its finer cell (the "face level" is the larger of the two levels);
// it hangs on the side of a coarser cell, of which it covers only a part.
//
// Changes. split() and merge() update only the faces around the cells involved. adapt() executes
// marks (estimate -> mark -> execute) under the graph's maximum level jump between face neighbours
// and its minimum and maximum level, and reports every new and removed cell and face with the
// origin of each new one, so fields can be remapped (see remap.hpp). Within one change, removed
// ids are never reused, so a field can be remapped in place.

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "liquid/core/morton.hpp"
#include "liquid/core/types.hpp"
#include "liquid/tree/id_list.hpp"
#include "liquid/tree/node_index.hpp"

namespace liquid::tree {

using CellId = std::int32_t;
using FaceId = std::int32_t;
inline constexpr CellId no_cell = -1;  ///< the outside of the domain, or "none"
inline constexpr FaceId no_face = -1;

namespace detail {
/// Loops shorter than this run on one thread: below it, starting threads costs more than it saves.
inline constexpr long parallel_min = 8192;
/// A number no graph state has had before in this process (see CellGraph::topology()).
inline std::uint64_t next_topology() {
  static std::atomic<std::uint64_t> last{0};
  return ++last;
}
}  // namespace detail

/// max_jump value that leaves the level jump between face neighbours unconstrained.
inline constexpr int unlimited_jump = 1 << 20;

template <int Dim>
struct CellGraphOptions {
  int max_jump = 2;   ///< largest level difference across a face (1 = graded); or unlimited_jump
  int min_level = 0;  ///< adapt() never merges below this level
  int max_level = morton::max_level<Dim>;  ///< no cell is ever split beyond this level
};

/// A node of the tree as the refinement predicate of CellGraph::build sees it.
template <int Dim>
struct TreeNode {
  int level = 0;
  IVec<Dim> address;  ///< at `level`
  Box<Dim> box;
};

/// One face (graph edge). Side 0 is the cell at the lower coordinate along `axis`, side 1 the upper.
struct GraphFace {
  std::array<CellId, 2> cell{no_cell, no_cell};   ///< no_cell on the outside of a boundary face
  std::array<std::int8_t, 2> side_level{-1, -1};  ///< level of each side's cell; -1 outside
  std::int8_t axis = 0;                           ///< normal axis
  std::int8_t boundary = -1;  ///< -1 interior; else the domain side 2*axis + (0 lower, 1 upper)
  std::array<std::int32_t, 2> slot{-1, -1};  ///< (internal) position in each side's face list

  /// Level of the face itself: that of its finer side.
  int level() const { return side_level[0] > side_level[1] ? side_level[0] : side_level[1]; }
  /// True when the face covers only part of side `s`'s cell face (a T-junction on that side).
  bool hanging(int s) const { return side_level[s] >= 0 && side_level[s] < level(); }
  bool hanging() const { return hanging(0) || hanging(1); }
  bool is_boundary() const { return boundary >= 0; }
};

/// How a cell meets its neighbour across one of its faces.
enum class Adjacency : std::int8_t {
  boundary,  ///< the face is on the domain boundary (no neighbour)
  same,      ///< neighbour of the same level: the face is full on both sides
  coarser,   ///< neighbour is coarser: this cell's whole side is part of the neighbour's side
  finer,     ///< neighbour is finer: the face is part of this cell's side (several faces on the side)
};

/// A face seen from one cell side, as a stencil builder wants it.
struct SideFace {
  FaceId face = no_face;
  CellId neighbour = no_cell;  ///< no_cell on the domain boundary
  int neighbour_level = -1;
  Adjacency adjacency = Adjacency::boundary;
};

/// What adapt() is asked to do with a cell.
enum class Mark : std::int8_t { keep = 0, split = 1, merge = 2 };

/// Sparse marks for adapt(): the cells to split and the cells to merge. A sibling group merges only
/// when every member is listed. Duplicates and dead ids are ignored; order does not matter (adapt
/// sorts both lists, so the outcome equals that of the same marks given densely).
struct MarkList {
  std::vector<CellId> split;
  std::vector<CellId> merge;
  void clear() {
    split.clear();
    merge.clear();
  }
  bool empty() const { return split.empty() && merge.empty(); }
};

/// Sparse linear combinations: entry i is sum_k weight[k] * old[source[k]], k in [begin[i], begin[i+1]).
struct Origins {
  std::vector<std::int32_t> begin{0};
  std::vector<std::int32_t> source;
  std::vector<double> weight;

  std::size_t size() const { return begin.size() - 1; }
};

/// What one change (adapt, split or merge) did. Ids in new_* and removed_* are disjoint.
struct AdaptReport {
  std::vector<CellId> new_cells;      ///< alive cells created by the change
  std::vector<CellId> removed_cells;  ///< cells alive before the change, now removed
  Origins cell_origins;               ///< per new cell, in old cell ids: 1 source (weight 1) = inside an old
                                      ///< cell; 2^Dim sources (weight 2^-Dim each) = union of old cells
  std::vector<FaceId> new_faces;
  std::vector<FaceId> removed_faces;
  Origins face_origins;  ///< per new face, in old face ids: 1 source = part of an old face; several =
                         ///< the area-weighted union of old faces, or for a face inside a split cell
                         ///< the mean of that cell's two sides along the face's axis

  long n_split = 0;           ///< cells split, balancing splits included
  long n_balance_splits = 0;  ///< of which forced by the level-jump limit
  long n_merged = 0;          ///< sibling groups merged
  long n_refused_split = 0;   ///< split marks refused (at the maximum level)
  long n_refused_merge = 0;   ///< merge-marked cells that stayed (jump limit, min level, group incomplete)

  bool empty() const { return new_cells.empty() && removed_cells.empty(); }
};

/// Everything that decides a graph's future, its ids and free lists included: what a checkpoint
/// stores so that a restored graph evolves bit for bit like the original. Plain arrays by id.
template <int Dim>
struct CellGraphState {
  static constexpr int face_record = 8;  ///< ints per face in `faces`
  Box<Dim> domain;
  CellGraphOptions<Dim> options;
  std::vector<std::int32_t> level;    ///< per cell id; -1 for a dead id
  std::vector<std::int64_t> address;  ///< Dim per cell id
  /// Per face id: cell[0], cell[1], side_level[0], side_level[1], axis, boundary, slot[0], slot[1].
  std::vector<std::int32_t> faces;
  std::vector<std::uint8_t> face_alive;
  std::vector<std::int32_t> free_cells, free_faces;  ///< in the order they will be reused (from the back)
};

/// The outcome of CellGraph::check_invariants().
struct InvariantReport {
  std::vector<std::string> failures;  ///< one sentence each (the first few hundred)
  long n_failures = 0;
  bool ok() const { return n_failures == 0; }
  /// The first `max_lines` failures, one per line.
  std::string text(int max_lines = 10) const;
};

template <int Dim>
class CellGraph {
 public:
  static constexpr int n_children = 1 << Dim;
  static constexpr int n_sides = 2 * Dim;
  using Predicate = std::function<bool(const TreeNode<Dim>&)>;

  /// A graph with one cell, the root covering `domain` (lo < hi on every axis).
  explicit CellGraph(const Box<Dim>& domain, const CellGraphOptions<Dim>& options = {});

  /// Builds the tree top-down: a node is split while `refine(node)` is true (always below
  /// options.min_level, never at options.max_level), then coarse leaves are split until the level
  /// jump holds. Cells of the predicate's tree are numbered in Morton order, cells added by the
  /// balancing after them. Evaluates `refine` from several threads at once.
  static CellGraph build(const Box<Dim>& domain, const Predicate& refine,
                         const CellGraphOptions<Dim>& options = {});

  /// The graph as plain arrays (see CellGraphState), and back. from_state() checks the arrays'
  /// sizes and every invariant, and throws liquid::Error naming the first problem.
  CellGraphState<Dim> state() const;
  static CellGraph from_state(const CellGraphState<Dim>& state);

  // ---- sizes and settings
  const Box<Dim>& domain() const { return domain_; }
  const CellGraphOptions<Dim>& options() const { return options_; }
  int max_jump() const { return options_.max_jump; }
  int n_cells() const { return n_cells_; }                               ///< alive cells (leaves)
  int n_faces() const { return n_faces_; }                               ///< alive faces
  int cell_capacity() const { return static_cast<int>(cells_.size()); }  ///< largest cell id + 1
  int face_capacity() const { return static_cast<int>(faces_.size()); }  ///< largest face id + 1
  int deepest_level() const { return deepest_; }
  /// Changes whenever cells or faces do (a split, merge or adapt), and differs between graphs built
  /// apart: what is derived from the topology alone holds while this number stays the same.
  std::uint64_t topology() const { return topology_; }
  long n_cells_at_level(int level) const { return n_at_level_[level]; }

  // ---- cells
  bool alive(CellId c) const { return c >= 0 && c < cell_capacity() && cells_[c].alive; }
  int level(CellId c) const { return cells_[c].level; }
  const IVec<Dim>& address(CellId c) const { return cells_[c].address; }
  std::uint64_t key(CellId c) const { return cells_[c].key; }
  Vec<Dim> cell_size(CellId c) const { return level_size_[cells_[c].level]; }
  Box<Dim> box(CellId c) const;
  Vec<Dim> centre(CellId c) const;
  double volume(CellId c) const { return cell_size(c).prod(); }
  /// All faces of `c`, in no particular order.
  std::span<const FaceId> faces(CellId c) const {
    return {cells_[c].faces.data(), static_cast<std::size_t>(cells_[c].faces.size())};
  }

  /// Calls fn(const SideFace&) for each face on side (axis, dir) of cell c; dir = -1 lower, +1 upper.
  template <class Fn>
  void for_each_side_face(CellId c, int axis, int dir, Fn&& fn) const;
  /// The faces on side (axis, dir) of `c` (out is cleared first).
  void side_faces(CellId c, int axis, int dir, std::vector<SideFace>& out) const;

  // ---- faces
  bool face_alive(FaceId f) const { return f >= 0 && f < face_capacity() && face_alive_[f]; }
  const GraphFace& face(FaceId f) const { return faces_[f]; }
  Vec<Dim> face_centre(FaceId f) const;
  double face_area(FaceId f) const;
  /// Centres and areas of all faces, indexed by face id (dead entries untouched). Uses OpenMP.
  void face_geometry(std::vector<Vec<Dim>>& centres, std::vector<double>& areas) const;

  // ---- iteration (ascending ids)
  template <class Fn>
  void for_each_cell(Fn&& fn) const {
    for (CellId c = 0; c < cell_capacity(); ++c)
      if (cells_[c].alive) fn(c);
  }
  template <class Fn>
  void for_each_face(Fn&& fn) const {
    for (FaceId f = 0; f < face_capacity(); ++f)
      if (face_alive_[f]) fn(f);
  }
  std::vector<CellId> cell_ids() const;
  std::vector<FaceId> face_ids() const;

  // ---- queries (all safe from many threads at once)
  /// The leaf holding `x` (points outside the domain are clamped onto it; ties go to the upper
  /// cell). A descent from the root along x's Morton code: O(depth), no search, no hashing.
  /// Throws on a non-finite coordinate.
  CellId locate(const Vec<Dim>& x) const;
  /// As locate(x), but returns `hint` at once when it is alive and holds x.
  CellId locate(const Vec<Dim>& x, CellId hint) const;
  /// locate() for every point (OpenMP); out.size() must equal x.size().
  void locate(std::span<const Vec<Dim>> x, std::span<CellId> out) const;
  /// The leaf at exactly (level, address), or no_cell.
  CellId find(int level, const IVec<Dim>& address) const;
  /// The cells within k face-hops of c, c first, in breadth-first order (out is cleared first).
  void k_ring(CellId c, int k, std::vector<CellId>& out) const;

  /// The sibling test by address code: 2^Dim distinct alive cells of one level and one parent.
  bool are_siblings(std::span<const CellId> cells) const;
  /// The 2^Dim siblings of c (child order, c among them) when all are leaves.
  std::optional<std::array<CellId, n_children>> siblings(CellId c) const;
  /// True when c's sibling group is all leaves and merging it keeps min_level and the level jump.
  bool can_merge(CellId c) const;

  // ---- changes
  /// Splits c into its 2^Dim children, first splitting coarser neighbours that would break the
  /// level jump (recursively). Throws if c is not alive or is at max_level. Returns c's children
  /// in child order; `report` (optional, out) receives what changed.
  std::array<CellId, n_children> split(CellId c, AdaptReport* report = nullptr);
  /// Replaces the 2^Dim sibling leaves by their parent; returns it. Throws unless are_siblings()
  /// and can_merge() hold. `report` (optional, out) receives what changed.
  CellId merge(std::span<const CellId> siblings, AdaptReport* report = nullptr);
  /// Executes marks indexed by cell id (marks.size() >= cell_capacity(); dead ids ignored): first
  /// every split (at most one level per marked cell, plus the balancing splits), then every
  /// sibling group whose members are all marked merge, where min_level and the jump limit allow.
  AdaptReport adapt(std::span<const Mark> marks);
  /// adapt() from sparse marks: costs O(marked cells + changed cells), not O(cells), so a narrow
  /// band can be re-adapted at a cost proportional to what changes. The lists are sorted in place.
  AdaptReport adapt(MarkList& marks);

  // ---- checks
  /// Checks every structural invariant (see the .cpp); O(cells + faces) hash probes.
  InvariantReport check_invariants() const;

 private:
  struct CellData {
    IVec<Dim> address = IVec<Dim>::Zero();
    std::uint64_t key = 1;
    std::int8_t level = 0;
    bool alive = false;
    detail::IdList faces;
  };
  struct FaceOriginRecord {
    std::int32_t begin = 0, end = 0;  // into log_source_/log_weight_
  };

  CellGraph() = default;

  // Allocation and bookkeeping (cell_graph.cpp).
  void init_levels();
  CellId new_cell(int level, const IVec<Dim>& address);
  void kill_cell(CellId c);
  FaceId add_face(CellId minus, CellId plus, int axis, int boundary, int level_minus, int level_plus);
  void attach(FaceId f, int side, CellId c, int level);
  void detach(FaceId f, int side);
  void kill_face(FaceId f);
  CellId covering_leaf(int level, const IVec<Dim>& address) const;

  // Topology changes (cell_graph_change.cpp).
  void begin_change();
  void end_change(AdaptReport* report);
  void split_raw(CellId c);
  void split_balanced(CellId c, AdaptReport& counts);
  CellId merge_raw(const std::array<CellId, n_children>& children);
  bool merge_allowed(const std::array<CellId, n_children>& children) const;
  void face_terms(FaceId f, double scale, std::vector<std::pair<FaceId, double>>& out) const;
  void record_face_origin(FaceId f, const std::vector<std::pair<FaceId, double>>& terms);

  Box<Dim> domain_;
  CellGraphOptions<Dim> options_;
  std::vector<Vec<Dim>> level_size_;  // cell size per level
  std::vector<CellData> cells_;
  std::vector<GraphFace> faces_;
  std::vector<std::uint8_t> face_alive_;
  std::vector<CellId> free_cells_;
  std::vector<FaceId> free_faces_;
  detail::NodeIndex<Dim> nodes_;  // every tree node by key
  std::vector<long> n_at_level_;
  int deepest_ = 0;
  int n_cells_ = 0;
  int n_faces_ = 0;
  std::uint64_t topology_ = detail::next_topology();

  // Change log (valid between begin_change and end_change).
  std::uint32_t epoch_ = 0;
  bool in_change_ = false;
  std::vector<std::uint32_t> cell_birth_, face_birth_;
  std::vector<CellId> born_cells_, pending_free_cells_, removed_cells_;
  std::vector<FaceId> born_faces_, pending_free_faces_, removed_faces_;
  std::vector<std::array<CellId, n_children>> cell_origin_;  // per born cell (index in born_cells_)
  std::vector<std::int8_t> cell_origin_count_;
  std::vector<std::int32_t> cell_log_index_;   // cell id -> index in born_cells_
  std::vector<FaceOriginRecord> face_origin_;  // per born face
  std::vector<std::int32_t> face_log_index_;   // face id -> index in born_faces_
  std::vector<FaceId> log_source_;
  std::vector<double> log_weight_;
  std::vector<std::uint32_t> merge_stamp_;  // adapt(): == merge_round_ when the cell is marked merge
  std::uint32_t merge_round_ = 0;
};

// Geometry, defined here so that the per-particle and per-face loops inline it.
template <int Dim>
inline Box<Dim> CellGraph<Dim>::box(CellId c) const {
  const CellData& cell = cells_[c];
  const Vec<Dim>& s = level_size_[cell.level];
  Box<Dim> b;
  for (int d = 0; d < Dim; ++d) {
    b.lo[d] = domain_.lo[d] + static_cast<double>(cell.address[d]) * s[d];
    b.hi[d] = domain_.lo[d] + static_cast<double>(cell.address[d] + 1) * s[d];
  }
  return b;
}

template <int Dim>
inline Vec<Dim> CellGraph<Dim>::centre(CellId c) const {
  const CellData& cell = cells_[c];
  const Vec<Dim>& s = level_size_[cell.level];
  Vec<Dim> x;
  for (int d = 0; d < Dim; ++d) x[d] = domain_.lo[d] + (static_cast<double>(cell.address[d]) + 0.5) * s[d];
  return x;
}

template <int Dim>
inline Vec<Dim> CellGraph<Dim>::face_centre(FaceId f) const {
  const GraphFace& g = faces_[f];
  const int fine = g.side_level[0] >= g.side_level[1] ? 0 : 1;
  const CellId c = g.cell[fine];
  Vec<Dim> x = centre(c);
  const Box<Dim> b = box(c);
  x[g.axis] = fine == 0 ? b.hi[g.axis] : b.lo[g.axis];
  return x;
}

template <int Dim>
template <class Fn>
void CellGraph<Dim>::for_each_side_face(CellId c, int axis, int dir, Fn&& fn) const {
  const int self_side = dir > 0 ? 0 : 1;  // on its upper side, c is the face's lower (minus) side
  const int my_level = cells_[c].level;
  for (FaceId f : cells_[c].faces) {
    const GraphFace& g = faces_[f];
    if (g.axis != axis || g.cell[self_side] != c) continue;
    SideFace s;
    s.face = f;
    s.neighbour = g.cell[1 - self_side];
    s.neighbour_level = g.side_level[1 - self_side];
    if (s.neighbour == no_cell)
      s.adjacency = Adjacency::boundary;
    else if (s.neighbour_level == my_level)
      s.adjacency = Adjacency::same;
    else
      s.adjacency = s.neighbour_level < my_level ? Adjacency::coarser : Adjacency::finer;
    fn(s);
  }
}

extern template class CellGraph<2>;
extern template class CellGraph<3>;

}  // namespace liquid::tree
