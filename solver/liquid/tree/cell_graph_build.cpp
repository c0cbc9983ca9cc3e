// CellGraph::build: the whole graph at once, without incremental splits, and without hashing on
// the hot paths.
//   1. nodes level by level: the predicate runs on all nodes of a level in parallel, a prefix sum
//      places the children, so each level's nodes are in Morton order;
//   2. leaf ids in Morton (depth-first) order from per-subtree leaf counts; the node index's child
//      blocks straight from the level arrays;
//   3. faces by a recursive sweep of the tree: inside each interior node, the faces between its
//      children; across each shared side, the faces between the leaves of both sides; on the
//      domain boundary, one face per leaf. The sweep is cut into a few thousand independent items
//      (in a fixed order, so face ids do not depend on the thread count) run in parallel;
//   4. per-cell face lists in face-id order;
//   5. the level jump, by splitting the coarser cell of every face that breaks it (split_balanced
//      does the rest recursively), checking only faces of new cells after the first pass.
#include <omp.h>

#include <algorithm>
#include <numeric>

#include "liquid/core/error.hpp"
#include "liquid/tree/cell_graph.hpp"

namespace liquid::tree {

namespace {

using detail::side_child;

/// The recursive face sweep over a NodeIndex. Node entries: leaf cell id >= 0, interior < 0.
template <int Dim>
class FaceSweep {
 public:
  static constexpr int n_children = 1 << Dim;
  enum Kind : std::int8_t { inside, across, boundary };
  struct Item {
    Kind kind;
    std::int8_t axis;   // across, boundary
    std::int8_t upper;  // boundary: the node's upper side along axis
    std::int32_t a, b;  // across: a lower, b upper
  };
  static constexpr int max_parts = n_children + Dim * n_children / 2;

  FaceSweep(const detail::NodeIndex<Dim>& nodes, const std::vector<std::int8_t>& level)
      : nodes_(nodes), level_(level) {}

  bool splittable(const Item& it) const { return it.a < 0 || (it.kind == across && it.b < 0); }

  /// The sub-items of a splittable item.
  int parts(const Item& it, Item* out) const {
    int n = 0;
    if (it.kind == inside) {
      for (int i = 0; i < n_children; ++i) out[n++] = Item{inside, 0, 0, child(it.a, i), -1};
      for (int d = 0; d < Dim; ++d)
        for (int i = 0; i < n_children; ++i)
          if (!((i >> d) & 1))
            out[n++] =
                Item{across, static_cast<std::int8_t>(d), 0, child(it.a, i), child(it.a, i | (1 << d))};
    } else if (it.kind == across) {
      for (int j = 0; j < n_children / 2; ++j) {
        const std::int32_t a = it.a >= 0 ? it.a : child(it.a, side_child<Dim>(it.axis, 1, j));
        const std::int32_t b = it.b >= 0 ? it.b : child(it.b, side_child<Dim>(it.axis, 0, j));
        out[n++] = Item{across, it.axis, 0, a, b};
      }
    } else {
      for (int j = 0; j < n_children / 2; ++j)
        out[n++] = Item{boundary, it.axis, it.upper, child(it.a, side_child<Dim>(it.axis, it.upper, j)), -1};
    }
    return n;
  }

  /// Runs the sweep below `it`: with out == nullptr only counts the faces, else writes them.
  std::int64_t run(const Item& it, GraphFace* out) const {
    if (!splittable(it)) {
      if (it.kind == inside) return 0;  // a leaf has no inner faces
      if (out != nullptr) *out = emit(it);
      return 1;
    }
    Item sub[max_parts];
    const int n = parts(it, sub);
    std::int64_t count = 0;
    for (int i = 0; i < n; ++i) count += run(sub[i], out == nullptr ? nullptr : out + count);
    return count;
  }

 private:
  std::int32_t child(std::int32_t e, int i) const { return nodes_.block(-2 - e)[i]; }

