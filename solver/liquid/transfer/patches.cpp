#include "liquid/transfer/patches.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

#include <fmt/format.h>

#include "liquid/core/error.hpp"
#include "liquid/core/parallel.hpp"
#include "liquid/transfer/face_stencil.hpp"
#include "liquid/transfer/regular.hpp"

namespace liquid::transfer {

namespace {

/// Position of offset o (each entry in {-1, 0, 1}) in a cell's 3^Dim block.
template <int Dim>
int block_index(const IVec<Dim>& o) {
  int i = 0, m = 1;
  for (int j = 0; j < Dim; ++j, m *= 3) i += static_cast<int>(o[j] + 1) * m;
  return i;
}

/// Position of the axis-k face at offset o in a cell's table: o_k in {0 (lower side), 1 (upper)} of
/// the cell at offset o (with o_k = 0), the other entries in {-1, 0, 1}.
template <int Dim>
int face_index(int k, const IVec<Dim>& o) {
  int i = static_cast<int>(o[k]), m = 2;
  for (int j = 0; j < Dim; ++j)
    if (j != k) i += static_cast<int>(o[j] + 1) * m, m *= 3;
  return i;
}

/// A point's multilinear stencil for component k, relative to the cell that holds it: corner 0 is
/// the axis-k face at offset `off` (off_k = 0, the cell's lower side; off_j in {-1, 0}); the
/// fractions and the clamped axes as the regular baselines' LinearStencil has them.
template <int Dim>
struct Local {
  IVec<Dim> off = IVec<Dim>::Zero();
  Vec<Dim> t = Vec<Dim>::Zero();
  std::array<bool, Dim> clamped{};

