// CellGraph topology changes: split and merge with local face updates, the level-jump balancing,
// adapt(), and the change log that becomes an AdaptReport.
//
// Face rules. A face lies on the side of its finer cell. Splitting cell c (level l):
//   - a face whose other side is finer (face level > l) lies inside one child's side: it is
//     handed to that child and keeps its id and geometry;
//   - a face as large as c's side (other side same level, coarser or outside) is replaced by
//     2^(Dim-1) faces, one per child on that side;
//   - 2^(Dim-1) new faces per axis separate the children.
// Merging 2^Dim sibling leaves (level l) into their parent is the reverse: faces between siblings
// go; faces to a neighbour of level >= l are handed to the parent unchanged; the 2^(Dim-1) faces
// to a neighbour coarser than l (or the outside) on one side become one face.
#include <algorithm>

#include "liquid/core/error.hpp"
#include "liquid/tree/cell_graph.hpp"

namespace liquid::tree {

namespace {
using Terms = std::vector<std::pair<FaceId, double>>;
using detail::side_child;
}  // namespace

template <int Dim>
void CellGraph<Dim>::begin_change() {
  LIQUID_ASSERT(!in_change_, "CellGraph: nested change");
  ++epoch_;
  in_change_ = true;
  topology_ = detail::next_topology();
}

template <int Dim>
void CellGraph<Dim>::end_change(AdaptReport* report) {
  if (report != nullptr) {
    AdaptReport& r = *report;
    for (std::size_t i = 0; i < born_cells_.size(); ++i) {
      const CellId c = born_cells_[i];
      if (!cells_[c].alive) continue;
      r.new_cells.push_back(c);
      const int n = cell_origin_count_[i];
      for (int k = 0; k < n; ++k) {
        r.cell_origins.source.push_back(cell_origin_[i][k]);
        r.cell_origins.weight.push_back(1.0 / n);
      }
      r.cell_origins.begin.push_back(static_cast<std::int32_t>(r.cell_origins.source.size()));
    }
    r.removed_cells = removed_cells_;
    Terms terms;
    for (std::size_t i = 0; i < born_faces_.size(); ++i) {
      const FaceId f = born_faces_[i];
      if (!face_alive_[f]) continue;
      r.new_faces.push_back(f);
      // Merge repeated sources so each old face appears once.
      terms.clear();
      for (std::int32_t k = face_origin_[i].begin; k < face_origin_[i].end; ++k)
        terms.emplace_back(log_source_[k], log_weight_[k]);
      std::sort(terms.begin(), terms.end());
      for (std::size_t k = 0; k < terms.size(); ++k) {
        if (k > 0 && terms[k].first == terms[k - 1].first) {
          r.face_origins.weight.back() += terms[k].second;
          continue;
        }
        r.face_origins.source.push_back(terms[k].first);
        r.face_origins.weight.push_back(terms[k].second);
      }
      r.face_origins.begin.push_back(static_cast<std::int32_t>(r.face_origins.source.size()));
    }
    r.removed_faces = removed_faces_;
  }
  free_cells_.insert(free_cells_.end(), pending_free_cells_.rbegin(), pending_free_cells_.rend());
  free_faces_.insert(free_faces_.end(), pending_free_faces_.rbegin(), pending_free_faces_.rend());
  for (CellId c : born_cells_) cell_log_index_[c] = -1;
  for (FaceId f : born_faces_) face_log_index_[f] = -1;
  born_cells_.clear();
  pending_free_cells_.clear();
  removed_cells_.clear();
  born_faces_.clear();
  pending_free_faces_.clear();
  removed_faces_.clear();
  cell_origin_.clear();
  cell_origin_count_.clear();
  face_origin_.clear();
  log_source_.clear();
  log_weight_.clear();
  in_change_ = false;
}

template <int Dim>
void CellGraph<Dim>::face_terms(FaceId f, double scale, std::vector<std::pair<FaceId, double>>& out) const {
  if (face_birth_[f] < epoch_) {
    out.emplace_back(f, scale);
    return;
  }
  const FaceOriginRecord& rec = face_origin_[face_log_index_[f]];
  for (std::int32_t k = rec.begin; k < rec.end; ++k) out.emplace_back(log_source_[k], scale * log_weight_[k]);
}

template <int Dim>
void CellGraph<Dim>::record_face_origin(FaceId f, const std::vector<std::pair<FaceId, double>>& terms) {
  FaceOriginRecord& rec = face_origin_[face_log_index_[f]];
  rec.begin = static_cast<std::int32_t>(log_source_.size());
  for (const auto& [src, w] : terms) {
    log_source_.push_back(src);
    log_weight_.push_back(w);
  }
  rec.end = static_cast<std::int32_t>(log_source_.size());
}

template <int Dim>
void CellGraph<Dim>::split_raw(CellId c) {
  LIQUID_ASSERT(in_change_ && cells_[c].alive, "CellGraph::split_raw: bad call on cell {}", c);
  const int l = cells_[c].level;
  const IVec<Dim> a = cells_[c].address;
  const std::uint64_t k = cells_[c].key;
  const detail::IdList old_faces = std::move(cells_[c].faces);

  // Children inherit from c, or from the old cell c came from.
  std::array<CellId, n_children> src{};
  int n_src = 1;
  if (cell_birth_[c] < epoch_) {
    src[0] = c;
  } else {
    const std::int32_t i = cell_log_index_[c];
    src = cell_origin_[i];
    n_src = cell_origin_count_[i];
    LIQUID_ASSERT(n_src == 1, "CellGraph: splitting a cell merged in the same change");
  }

  // A face inside c along axis d takes the mean of c's two sides along d (area-weighted).
  std::array<Terms, Dim> inner;
  for (FaceId f : old_faces) {
    const GraphFace& g = faces_[f];
    const double frac = std::ldexp(1.0, -(Dim - 1) * (g.level() - l));
    face_terms(f, 0.5 * frac, inner[g.axis]);
  }

  std::array<CellId, n_children> ch;
  for (int i = 0; i < n_children; ++i) {
    IVec<Dim> b = 2 * a;
    for (int d = 0; d < Dim; ++d) b[d] += (i >> d) & 1;
    ch[i] = new_cell(l + 1, b);
    const std::int32_t li = cell_log_index_[ch[i]];
    cell_origin_[li] = src;
    cell_origin_count_[li] = static_cast<std::int8_t>(n_src);
  }
  nodes_.split(k, ch);

  Terms terms;
  for (FaceId f : old_faces) {
    const GraphFace g = faces_[f];  // copy: add_face may grow faces_
    const int s = g.cell[0] == c ? 0 : 1;
    const int upper = s == 0 ? 1 : 0;  // c is the lower side: the face is on c's upper side
    const CellId other = g.cell[1 - s];
    const int other_level = g.side_level[1 - s];
    if (other_level > l) {
      const IVec<Dim>& oa = cells_[other].address;
      int idx = upper << g.axis;
      for (int e = 0; e < Dim; ++e)
        if (e != g.axis) idx |= static_cast<int>((oa[e] >> (other_level - l - 1)) & 1) << e;
      attach(f, s, ch[idx], l + 1);
      continue;
    }
    if (other != no_cell) detach(f, 1 - s);
    terms.clear();
    face_terms(f, 1.0, terms);
    for (int j = 0; j < n_children / 2; ++j) {
      const CellId child = ch[side_child<Dim>(g.axis, upper, j)];
      const FaceId h = s == 0 ? add_face(child, other, g.axis, g.boundary, l + 1, other_level)
                              : add_face(other, child, g.axis, g.boundary, other_level, l + 1);
      record_face_origin(h, terms);
    }
    kill_face(f);
  }
  for (int d = 0; d < Dim; ++d) {
    for (int i = 0; i < n_children; ++i) {
      if ((i >> d) & 1) continue;
      const FaceId h = add_face(ch[i], ch[i | (1 << d)], d, -1, l + 1, l + 1);
      record_face_origin(h, inner[d]);
    }
  }
  kill_cell(c);
}

template <int Dim>
void CellGraph<Dim>::split_balanced(CellId c, AdaptReport& counts) {
  const int jump = options_.max_jump;
  std::vector<CellId> stack{c};
  while (!stack.empty()) {
    const CellId x = stack.back();
    if (!cells_[x].alive) {
      stack.pop_back();
      continue;
    }
    // After the split x's children sit at level(x)+1; coarser neighbours must be within `jump`.
    const int need = cells_[x].level + 1 - jump;
    bool pushed = false;
    if (need > 0) {
      for (FaceId f : cells_[x].faces) {
        const GraphFace& g = faces_[f];
        const int s = g.cell[0] == x ? 0 : 1;
        if (g.cell[1 - s] != no_cell && g.side_level[1 - s] < need) {
          stack.push_back(g.cell[1 - s]);
          pushed = true;
        }
      }
    }
    if (pushed) continue;
    stack.pop_back();
    split_raw(x);
    ++counts.n_split;
    if (x != c) ++counts.n_balance_splits;
  }
}

template <int Dim>
CellId CellGraph<Dim>::merge_raw(const std::array<CellId, n_children>& ch) {
  const int l = cells_[ch[0]].level;
  const std::uint64_t k = morton::parent_key<Dim>(cells_[ch[0]].key);
  IVec<Dim> a = cells_[ch[0]].address;
  for (int d = 0; d < Dim; ++d) a[d] >>= 1;

  const CellId p = new_cell(l - 1, a);
  {
    const std::int32_t li = cell_log_index_[p];
    for (int i = 0; i < n_children; ++i) {
      LIQUID_ASSERT(cell_birth_[ch[i]] < epoch_, "CellGraph: merging cells created in the same change");
      cell_origin_[li][i] = ch[i];
    }
    cell_origin_count_[li] = static_cast<std::int8_t>(n_children);
  }
  nodes_.merge(k, p);

  // Per side of the parent: faces to a coarser neighbour (or the outside) become one.
  std::array<Terms, n_sides> united;
  std::array<GraphFace, n_sides> shape;
  std::array<bool, n_sides> has{};
  const double part = std::ldexp(1.0, -(Dim - 1));
  for (int i = 0; i < n_children; ++i) {
    const detail::IdList list = std::move(cells_[ch[i]].faces);
    for (FaceId f : list) {
      if (!face_alive_[f]) continue;  // between siblings, already gone
      const GraphFace g = faces_[f];
      const int s = g.cell[0] == ch[i] ? 0 : 1;
      const CellId other = g.cell[1 - s];
      const int other_level = g.side_level[1 - s];
      if (other != no_cell && other_level == l && morton::parent_key<Dim>(cells_[other].key) == k) {
        kill_face(f);
        continue;
      }
      if (other_level >= l) {
        attach(f, s, p, l - 1);
        continue;
      }
      const int side = 2 * g.axis + (s == 0 ? 1 : 0);
      if (other != no_cell) detach(f, 1 - s);
      face_terms(f, part, united[side]);
      if (!has[side]) {
        has[side] = true;
        shape[side] = g;
        shape[side].cell[s] = p;
        shape[side].side_level[s] = static_cast<std::int8_t>(l - 1);
      }
      kill_face(f);
    }
  }
  for (int side = 0; side < n_sides; ++side) {
    if (!has[side]) continue;
    const GraphFace& g = shape[side];
    const FaceId h = add_face(g.cell[0], g.cell[1], g.axis, g.boundary, g.side_level[0], g.side_level[1]);
    record_face_origin(h, united[side]);
  }
  for (CellId c : ch) kill_cell(c);
  return p;
}

template <int Dim>
std::array<CellId, CellGraph<Dim>::n_children> CellGraph<Dim>::split(CellId c, AdaptReport* report) {
  LIQUID_VERIFY(alive(c), "CellGraph::split: cell {} is not alive", c);
  LIQUID_VERIFY(cells_[c].level < options_.max_level, "CellGraph::split: cell {} is at the maximum level {}",
                c, options_.max_level);
  const std::uint64_t k = cells_[c].key;
  AdaptReport local;
  AdaptReport& r = report != nullptr ? *report : local;
  r = AdaptReport{};
  begin_change();
  split_balanced(c, r);
  end_change(report);
  std::array<CellId, n_children> ch;
  for (int i = 0; i < n_children; ++i) ch[i] = nodes_.find(morton::child_key<Dim>(k, i));
  return ch;
}

template <int Dim>
CellId CellGraph<Dim>::merge(std::span<const CellId> group, AdaptReport* report) {
  LIQUID_VERIFY(are_siblings(group),
                "CellGraph::merge: the {} cells given are not the {} leaf children of one parent",
                group.size(), n_children);
  std::array<CellId, n_children> ch;
  for (CellId c : group) ch[morton::child_index<Dim>(cells_[c].key)] = c;
  LIQUID_VERIFY(
      merge_allowed(ch),
      "CellGraph::merge: merging cell {}'s siblings (level {}) would break min_level {} or the level jump {}",
      ch[0], cells_[ch[0]].level, options_.min_level, options_.max_jump);
  if (report != nullptr) *report = AdaptReport{};
  begin_change();
  const CellId p = merge_raw(ch);
  end_change(report);
  if (report != nullptr) report->n_merged = 1;
  return p;
}

template <int Dim>
AdaptReport CellGraph<Dim>::adapt(std::span<const Mark> marks) {
  LIQUID_VERIFY(marks.size() >= cells_.size(), "CellGraph::adapt: {} marks for {} cell ids (cell_capacity())",
                marks.size(), cells_.size());
  MarkList list;
  for (CellId c = 0; c < cell_capacity(); ++c) {
    if (!cells_[c].alive) continue;
    if (marks[c] == Mark::split)
      list.split.push_back(c);
    else if (marks[c] == Mark::merge)
      list.merge.push_back(c);
  }
  return adapt(list);
}

template <int Dim>
AdaptReport CellGraph<Dim>::adapt(MarkList& marks) {
  // Only cells alive now count: a dead id listed here could be handed out again by a split below
  // and must not be mistaken for the cell born under it.
  for (auto* list : {&marks.split, &marks.merge}) {
    std::erase_if(*list, [this](CellId c) { return !alive(c); });
    std::sort(list->begin(), list->end());
    list->erase(std::unique(list->begin(), list->end()), list->end());
  }
  // Stamp the merge marks of cells alive now; ids born during this change are never stamped (the
  // free list only hands out ids dead before it, and ids removed by it are not reused within it).
  if (++merge_round_ == 0) {
    std::fill(merge_stamp_.begin(), merge_stamp_.end(), 0u);
    merge_round_ = 1;
  }
  if (merge_stamp_.size() < cells_.size()) merge_stamp_.resize(cells_.size(), 0u);
  long n_merge_marked = 0;
  for (CellId c : marks.merge) {
    merge_stamp_[c] = merge_round_;
    ++n_merge_marked;
  }
  const auto marked_merge = [&](CellId s) {
    return static_cast<std::size_t>(s) < merge_stamp_.size() && merge_stamp_[s] == merge_round_;
  };

  AdaptReport r;
  begin_change();
  for (CellId c : marks.split) {
    if (!alive(c)) continue;  // already split by balancing: the mark is met
    if (cells_[c].level >= options_.max_level) {
      ++r.n_refused_split;
      continue;
    }
    split_balanced(c, r);
  }
  long n_merged_cells = 0;
  for (CellId c : marks.merge) {
    if (!alive(c) || !marked_merge(c) || morton::child_index<Dim>(cells_[c].key) != 0) continue;
    const auto group = siblings(c);
    if (!group) continue;
    bool all = true;
    for (CellId s : *group) all = all && cell_birth_[s] < epoch_ && marked_merge(s);
    if (!all || !merge_allowed(*group)) continue;
    merge_raw(*group);
    ++r.n_merged;
    n_merged_cells += n_children;
  }
  r.n_refused_merge = n_merge_marked - n_merged_cells;
  end_change(&r);
  return r;
}

// The class itself is instantiated in cell_graph.cpp; this file instantiates the members it defines.
#define LIQUID_CELL_GRAPH_CHANGE(D)                                                                      \
  template void CellGraph<D>::begin_change();                                                            \
  template void CellGraph<D>::end_change(AdaptReport*);                                                  \
  template void CellGraph<D>::face_terms(FaceId, double, std::vector<std::pair<FaceId, double>>&) const; \
  template void CellGraph<D>::record_face_origin(FaceId, const std::vector<std::pair<FaceId, double>>&); \
  template void CellGraph<D>::split_raw(CellId);                                                         \
  template void CellGraph<D>::split_balanced(CellId, AdaptReport&);                                      \
  template CellId CellGraph<D>::merge_raw(const std::array<CellId, CellGraph<D>::n_children>&);          \
  template std::array<CellId, CellGraph<D>::n_children> CellGraph<D>::split(CellId, AdaptReport*);       \
  template CellId CellGraph<D>::merge(std::span<const CellId>, AdaptReport*);                            \
  template AdaptReport CellGraph<D>::adapt(std::span<const Mark>);                                       \
  template AdaptReport CellGraph<D>::adapt(MarkList&);
LIQUID_CELL_GRAPH_CHANGE(2)
LIQUID_CELL_GRAPH_CHANGE(3)
#undef LIQUID_CELL_GRAPH_CHANGE

}  // namespace liquid::tree