  GraphFace emit(const Item& it) const {
    GraphFace f;
    f.axis = it.axis;
    if (it.kind == across) {
      f.cell = {it.a, it.b};
      f.side_level = {level_[it.a], level_[it.b]};
    } else {
      const int self = it.upper ? 0 : 1;
      f.cell[self] = it.a;
      f.side_level[self] = level_[it.a];
      f.boundary = static_cast<std::int8_t>(2 * it.axis + it.upper);
    }
    return f;
  }

  const detail::NodeIndex<Dim>& nodes_;
  const std::vector<std::int8_t>& level_;
};

}  // namespace

template <int Dim>
CellGraph<Dim> CellGraph<Dim>::build(const Box<Dim>& domain, const Predicate& refine,
                                     const CellGraphOptions<Dim>& options) {
  CellGraph g;
  g.domain_ = domain;
  g.options_ = options;
  g.init_levels();
  LIQUID_VERIFY(static_cast<bool>(refine), "CellGraph::build: the refinement predicate is empty");
  const auto split = [&](std::uint64_t key, int level) {
    if (level >= options.max_level) return false;
    if (level < options.min_level) return true;
    TreeNode<Dim> node;
    node.level = level;
    node.address = morton::key_address<Dim>(key);
    for (int d = 0; d < Dim; ++d) {
      node.box.lo[d] = domain.lo[d] + static_cast<double>(node.address[d]) * g.level_size_[level][d];
      node.box.hi[d] = domain.lo[d] + static_cast<double>(node.address[d] + 1) * g.level_size_[level][d];
    }
    return refine(node);
  };

  // 1. Nodes level by level; first_child[l][i] indexes level l+1, -1 for a leaf.
  std::vector<std::vector<std::uint64_t>> keys{{1}};
  std::vector<std::vector<std::int64_t>> first_child;
  for (int l = 0;; ++l) {
    const long n = static_cast<long>(keys[l].size());
    std::vector<std::int64_t> fc(n);
#pragma omp parallel for schedule(dynamic, 256) if (n > detail::parallel_min)
    for (long i = 0; i < n; ++i) fc[i] = split(keys[l][i], l) ? 1 : 0;
    std::int64_t count = 0;
    for (long i = 0; i < n; ++i) {
      const bool s = fc[i] != 0;
      fc[i] = s ? count : -1;
      count += s ? n_children : 0;
    }
    first_child.push_back(std::move(fc));
    if (count == 0) break;
    std::vector<std::uint64_t> next(count);
#pragma omp parallel for schedule(static) if (n > detail::parallel_min)
    for (long i = 0; i < n; ++i)
      if (first_child[l][i] >= 0)
        for (int c = 0; c < n_children; ++c)
          next[first_child[l][i] + c] = morton::child_key<Dim>(keys[l][i], c);
    keys.push_back(std::move(next));
  }
  const int n_levels = static_cast<int>(keys.size());

  // 2. Leaf counts bottom-up, then each node's first leaf id top-down (depth-first = Morton order).
  std::vector<std::vector<std::int64_t>> below(n_levels), first_leaf(n_levels);
  for (int l = n_levels - 1; l >= 0; --l) {
    const long n = static_cast<long>(keys[l].size());
    below[l].resize(n);
#pragma omp parallel for schedule(static) if (n > detail::parallel_min)
    for (long i = 0; i < n; ++i) {
      const std::int64_t fc = first_child[l][i];
      std::int64_t sum = 1;
      if (fc >= 0) {
        sum = 0;
        for (int c = 0; c < n_children; ++c) sum += below[l + 1][fc + c];
      }
      below[l][i] = sum;
    }
  }
  const std::int64_t n_cells = below[0][0];
  LIQUID_VERIFY(n_cells < INT32_MAX, "CellGraph::build: {} leaves exceed the 32-bit cell ids", n_cells);
  first_leaf[0] = {0};
  std::vector<std::int64_t> block_base(n_levels + 1, 0);  // first block id of each level's interior nodes
  for (int l = 0; l < n_levels; ++l)
    block_base[l + 1] =
        block_base[l] + (l + 1 < n_levels ? static_cast<std::int64_t>(keys[l + 1].size()) / n_children : 0);
  for (int l = 0; l + 1 < n_levels; ++l) {
    const long n = static_cast<long>(keys[l].size());
    first_leaf[l + 1].resize(keys[l + 1].size());
#pragma omp parallel for schedule(static) if (n > detail::parallel_min)
    for (long i = 0; i < n; ++i) {
      const std::int64_t fc = first_child[l][i];
      if (fc < 0) continue;
      std::int64_t at = first_leaf[l][i];
      for (int c = 0; c < n_children; ++c) {
        first_leaf[l + 1][fc + c] = at;
        at += below[l + 1][fc + c];
      }
    }
  }
  const auto entry = [&](int l, std::int64_t i) -> std::int32_t {
    const std::int64_t fc = first_child[l][i];
    return fc < 0 ? static_cast<std::int32_t>(first_leaf[l][i])
                  : static_cast<std::int32_t>(-2 - (block_base[l] + fc / n_children));
  };

  // Node index: one block per interior node, in level order.
  {
    std::vector<typename detail::NodeIndex<Dim>::Block> blocks(block_base[n_levels]);
    std::vector<std::uint64_t> interior(block_base[n_levels]);
    for (int l = 0; l + 1 < n_levels; ++l) {
      const long n = static_cast<long>(keys[l].size());
#pragma omp parallel for schedule(static) if (n > detail::parallel_min)
      for (long i = 0; i < n; ++i) {
        const std::int64_t fc = first_child[l][i];
        if (fc < 0) continue;
        const std::int64_t b = block_base[l] + fc / n_children;
        interior[b] = keys[l][i];
        for (int c = 0; c < n_children; ++c) blocks[b][c] = entry(l + 1, fc + c);
      }
    }
    g.nodes_.assign(entry(0, 0), std::move(blocks), interior);
  }

  // Cells.
  g.cells_.resize(n_cells);
  g.cell_birth_.assign(n_cells, 0);
  g.cell_log_index_.assign(n_cells, -1);
  std::vector<std::int8_t> level_of(n_cells);
  for (int l = 0; l < n_levels; ++l) {
    const long n = static_cast<long>(keys[l].size());
#pragma omp parallel for schedule(static) if (n > detail::parallel_min)
    for (long i = 0; i < n; ++i) {
      if (first_child[l][i] >= 0) continue;
      const std::int64_t c = first_leaf[l][i];
      CellData& cell = g.cells_[c];
      cell.key = keys[l][i];
      cell.level = static_cast<std::int8_t>(l);
      cell.address = morton::key_address<Dim>(keys[l][i]);
      cell.alive = true;
      level_of[c] = static_cast<std::int8_t>(l);
    }
    long n_leaves = 0;
    for (long i = 0; i < n; ++i) n_leaves += first_child[l][i] < 0 ? 1 : 0;
    g.n_at_level_[l] = n_leaves;
    if (n_leaves > 0) g.deepest_ = l;
  }
  g.n_cells_ = static_cast<int>(n_cells);
  keys.clear();
  below.clear();

  // 3. Faces by the sweep, cut into independent items.
  using Sweep = FaceSweep<Dim>;
  const Sweep sweep(g.nodes_, level_of);
  std::vector<typename Sweep::Item> items{{Sweep::inside, 0, 0, g.nodes_.root(), -1}};
  for (int d = 0; d < Dim; ++d)
    for (std::int8_t upper = 0; upper < 2; ++upper)
      items.push_back({Sweep::boundary, static_cast<std::int8_t>(d), upper, g.nodes_.root(), -1});
  const std::size_t enough = 256 * static_cast<std::size_t>(omp_get_max_threads()) + 1024;
  for (int round = 0; round < 16 && items.size() < enough; ++round) {
    std::vector<typename Sweep::Item> next;
    next.reserve(items.size() * Sweep::max_parts);
    bool any = false;
    typename Sweep::Item sub[Sweep::max_parts];
    for (const auto& it : items) {
      if (!sweep.splittable(it)) {
        next.push_back(it);
        continue;
      }
      any = true;
      const int n = sweep.parts(it, sub);
      next.insert(next.end(), sub, sub + n);
    }
    items.swap(next);
    if (!any) break;
  }
  // Count, place, then write each item's faces.
  std::vector<std::int64_t> at(items.size() + 1, 0);
  const long n_items = static_cast<long>(items.size());
#pragma omp parallel for schedule(dynamic, 1) if (n_cells > detail::parallel_min)
  for (long i = 0; i < n_items; ++i) at[i + 1] = sweep.run(items[i], nullptr);
  std::partial_sum(at.begin(), at.end(), at.begin());
  const std::int64_t n_faces = at.back();
  LIQUID_VERIFY(n_faces < INT32_MAX, "CellGraph::build: {} faces exceed the 32-bit face ids", n_faces);
  g.faces_.resize(n_faces);
#pragma omp parallel for schedule(dynamic, 1) if (n_cells > detail::parallel_min)
  for (long i = 0; i < n_items; ++i) sweep.run(items[i], g.faces_.data() + at[i]);
  g.face_alive_.assign(n_faces, 1);
  g.face_birth_.assign(n_faces, 0);
  g.face_log_index_.assign(n_faces, -1);
  g.n_faces_ = static_cast<int>(n_faces);

  // 4. Face lists, in face-id order.
  {
    std::vector<std::int32_t> degree(n_cells, 0);
    for (const GraphFace& f : g.faces_)
      for (int s = 0; s < 2; ++s)
        if (f.cell[s] != no_cell) ++degree[f.cell[s]];
#pragma omp parallel for schedule(static) if (static_cast <long>(n_cells) > detail::parallel_min)
    for (long c = 0; c < static_cast<long>(n_cells); ++c) g.cells_[c].faces.reserve(degree[c]);
  }
  for (FaceId f = 0; f < static_cast<FaceId>(n_faces); ++f) {
    GraphFace& face = g.faces_[f];
    for (int s = 0; s < 2; ++s) {
      if (face.cell[s] == no_cell) continue;
      auto& list = g.cells_[face.cell[s]].faces;
      face.slot[s] = list.size();
      list.push_back(f);
    }
  }

  // 5. Level jump.
  if (options.max_jump < options.max_level) {
    const int jump = options.max_jump;
    const auto coarser_if_broken = [&](FaceId f) -> CellId {
      const GraphFace& face = g.faces_[f];
      if (face.boundary >= 0 || std::abs(face.side_level[0] - face.side_level[1]) <= jump) return no_cell;
      return face.side_level[0] < face.side_level[1] ? face.cell[0] : face.cell[1];
    };
    std::vector<CellId> coarse;
    {
      std::vector<std::vector<CellId>> per_thread(omp_get_max_threads());
#pragma omp parallel for schedule(static) if (static_cast <long>(n_faces) > detail::parallel_min)
      for (long f = 0; f < static_cast<long>(n_faces); ++f) {
        const CellId c = coarser_if_broken(static_cast<FaceId>(f));
        if (c != no_cell) per_thread[omp_get_thread_num()].push_back(c);
      }
      for (auto& v : per_thread) coarse.insert(coarse.end(), v.begin(), v.end());
    }
    if (!coarse.empty()) {
      g.begin_change();
      AdaptReport counts;
      std::size_t checked = 0;
      while (!coarse.empty()) {
        std::sort(coarse.begin(), coarse.end());
        coarse.erase(std::unique(coarse.begin(), coarse.end()), coarse.end());
        for (CellId c : coarse)
          if (g.cells_[c].alive) g.split_balanced(c, counts);
        coarse.clear();
        // Only faces of cells created since the last pass can break the jump now.
        const std::size_t born = g.born_cells_.size();
        for (std::size_t i = checked; i < born; ++i) {
          const CellId c = g.born_cells_[i];
          if (!g.cells_[c].alive) continue;
          for (FaceId f : g.cells_[c].faces) {
            const CellId x = coarser_if_broken(f);
            if (x != no_cell) coarse.push_back(x);
          }
        }
        checked = born;
      }
      g.end_change(nullptr);
    }
  }
  return g;
}

template CellGraph<2> CellGraph<2>::build(const Box<2>&, const Predicate&, const CellGraphOptions<2>&);
template CellGraph<3> CellGraph<3>::build(const Box<3>&, const Predicate&, const CellGraphOptions<3>&);

}  // namespace liquid::tree