  Local(const Vec<Dim>& lo, const Vec<Dim>& h, const IVec<Dim>& a, long n, int k, const Vec<Dim>& x) {
    for (int j = 0; j < Dim; ++j) {
      const double s = (x[j] - lo[j]) / h[j];
      if (j == k) {
        t[j] = std::clamp(s, 0.0, 1.0);
        continue;
      }
      const double q = std::clamp(s - 0.5, -0.5, 0.5);  // from the cell's centre line
      if (q < 0.0) {
        if (a[j] == 0)
          off[j] = 0, t[j] = 0.0, clamped[j] = true;  // below the first lattice line: held on it
        else
          off[j] = -1, t[j] = q + 1.0;
      } else if (a[j] == n - 1) {
        off[j] = -1, t[j] = 1.0, clamped[j] = q > 0.0;  // beyond the last lattice line: held on it
      } else {
        off[j] = 0, t[j] = q;
      }
    }
  }
  double weight(int corner) const { return multilinear_weight<Dim>(t, corner); }
  Vec<Dim> gradient(int corner, const Vec<Dim>& h) const {
    return multilinear_gradient<Dim>(t, clamped, corner, h);
  }
};

/// A thread's buffers for tent_to_faces: the face's cells, the counts.
struct TentScratch {
  std::vector<tree::CellId> cells;
  TransferReport report;
};

/// Calls fn(o) for every offset of a 3^Dim block.
template <int Dim, class Fn>
void for_each_offset(Fn&& fn) {
  IVec<Dim> o = IVec<Dim>::Constant(-1);
  while (true) {
    fn(o);
    int j = 0;
    for (; j < Dim; ++j) {
      if (++o[j] <= 1) break;
      o[j] = -1;
    }
    if (j == Dim) return;
  }
}

/// Calls fn(q) for each in-domain cell of the two layers along k of a block (`blk`) that an axis-k
/// face's hat reaches: the block of the face's upper cell (`upper`), or of its lower cell at the
/// domain's upper wall.
template <int Dim, class Fn>
void for_each_hat_cell(int k, bool upper, const tree::CellId* blk, Fn&& fn) {
  for_each_offset<Dim>([&](const IVec<Dim>& o) {
    if (o[k] != (upper ? -1 : 0) && o[k] != (upper ? 0 : 1)) return;
    const tree::CellId q = blk[block_index<Dim>(o)];
    if (q != tree::no_cell) fn(q);
  });
}

}  // namespace

template <int Dim>
UniformPatches<Dim>::UniformPatches(const tree::CellGraph<Dim>& graph, std::span<const tree::CellId> cells)
    : graph_(&graph) {
  const long m = static_cast<long>(cells.size());
  std::vector<tree::CellId> blocks(static_cast<std::size_t>(m) * block, tree::no_cell);
  std::vector<std::uint8_t> ok(m, 0);
  parallel_for(
      m,
      [&](long i) {
        const tree::CellId c = cells[i];
        LIQUID_VERIFY(graph.alive(c), "UniformPatches: cell {} is not alive", c);
        const int level = graph.level(c);
        if (level < 1) return;
        const long n = 1L << level;
        const IVec<Dim> a = graph.address(c);
        bool regular = true;
        for_each_offset<Dim>([&](const IVec<Dim>& o) {
          if (!regular) return;
          const IVec<Dim> b = a + o;
          for (int j = 0; j < Dim; ++j)
            if (b[j] < 0 || b[j] >= n) return;  // outside the domain: a wall, no cell
          const tree::CellId q = graph.find(level, b);
          if (q == tree::no_cell) regular = false;
          blocks[i * block + block_index<Dim>(o)] = q;
        });
        ok[i] = regular;
      },
      256);
  slot_.assign(graph.cell_capacity(), -1);
  for (long i = 0; i < m; ++i) {
    const tree::CellId c = cells[i];
    if (!ok[i] || slot_[c] >= 0) continue;
    slot_[c] = static_cast<std::int32_t>(cells_.size());
    cells_.push_back(c);
    blocks_.insert(blocks_.end(), blocks.begin() + i * block, blocks.begin() + (i + 1) * block);
  }
  // Each cell of the blocks' side faces, found once (a cell lies in up to 3^Dim blocks): per side
  // 2k + (0 lower, 1 upper), the face and how many faces the side has (one inside a patch).
  std::vector<std::int32_t> at(graph.cell_capacity(), -1);
  std::vector<tree::CellId> members;
  for (tree::CellId q : blocks_)
    if (q != tree::no_cell && at[q] < 0)
      at[q] = static_cast<std::int32_t>(members.size()), members.push_back(q);
  constexpr int n_sides = 2 * Dim;
  std::vector<tree::FaceId> side_face(members.size() * n_sides, tree::no_face);
  std::vector<std::uint8_t> side_count(members.size() * n_sides, 0);
  parallel_for(
      static_cast<long>(members.size()),
      [&](long i) {
        const tree::CellId q = members[i];
        for (tree::FaceId f : graph.faces(q)) {
          const tree::GraphFace& g = graph.face(f);
          const int side = 2 * g.axis + (g.cell[0] == q ? 1 : 0);  // q below the face: its upper side
          side_face[i * n_sides + side] = f;
          side_count[i * n_sides + side] =
              static_cast<std::uint8_t>(std::min(side_count[i * n_sides + side] + 1, 255));
        }
      },
      512);
  faces_table_.assign(cells_.size() * Dim * axis_faces, tree::no_face);
  parallel_for(
      n_cells(),
      [&](long s) {
        for (int k = 0; k < Dim; ++k)
          for_each_offset<Dim>([&](const IVec<Dim>& o) {
            if (o[k] != 0) return;
            const tree::CellId q = blocks_[s * block + block_index<Dim>(o)];
            if (q == tree::no_cell) return;
            const long first = static_cast<long>(at[q]) * n_sides;
            for (int side = 0; side < 2; ++side) {
              const int found = side_count[first + 2 * k + side];
              LIQUID_VERIFY(found == 1, "UniformPatches: cell {} has {} faces on side {}{} inside a patch", q,
                            found, side ? '+' : '-', k);
              IVec<Dim> oo = o;
              oo[k] = side;
              faces_table_[(s * Dim + k) * axis_faces + face_index<Dim>(k, oo)] =
                  side_face[first + 2 * k + side];
            }
          });
      },
      256);
  face_.assign(graph.face_capacity(), 0);
  for (tree::CellId c : cells_)
    for (tree::FaceId f : graph.faces(c)) {
      if (face_[f]) continue;
      bool all = true;
      for (tree::CellId side : graph.face(f).cell) all = all && (side == tree::no_cell || cell(side));
      if (all) face_[f] = 1;
    }
  for (tree::FaceId f = 0; f < graph.face_capacity(); ++f)
    if (face_[f]) faces_.push_back(f);
  // Rim faces: the hat reaches a cell (of the same level, in a patch cell's block) that is not a
  // patch cell, whose particles the scatter does not visit.
  std::vector<std::uint8_t> rim(faces_.size(), 0);
  parallel_for(
      n_faces(),
      [&](long i) {
        const tree::FaceId f = faces_[i];
        const tree::GraphFace& g = graph.face(f);
        const int k = g.axis;
        const bool upper = g.cell[1] != tree::no_cell;
        const tree::CellId ref = upper ? g.cell[1] : g.cell[0];
        const tree::CellId* blk = blocks_.data() + static_cast<long>(slot_[ref]) * block;
        bool on_rim = false;
        for_each_hat_cell<Dim>(k, upper, blk, [&](tree::CellId q) { on_rim = on_rim || !cell(q); });
        rim[i] = on_rim;
      },
      1024);
  for (long i = 0; i < n_faces(); ++i)
    if (rim[i]) face_[faces_[i]] = 2, ++n_rim_;
  // The scatter's groups: (colour, level, slab), cells in slot order within a group.
  constexpr int top = Dim - 1;
  struct Key {
    int colour, level;
    long slab;
    std::int32_t slot;
    bool operator<(const Key& o) const {
      return std::tie(colour, level, slab, slot) < std::tie(o.colour, o.level, o.slab, o.slot);
    }
  };
  std::vector<Key> keys(cells_.size());
  for (std::size_t i = 0; i < cells_.size(); ++i) {
    const long slab = graph.address(cells_[i])[top] / 2;
    keys[i] = {static_cast<int>(slab % 2), graph.level(cells_[i]), slab, static_cast<std::int32_t>(i)};
  }
  std::sort(keys.begin(), keys.end());
  group_slots_.resize(keys.size());
  for (std::size_t i = 0; i < keys.size(); ++i) {
    group_slots_[i] = keys[i].slot;
    const bool starts = i == 0 || keys[i].colour != keys[i - 1].colour ||
                        keys[i].level != keys[i - 1].level || keys[i].slab != keys[i - 1].slab;
    if (starts) colours_[keys[i].colour].push_back({static_cast<long>(i), static_cast<long>(i)});
    colours_[keys[i].colour].back().second = static_cast<long>(i) + 1;
  }
}

template <int Dim>
Vec<Dim> UniformPatches<Dim>::value(tree::CellId c, const Vec<Dim>& x, std::span<const double> u,
                                    double* affine) const {
  const std::int32_t s = slot_[c];
  const int level = graph_->level(c);
  const long n = 1L << level;
  const IVec<Dim>& a = graph_->address(c);
  const Vec<Dim> lo = graph_->box(c).lo, h = graph_->cell_size(c);
  Vec<Dim> v;
  for (int k = 0; k < Dim; ++k) {
    const Local<Dim> st(lo, h, a, n, k, x);
    const tree::FaceId* table = faces_table_.data() + (static_cast<long>(s) * Dim + k) * axis_faces;
    double value = 0.0;
    Vec<Dim> grad = Vec<Dim>::Zero();
    for (int corner = 0; corner < (1 << Dim); ++corner) {
      IVec<Dim> o = st.off;
      for (int j = 0; j < Dim; ++j) o[j] += (corner >> j) & 1;
      const tree::FaceId f = table[face_index<Dim>(k, o)];
      if (f == tree::no_face) continue;  // a lattice line past a wall; its weight is 0
      value += st.weight(corner) * u[f];
      if (affine) grad += st.gradient(corner, h) * u[f];
    }
    v[k] = value;
    if (affine)
      for (int j = 0; j < Dim; ++j) affine[k * Dim + j] = grad[j];
  }
  return v;
}

template <int Dim>
void UniformPatches<Dim>::check_inputs(const particles::Particles<Dim>& particles,
                                       const particles::CellBins& bins, std::span<const double> affine,
                                       const FaceValues& out) const {
  LIQUID_VERIFY(bins.n_particles() == particles.size(),
                "UniformPatches: bins hold {} particles, there are {}", bins.n_particles(), particles.size());
  LIQUID_VERIFY(affine.empty() || affine.size() == static_cast<std::size_t>(particles.size()) * Dim * Dim,
                "UniformPatches: affine field of {} doubles for {} particles", affine.size(),
                particles.size());
  LIQUID_VERIFY(static_cast<int>(out.value.size()) >= graph_->face_capacity(),
                "UniformPatches: {} face values for {} face ids", out.value.size(), graph_->face_capacity());
}

template <int Dim>
void UniformPatches<Dim>::gather_face(long i, const particles::Particles<Dim>& particles,
                                      const particles::CellBins& bins, std::span<const double> affine,
                                      FaceValues& out, TransferReport& r, double sum, double mass,
                                      bool outside_only) const {
  const tree::CellGraph<Dim>& graph = *graph_;
  const tree::FaceId f = faces_[i];
  const tree::GraphFace& g = graph.face(f);
  const int k = g.axis;
  // The face is the lower axis-k side of its upper cell, or the upper side of its lower cell at the
  // domain's upper wall; the particles its hat reaches are in the two layers of that cell's block
  // along k.
  const bool upper = g.cell[1] != tree::no_cell;
  const tree::CellId ref = upper ? g.cell[1] : g.cell[0];
  IVec<Dim> af = graph.address(ref);
  if (!upper) ++af[k];
  const int level = graph.level(ref);
  const long n = 1L << level;
  const Vec<Dim> xf = graph.face_centre(f);
  const Vec<Dim> h = graph.cell_size(ref);
  const tree::CellId* blk = blocks_.data() + static_cast<long>(slot_[ref]) * block;
  for_each_hat_cell<Dim>(k, upper, blk, [&](tree::CellId q) {
    if (outside_only && cell(q)) return;  // the scatter brought this cell's particles
    const IVec<Dim>& aq = graph.address(q);
    const Vec<Dim> lo = graph.box(q).lo;
    for (std::int32_t p : bins.of(q)) {
      const Vec<Dim>& xp = particles.x[p];
      const Local<Dim> st(lo, h, aq, n, k, xp);
      int corner = 0;
      bool inside = true;
      for (int j = 0; j < Dim; ++j) {
        const long d = af[j] - aq[j] - st.off[j];
        inside = inside && (d == 0 || d == 1);
        corner |= static_cast<int>(d & 1) << j;
      }
      if (!inside) continue;
      const double w = st.weight(corner);
      if (w == 0.0) continue;
      double value = particles.v[p][k];
      if (!affine.empty())
        for (int j = 0; j < Dim; ++j) value += affine[(p * Dim + k) * Dim + j] * (xf[j] - xp[j]);
      sum += w * value;
      mass += w;
    }
  });
  store_mean(out, f, sum, mass, r);
}

template <int Dim>
TransferReport UniformPatches<Dim>::to_faces_gather(const particles::Particles<Dim>& particles,
                                                    const particles::CellBins& bins,
                                                    std::span<const double> affine, FaceValues& out) const {
  check_inputs(particles, bins, affine, out);
  TransferReport total;
  parallel_for(
      n_faces(), [] { return TransferReport{}; },
      [&](TransferReport& r, long i) { gather_face(i, particles, bins, affine, out, r, 0.0, 0.0, false); },
      [&](TransferReport& r) { total += r; }, 256);
  total.max_degree_used = 1;
  return total;
}

template <int Dim>
TransferReport UniformPatches<Dim>::to_faces(const particles::Particles<Dim>& particles,
                                             const particles::CellBins& bins, std::span<const double> affine,
                                             FaceValues& out) const {
  check_inputs(particles, bins, affine, out);
  const tree::CellGraph<Dim>& graph = *graph_;
  // Sums and masses per face id, of the scattered faces only. A particle in a cell of slab z (along
  // the last axis, at its level) reaches faces of the cells z - 1 .. z + 1 of that level, so groups
  // of one colour (slabs two apart, any level: the faces of different levels differ) never share
  // a face.
  std::vector<std::array<double, 2>> acc(graph.face_capacity(), {0.0, 0.0});  // sum, mass
  for (int colour = 0; colour < 2; ++colour) {
    const auto& groups = colours_[colour];
    parallel_for(
        static_cast<long>(groups.size()),
        [&](long gi) {
          for (long i = groups[gi].first; i < groups[gi].second; ++i) {
            const std::int32_t s = group_slots_[i];
            const tree::CellId c = cells_[s];
            const int level = graph.level(c);
            const long n = 1L << level;
            const IVec<Dim>& a = graph.address(c);
            const Vec<Dim> lo = graph.box(c).lo, h = graph.cell_size(c);
            for (std::int32_t p : bins.of(c)) {
              const Vec<Dim>& xp = particles.x[p];
              for (int k = 0; k < Dim; ++k) {
                const Local<Dim> st(lo, h, a, n, k, xp);
                const tree::FaceId* table =
                    faces_table_.data() + (static_cast<long>(s) * Dim + k) * axis_faces;
                for (int corner = 0; corner < (1 << Dim); ++corner) {
                  IVec<Dim> o = st.off;
                  for (int j = 0; j < Dim; ++j) o[j] += (corner >> j) & 1;
                  const tree::FaceId f = table[face_index<Dim>(k, o)];
                  if (f == tree::no_face || face_[f] == 0) continue;  // past a wall, or not a patch face
                  const double w = st.weight(corner);
                  if (w == 0.0) continue;
                  double value = particles.v[p][k];
                  if (!affine.empty())
                    for (int j = 0; j < Dim; ++j) {
                      // The face's centre on c's lattice: o_k is its side, the other axes the
                      // middle of the cell at offset o.
                      const double xf = lo[j] + h[j] * (static_cast<double>(o[j]) + (j == k ? 0.0 : 0.5));
                      value += affine[(p * Dim + k) * Dim + j] * (xf - xp[j]);
                    }
                  acc[f][0] += w * value;
                  acc[f][1] += w;
                }
              }
            }
          }
        },
        1);
  }
  TransferReport total;
  parallel_for(
      n_faces(), [] { return TransferReport{}; },
      [&](TransferReport& r, long i) {
        const tree::FaceId f = faces_[i];
        // A rim face adds the particles of its hat's cells outside the patches to the scattered sums.
        if (face_[f] == 2) return gather_face(i, particles, bins, affine, out, r, acc[f][0], acc[f][1], true);
        store_mean(out, f, acc[f][0], acc[f][1], r);
      },
      [&](TransferReport& r) { total += r; }, 1024);
  total.max_degree_used = 1;
  return total;
}

template <int Dim>
TransferReport tent_to_faces(const tree::CellGraph<Dim>& graph, const particles::Particles<Dim>& particles,
                             const particles::CellBins& bins, std::span<const double> affine,
                             std::span<const std::uint8_t> skip, FaceValues& out) {
  TransferReport total;
  parallel_for(
      graph.face_capacity(), [] { return TentScratch{}; },
      [&](TentScratch& st, long fl) {
        const tree::FaceId f = static_cast<tree::FaceId>(fl);
        if (!graph.face_alive(f) || skip[f]) return;
        const tree::GraphFace& g = graph.face(f);
        const int k = g.axis;
        const Vec<Dim> xf = graph.face_centre(f);
        tree::CellId fine = g.side_level[0] >= g.side_level[1] ? g.cell[0] : g.cell[1];
        const Vec<Dim> h = graph.cell_size(fine);
        // The face's cells and their face neighbours, once each, in id order; of those, the cells
        // whose box meets the inside of the tent's support (the others hold no weight).
        std::vector<tree::CellId>& cells = st.cells;
        face_neighbourhood<Dim>(graph, f, cells);
        double sum = 0.0, mass = 0.0;
        for (tree::CellId q : cells) {
          const Box<Dim> b = graph.box(q);
          bool meets = true;
          for (int j = 0; j < Dim; ++j) meets = meets && b.lo[j] < xf[j] + h[j] && b.hi[j] > xf[j] - h[j];
          if (!meets) continue;
          for (std::int32_t p : bins.of(q)) {
            const Vec<Dim>& xp = particles.x[p];
            double w = 1.0;
            for (int j = 0; j < Dim && w > 0.0; ++j) w *= std::max(0.0, 1.0 - std::abs(xp[j] - xf[j]) / h[j]);
            if (w <= 0.0) continue;
            double value = particles.v[p][k];
            if (!affine.empty())
              for (int j = 0; j < Dim; ++j) value += affine[(p * Dim + k) * Dim + j] * (xf[j] - xp[j]);
            sum += w * value;
            mass += w;
          }
        }
        ++st.report.targets;
        if (mass > 0.0) {
          out.value[f] = sum / mass, out.known[f] = 1, out.weight[f] = mass;
        } else {
          ++st.report.empty;
        }
      },
      [&](TentScratch& st) { total += st.report; }, 256);
  return total;
}
template <int Dim>
long blend_tent_mean(const tree::CellGraph<Dim>& graph, const particles::Particles<Dim>& particles,
                     const particles::CellBins& bins, std::span<const std::uint8_t> skip, double share,
                     FaceValues& out) {
  LIQUID_VERIFY(share >= 0.0 && share <= 1.0, "the tents' share {} is outside [0, 1]", share);
  if (share == 0.0) return 0;
  const long n = graph.face_capacity();
  std::vector<std::uint8_t> left(n, 1);  // the faces tent_to_faces leaves: skipped or not known
  for (long f = 0; f < n; ++f) left[f] = skip[f] || !out.known[f];
  FaceValues tents;
  tents.reset(static_cast<int>(n));
  tent_to_faces<Dim>(graph, particles, bins, {}, left, tents);
  long blended = 0;
  for (long f = 0; f < n; ++f)
    if (tents.known[f]) {
      out.value[f] += share * (tents.value[f] - out.value[f]);
      ++blended;
    }
  return blended;
}

template long blend_tent_mean<2>(const tree::CellGraph<2>&, const particles::Particles<2>&,
                                 const particles::CellBins&, std::span<const std::uint8_t>, double,
                                 FaceValues&);
template long blend_tent_mean<3>(const tree::CellGraph<3>&, const particles::Particles<3>&,
                                 const particles::CellBins&, std::span<const std::uint8_t>, double,
                                 FaceValues&);

template TransferReport tent_to_faces<2>(const tree::CellGraph<2>&, const particles::Particles<2>&,
                                         const particles::CellBins&, std::span<const double>,
                                         std::span<const std::uint8_t>, FaceValues&);
template TransferReport tent_to_faces<3>(const tree::CellGraph<3>&, const particles::Particles<3>&,
                                         const particles::CellBins&, std::span<const double>,
                                         std::span<const std::uint8_t>, FaceValues&);

template <int Dim>
Eigen::Matrix<double, Dim, Dim> patch_inertia(const tree::CellGraph<Dim>& graph, tree::CellId c, int k,
                                              const Vec<Dim>& x) {
  const int level = graph.level(c);
  LIQUID_VERIFY(level >= 1, "patch_inertia: cell {} is the root; a lattice needs level 1 or finer", c);
  const IVec<Dim>& a = graph.address(c);
  const Vec<Dim> lo = graph.box(c).lo, h = graph.cell_size(c);
  const Local<Dim> st(lo, h, a, 1L << level, k, x);
  Eigen::Matrix<double, Dim, Dim> d = Eigen::Matrix<double, Dim, Dim>::Zero();
  for (int corner = 0; corner < (1 << Dim); ++corner) {
    Vec<Dim> xf;
    for (int j = 0; j < Dim; ++j)
      xf[j] = lo[j] + h[j] * (static_cast<double>(st.off[j] + ((corner >> j) & 1)) + (j == k ? 0.0 : 0.5));
    const Vec<Dim> r = xf - x;
    d += st.weight(corner) * r * r.transpose();
  }
  return d;
}

template class UniformPatches<2>;
template class UniformPatches<3>;
template Eigen::Matrix<double, 2, 2> patch_inertia<2>(const tree::CellGraph<2>&, tree::CellId, int,
                                                      const Vec<2>&);
template Eigen::Matrix<double, 3, 3> patch_inertia<3>(const tree::CellGraph<3>&, tree::CellId, int,
                                                      const Vec<3>&);

}  // namespace liquid::transfer
