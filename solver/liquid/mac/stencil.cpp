#include "liquid/mac/stencil.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "liquid/core/error.hpp"
#include "liquid/rbf/polynomial.hpp"

namespace liquid::mac {

StencilRule parse_stencil_rule(const std::string& name) {
  if (name == "nearest") return StencilRule::nearest;
  if (name == "face-grown") return StencilRule::face_grown;
  if (name == "ring") return StencilRule::ring;
  throw Error("unknown stencil rule '" + name + "'; choose nearest, face-grown or ring");
}

const char* to_string(StencilRule rule) {
  switch (rule) {
    case StencilRule::nearest:
      return "nearest";
    case StencilRule::face_grown:
      return "face-grown";
    case StencilRule::ring:
      return "ring";
  }
  return "unknown";
}

int stencil_size(int dim, int degree, double growth) {
  LIQUID_VERIFY(growth > 0.0 && growth <= 64.0, "stencil growth {} must be in (0, 64]", growth);
  return static_cast<int>(std::ceil(growth * rbf::n_polynomial_terms(dim, degree))) + 1;
}

namespace {

// Candidate cells around the seeds, by rule; duplicates removed, seeds first.
template <int Dim>
void candidates(const tree::CellGraph<Dim>& graph, std::span<const tree::CellId> seeds, const Vec<Dim>& at,
                StencilRule rule, int n_target, std::vector<tree::CellId>& out, std::size_t& n_core) {
  thread_local std::vector<tree::CellId> ring;
  thread_local std::vector<std::pair<double, tree::CellId>> keyed;
  out.clear();
  n_core = 0;
  auto add_ring = [&](int k) {
    if (seeds.size() == 1) {  // one k-ring: already without duplicates, and it holds every smaller ring
      graph.k_ring(seeds[0], k, out);
      return;
    }
    for (tree::CellId s : seeds) {
      graph.k_ring(s, k, ring);
      out.insert(out.end(), ring.begin(), ring.end());
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  };
  // Nearest first, ties by id: each centre's distance once, not once per comparison.
  auto sort_by_distance = [&](std::vector<tree::CellId>::iterator first,
                              std::vector<tree::CellId>::iterator last) {
    keyed.clear();
    for (auto it = first; it != last; ++it) keyed.emplace_back((graph.centre(*it) - at).squaredNorm(), *it);
    std::sort(keyed.begin(), keyed.end());
    for (const auto& [d, c] : keyed) *first++ = c;
  };
  const int max_k = 6;
  switch (rule) {
    case StencilRule::ring: {
      // Laplacian stencils (one seed) also need half the target counted by the area of a side
      // the cells cover: a cell j levels finer than the centre counts 2^(-(Dim-1) j), so the
      // 2^((Dim-1) j) cells behind one finer side count as one neighbour. By the plain count alone
      // a 3D cell with a side two levels finer stops at its 1-ring (1 + 5 + 16 = 22 >= 21 nodes):
      // 16 nodes on one side, one on each other side, a lopsided row with a large truncation error.
      // Face stencils keep the plain count.
      const bool by_area = seeds.size() == 1;
      const int ref_level = graph.level(seeds[0]);
      for (int k = 1; k <= max_k; ++k) {
        add_ring(k);
        if (static_cast<int>(out.size()) < n_target) continue;
        if (!by_area) break;
        double area = 0.0;
        for (tree::CellId c : out)
          area += std::ldexp(1.0, -(Dim - 1) * std::max(0, graph.level(c) - ref_level));
        if (2.0 * area >= n_target) break;
      }
      sort_by_distance(out.begin(), out.end());
      return;
    }
    case StencilRule::nearest: {
      for (int k = 2; k <= max_k; ++k) {
        add_ring(k);
        if (static_cast<int>(out.size()) >= 2 * n_target) break;
      }
      sort_by_distance(out.begin(), out.end());
      return;
    }
    case StencilRule::face_grown: {
      add_ring(1);
      sort_by_distance(out.begin(), out.end());
      n_core = out.size();
      if (static_cast<int>(out.size()) >= n_target) return;
      std::vector<tree::CellId> first(out.begin(), out.end());
      for (int k = 2; k <= max_k; ++k) {
        add_ring(k);
        if (static_cast<int>(out.size()) >= n_target) break;
      }
      std::vector<tree::CellId> first_by_id = first, rest;
      std::sort(first_by_id.begin(), first_by_id.end());
      for (tree::CellId c : out)
        if (!std::binary_search(first_by_id.begin(), first_by_id.end(), c)) rest.push_back(c);
      sort_by_distance(rest.begin(), rest.end());
      out = first;
      out.insert(out.end(), rest.begin(), rest.end());
      return;
    }
  }
}

}  // namespace

template <int Dim>
void gather_stencil(const tree::CellGraph<Dim>& graph, const DofLayout<Dim>& layout,
                    const Boundary<Dim>& boundary, std::span<const tree::CellId> seeds, const Vec<Dim>& at,
                    StencilRule rule, int n_target, int n_cap, std::vector<StencilNode<Dim>>& out) {
  LIQUID_ASSERT(!seeds.empty(), "gather_stencil needs a seed cell");
  LIQUID_ASSERT(n_cap == 0 || n_cap >= n_target, "stencil cap {} below its target {}", n_cap, n_target);
  thread_local std::vector<tree::CellId> cells;
  std::size_t n_core_cells = 0, n_core_nodes = 0;
  candidates(graph, seeds, at, rule, n_target, cells, n_core_cells);
  out.clear();
  const Box<Dim>& domain = graph.domain();
  const Vec<Dim> anchor = graph.centre(seeds[0]);
  for (std::size_t i = 0; i < cells.size(); ++i) {
    if (i == n_core_cells) n_core_nodes = out.size();
    const tree::CellId c = cells[i];
    const int dof = layout.dof_of_cell[c];
    const Vec<Dim> x = graph.centre(c);
    if (dof < 0) {
      // An air cell next to an unknown: a Dirichlet node at its centre. Air cells further out are
      // not the boundary (p there is not the continuation of p inside) and are left out, as cells
      // behind the interface are in the level-set case.
      if (boundary.air_cells()) {
        bool touches = false;
        for (tree::FaceId f : graph.faces(c)) {
          const tree::GraphFace& g = graph.face(f);
          const tree::CellId o = g.cell[0] == c ? g.cell[1] : g.cell[0];
          if (o != tree::no_cell && layout.dof_of_cell[o] >= 0) {
            touches = true;
            break;
          }
        }
        if (touches) out.push_back({x, -1, boundary.dirichlet(x)});
        continue;
      }
      // Outside the liquid: the interface point on the segment from the anchor carries the value.
      if (!boundary.levelset) continue;
      const double phi_a = boundary.levelset(anchor), phi_x = boundary.levelset(x);
      const auto cut = levelset::crossing<Dim>(boundary.levelset, anchor, x, phi_a, phi_x);
      if (!cut) continue;  // the segment leaves and re-enters: this cell is not seen from the anchor
      out.push_back({cut->point, -1, boundary.dirichlet(cut->point)});
      continue;
    }
    out.push_back({x, dof, 0.0});
    // Mirror images across the Neumann walls this cell touches (and the corner images), or with
    // Dirichlet walls the projections onto them, carrying the wall value.
    const Box<Dim> b = graph.box(c);
    std::array<int, Dim> touch{};
    for (int k = 0; k < Dim; ++k) touch[k] = b.lo[k] <= domain.lo[k] ? -1 : (b.hi[k] >= domain.hi[k] ? 1 : 0);
    for (int mask = 1; mask < (1 << Dim); ++mask) {
      // g: the image; m: x projected onto the walls crossed (where the image's flux is taken).
      Vec<Dim> g = x, m = x;
      bool ok = true;
      for (int k = 0; k < Dim && ok; ++k) {
        if (!(mask >> k & 1)) continue;
        if (touch[k] == 0) {
          ok = false;
          continue;
        }
        m[k] = touch[k] < 0 ? domain.lo[k] : domain.hi[k];
        g[k] = boundary.dirichlet_walls ? m[k] : 2.0 * m[k] - x[k];
      }
      if (!ok) continue;
      if (boundary.dirichlet_walls) {
        out.push_back({g, -1, boundary.dirichlet(g)});
        continue;
      }
      // p(g) - p(x) = grad p(m) . (g - x) + O(|g - x|^3), and (g - x) is 2 |x_k - m_k| along each
      // outward normal crossed.
      double offset = 0.0;
      for (int k = 0; k < Dim; ++k)
        if (mask >> k & 1) offset += std::abs(g[k] - x[k]) * boundary.flux(m, k, touch[k]);
      out.push_back({g, dof, offset});
    }
  }
  // A crossing point within 1e-3 cell sizes of another node adds nothing but a near-singular
  // system: drop it (the node beside it already sits at the interface to that accuracy).
  if (boundary.levelset) {
    const double tol2 = std::pow(1e-3 * graph.cell_size(seeds[0]).maxCoeff(), 2);
    std::vector<StencilNode<Dim>> kept;
    for (std::size_t a = 0; a < out.size(); ++a) {
      bool drop = false;
      if (out[a].dof < 0)
        for (std::size_t b = 0; b < out.size() && !drop; ++b)
          drop = b != a && (out[b].dof >= 0 || b < a) && (out[a].x - out[b].x).squaredNorm() < tol2;
      if (!drop) kept.push_back(out[a]);
    }
    out.swap(kept);
  }
  // `ring` keeps whole rings (up to n_cap); `face_grown` keeps its candidate order (face neighbours
  // first); `nearest` keeps the nearest nodes. Both nearest-first cuts keep everything tied with the
  // last kept node, so that symmetric layouts stay symmetric.
  const int n_keep = rule == StencilRule::ring ? n_cap : n_target;
  if (n_keep <= 0 || static_cast<int>(out.size()) <= n_keep) return;
  if (rule == StencilRule::face_grown) {
    if (n_core_cells >= cells.size()) n_core_nodes = out.size();
    out.resize(std::max<std::size_t>(n_target, n_core_nodes));
    return;
  }
  std::stable_sort(out.begin(), out.end(), [&](const StencilNode<Dim>& a, const StencilNode<Dim>& b) {
    return (a.x - at).squaredNorm() < (b.x - at).squaredNorm();
  });
  const double cut = (out[n_keep - 1].x - at).squaredNorm() * (1.0 + 1e-9);
  std::size_t keep = n_keep;
  while (keep < out.size() && (out[keep].x - at).squaredNorm() <= cut) ++keep;
  out.resize(keep);
}

template <int Dim>
rbf::Status stencil_weights(std::vector<StencilNode<Dim>>& nodes, const Vec<Dim>& at,
                            const rbf::Operator<Dim>& op, const rbf::Config& config, std::vector<double>& w,
                            long& n_retried, rbf::WeightCache<Dim>* cache, double h) {
  thread_local std::vector<Vec<Dim>> xs;
  thread_local std::vector<int> order;
  thread_local std::vector<StencilNode<Dim>> sorted;
  const auto positions = [&] {
    xs.clear();
    for (const auto& n : nodes) xs.push_back(n.x);
  };
  if (cache != nullptr) {
    // Weights follow their nodes, so the caller is unaffected, except that a retry below then
    // drops the farthest node by distance rather than the last one gathered.
    positions();
    rbf::canonical_order<Dim>(xs, at, h, order);
    sorted.clear();
    for (int j : order) sorted.push_back(nodes[j]);
    nodes.swap(sorted);
  }
  const auto solve = [&] {
    positions();
    return cache != nullptr ? cache->weights(xs, at, h, op, config, w)
                            : rbf::weights<Dim>(xs, at, op, config, w);
  };
  // An interface passing a few thousandths of a cell from the anchor puts the crossings of many
  // segments within a hundredth of a cell of each other: a cluster of nearly equal known nodes that
  // no drop of the farthest node cures. A singular system first loses the known node of its closest
  // pair, while that pair is closer than a tenth of the stencil's scale; then the farthest nodes.
  const double scale = h > 0.0 ? h : (nodes.empty() ? 0.0 : (nodes.back().x - at).norm());
  const auto clustered_known_node = [&]() -> std::ptrdiff_t {
    double best = std::pow(0.1 * scale, 2);
    std::ptrdiff_t drop = -1;
    for (std::size_t a = 0; a < nodes.size(); ++a)
      for (std::size_t b = 0; b < a; ++b) {
        if (nodes[a].dof >= 0 && nodes[b].dof >= 0) continue;
        const double d2 = (nodes[a].x - nodes[b].x).squaredNorm();
        if (d2 < best) {
          best = d2;
          drop = static_cast<std::ptrdiff_t>(nodes[a].dof < 0 ? a : b);
        }
      }
    return drop;
  };
  int farthest_drops = 0;
  for (;;) {
    const rbf::Status st = solve();
    if (st.usable()) return st;
    if (st.info == rbf::Info::coincident_nodes && st.node_b > 0 && farthest_drops < 4) {
      nodes.erase(nodes.begin() + st.node_b);  // keep the nearer of the two
      ++farthest_drops;
    } else if (st.info == rbf::Info::singular_system && nodes.size() > 2) {
      if (const std::ptrdiff_t k = clustered_known_node(); k >= 0) {
        nodes.erase(nodes.begin() + k);
      } else if (farthest_drops < 4) {
        nodes.pop_back();  // drop the farthest node
        ++farthest_drops;
      } else {
        return st;
      }
    } else {
      return st;
    }
    ++n_retried;
  }
}

template void gather_stencil<2>(const tree::CellGraph<2>&, const DofLayout<2>&, const Boundary<2>&,
                                std::span<const tree::CellId>, const Vec<2>&, StencilRule, int, int,
                                std::vector<StencilNode<2>>&);
template void gather_stencil<3>(const tree::CellGraph<3>&, const DofLayout<3>&, const Boundary<3>&,
                                std::span<const tree::CellId>, const Vec<3>&, StencilRule, int, int,
                                std::vector<StencilNode<3>>&);
template rbf::Status stencil_weights<2>(std::vector<StencilNode<2>>&, const Vec<2>&, const rbf::Operator<2>&,
                                        const rbf::Config&, std::vector<double>&, long&, rbf::WeightCache<2>*,
                                        double);
template rbf::Status stencil_weights<3>(std::vector<StencilNode<3>>&, const Vec<3>&, const rbf::Operator<3>&,
                                        const rbf::Config&, std::vector<double>&, long&, rbf::WeightCache<3>*,
                                        double);

}  // namespace liquid::mac
