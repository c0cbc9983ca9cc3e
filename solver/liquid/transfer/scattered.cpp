#include "liquid/transfer/scattered.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <utility>

#include <fmt/format.h>

#include "liquid/core/error.hpp"
#include "liquid/core/parallel.hpp"
#include "liquid/rbf/interpolant.hpp"
#include "liquid/rbf/polynomial.hpp"
#include "liquid/rbf/weights.hpp"
#include "liquid/transfer/face_stencil.hpp"
#include "liquid/transfer/mls.hpp"

namespace liquid::transfer {

const char* to_string(Scheme scheme) {
  return scheme == Scheme::rbf ? "rbf" : "mls";
}

int TransferOptions::node_cap(int dim) const {
  if (max_nodes < 0) return 0;
  return max_nodes > 0 ? max_nodes : 4 * rbf::n_polynomial_terms(dim, degree);
}

rbf::Config TransferOptions::rbf_config() const {
  rbf::Config config{exponent, degree};
  config.condition_estimate = condition_estimate;
  return config;
}

std::string TransferOptions::describe() const {
  if (scheme == Scheme::rbf)
    return fmt::format("RBF (PHS r^{} + degree {}, {} ring{}{})", exponent, degree, rings,
                       rings > 1 ? "s" : "", clamp ? ", clamped" : "");
  return fmt::format("MLS (degree {}, {} ring{}{})", degree, rings, rings > 1 ? "s" : "",
                     clamp ? ", clamped" : "");
}

TransferReport& TransferReport::operator+=(const TransferReport& o) {
  targets += o.targets;
  empty += o.empty;
  clamped += o.clamped;
  degree_reduced += o.degree_reduced;
  fallback += o.fallback;
  max_degree_used = std::max(max_degree_used, o.max_degree_used);
  return *this;
}

std::string TransferReport::describe() const {
  const double pct = targets > 0 ? 100.0 * static_cast<double>(clamped) / static_cast<double>(targets) : 0.0;
  return fmt::format("targets {}, empty {}, clamped {} ({:.1f}%), degree lowered {}, fallback {}", targets,
                     empty, clamped, pct, degree_reduced, fallback);
}

namespace {

void check_options(const TransferOptions& o) {
  LIQUID_VERIFY(o.degree >= 0 && o.degree <= 4, "transfer: polynomial degree {} is outside [0, 4]", o.degree);
  LIQUID_VERIFY(o.rings >= 1 && o.rings <= 4, "transfer: {} rings is outside [1, 4]", o.rings);
  LIQUID_VERIFY(o.wall_rings >= 0 && o.wall_rings <= 2, "transfer: {} wall rings is outside [0, 2]",
                o.wall_rings);
  LIQUID_VERIFY(o.scheme == Scheme::mls || (o.exponent >= 1 && o.exponent <= 9 && o.exponent % 2 == 1),
                "transfer: PHS exponent {} must be odd and in [1, 9]", o.exponent);
}

/// Inverse-distance mean weights (the fallback of a singular stencil).
template <int Dim>
void shepard(std::span<const Vec<Dim>> nodes, const Vec<Dim>& at, std::vector<double>& w) {
  w.assign(nodes.size(), 0.0);
  double sum = 0.0;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const double d = (nodes[i] - at).norm();
    if (d == 0.0) {
      std::fill(w.begin(), w.end(), 0.0);
      w[i] = 1.0;
      return;
    }
    w[i] = 1.0 / (d * d);
    sum += w[i];
  }
  for (double& x : w) x /= sum;
}

/// v clamped to [lo, hi] when asked; counts the clamp.
double clamp_to(double v, double lo, double hi, bool clamp, TransferReport& r) {
  if (!clamp) return v;
  if (v < lo) {
    ++r.clamped;
    return lo;
  }
  if (v > hi) {
    ++r.clamped;
    return hi;
  }
  return v;
}

/// Keeps the `cap` nodes nearest to `at` (of equal distances, the earlier ones), with their values, in
/// their order. A selection by (distance, position), a total order, so the nodes kept are those of a
/// stable sort by distance without sorting them all.
template <int Dim>
void keep_nearest(std::vector<Vec<Dim>>& nodes, std::vector<double>& values, const Vec<Dim>& at, int cap) {
  if (cap <= 0 || static_cast<int>(nodes.size()) <= cap) return;
  thread_local std::vector<std::pair<double, int>> order;
  order.resize(nodes.size());
  for (std::size_t i = 0; i < order.size(); ++i)
    order[i] = {(nodes[i] - at).squaredNorm(), static_cast<int>(i)};
  std::nth_element(order.begin(), order.begin() + (cap - 1), order.end());
  std::sort(
      order.begin(), order.begin() + cap,
      [](const std::pair<double, int>& a, const std::pair<double, int>& b) { return a.second < b.second; });
  for (int j = 0; j < cap; ++j) {
    const int i = order[j].second;  // i >= j: the kept positions rise
    nodes[j] = nodes[i];
    values[j] = values[i];
  }
  nodes.resize(cap);
  values.resize(cap);
}

template <int Dim>
struct Scratch {
  std::vector<tree::CellId> cells, ring;
  std::vector<Vec<Dim>> nodes;
  std::vector<double> values, w;
  transfer::FaceStencil<Dim> stencil;
  TransferReport report;
};

/// The stencil cells of a face: its cells and those within rings - 1 hops of them (plus wall_rings
/// at a domain-boundary face), sorted.
template <int Dim>
void face_cells(const tree::CellGraph<Dim>& graph, tree::FaceId f, const TransferOptions& o,
                Scratch<Dim>& s) {
  const int rings = o.rings + (graph.face(f).is_boundary() ? o.wall_rings : 0);
  s.cells.clear();
  for (tree::CellId c : graph.face(f).cell) {
    if (c == tree::no_cell) continue;
    graph.k_ring(c, rings - 1, s.ring);
    s.cells.insert(s.cells.end(), s.ring.begin(), s.ring.end());
  }
  std::sort(s.cells.begin(), s.cells.end());
  s.cells.erase(std::unique(s.cells.begin(), s.cells.end()), s.cells.end());
}

}  // namespace

template <int Dim>
void gather_face_stencil(const tree::CellGraph<Dim>& graph, tree::CellId c, int rings,
                         std::span<const double> u, std::span<const std::uint8_t> known,
                         FaceStencil<Dim>& out) {
  graph.k_ring(c, rings, out.ring);
  out.faces.clear();
  for (tree::CellId r : out.ring)
    for (tree::FaceId f : graph.faces(r))
      if (known.empty() || known[f]) out.faces.push_back(f);
  std::sort(out.faces.begin(), out.faces.end());
  out.faces.erase(std::unique(out.faces.begin(), out.faces.end()), out.faces.end());
  for (int axis = 0; axis < Dim; ++axis) out.nodes[axis].clear(), out.values[axis].clear();
  for (tree::FaceId f : out.faces) {
    const int axis = graph.face(f).axis;
    out.nodes[axis].push_back(graph.face_centre(f));
    out.values[axis].push_back(u[f]);
  }
}

template <int Dim>
rbf::Interpolant<Dim> fitted_interpolant(const tree::CellGraph<Dim>& graph, tree::CellId c,
                                         std::span<const Vec<Dim>> nodes, std::span<const double> values,
                                         const rbf::Config& config, rbf::InterpolantCache<Dim>* cache) {
  LIQUID_VERIFY(values.size() == nodes.size(), "fitted_interpolant: {} values for {} nodes of cell {}",
                values.size(), nodes.size(), c);
  const long n = static_cast<long>(values.size());
  if (cache == nullptr) {
    rbf::Interpolant<Dim> interp(nodes, config);
    if (interp.status().usable()) interp.fit(Eigen::Map<const Eigen::VectorXd>(values.data(), n));
    return interp;
  }
  thread_local std::vector<int> order;
  rbf::Interpolant<Dim> interp =
      cache->interpolant(nodes, graph.centre(c), graph.cell_size(c)[0], config, order);
  if (!interp.status().usable()) return interp;
  Eigen::VectorXd sorted(n);
  for (long j = 0; j < n; ++j) sorted[j] = values[order[j]];
  interp.fit(sorted);
  return interp;
}

template void gather_face_stencil<2>(const tree::CellGraph<2>&, tree::CellId, int, std::span<const double>,
                                     std::span<const std::uint8_t>, FaceStencil<2>&);
template void gather_face_stencil<3>(const tree::CellGraph<3>&, tree::CellId, int, std::span<const double>,
                                     std::span<const std::uint8_t>, FaceStencil<3>&);
template rbf::Interpolant<2> fitted_interpolant<2>(const tree::CellGraph<2>&, tree::CellId,
                                                   std::span<const Vec<2>>, std::span<const double>,
                                                   const rbf::Config&, rbf::InterpolantCache<2>*);
template rbf::Interpolant<3> fitted_interpolant<3>(const tree::CellGraph<3>&, tree::CellId,
                                                   std::span<const Vec<3>>, std::span<const double>,
                                                   const rbf::Config&, rbf::InterpolantCache<3>*);

template <int Dim>
TransferReport particles_to_faces(const tree::CellGraph<Dim>& graph,
                                  const particles::Particles<Dim>& particles, const particles::CellBins& bins,
                                  const TransferOptions& options, FaceValues& out,
                                  std::span<const std::uint8_t> skip) {
  check_options(options);
  LIQUID_VERIFY(skip.empty() || static_cast<int>(skip.size()) >= graph.face_capacity(),
                "particles_to_faces: {} skip flags for {} face ids", skip.size(), graph.face_capacity());
  LIQUID_VERIFY(bins.n_particles() == particles.size(),
                "particles_to_faces: bins hold {} particles, there are {}", bins.n_particles(),
                particles.size());
  out.reset(graph.face_capacity());
  const rbf::Config config = options.rbf_config();
  const int node_cap = options.node_cap(Dim);
  TransferReport total;
  parallel_for(
      graph.face_capacity(), [] { return Scratch<Dim>{}; },
      [&](Scratch<Dim>& s, long fl) {
        const tree::FaceId f = static_cast<tree::FaceId>(fl);
        if (!graph.face_alive(f) || (!skip.empty() && skip[f])) return;
        const int axis = graph.face(f).axis;
        face_cells(graph, f, options, s);
        auto& nodes = s.nodes;
        nodes.clear();
        s.values.clear();
        for (tree::CellId c : s.cells)
          for (std::int32_t p : bins.of(c)) {
            nodes.push_back(particles.x[p]);
            s.values.push_back(particles.v[p][axis]);
          }
        ++s.report.targets;
        if (nodes.empty()) {
          ++s.report.empty;
          return;
        }
        const Vec<Dim> at = graph.face_centre(f);
        keep_nearest<Dim>(nodes, s.values, at, node_cap);
        int used = 0;
        if (options.scheme == Scheme::rbf) {
          const rbf::Status st = rbf::value_weights<Dim>(nodes, at, config, s.w);
          if (!st.usable()) {
            shepard<Dim>(nodes, at, s.w);
            ++s.report.fallback;
            used = 0;
          } else {
            used = st.degree_used;
          }
        } else {
          used = transfer::mls_weights<Dim>(nodes, at, options.degree, s.w);
        }
        if (used < options.degree) ++s.report.degree_reduced;
        s.report.max_degree_used = std::max(s.report.max_degree_used, used);
        double value = 0.0, lo = std::numeric_limits<double>::infinity(), hi = -lo;
        for (std::size_t i = 0; i < nodes.size(); ++i) {
          value += s.w[i] * s.values[i];
          lo = std::min(lo, s.values[i]);
          hi = std::max(hi, s.values[i]);
        }
        LIQUID_VERIFY(std::isfinite(value),
                      "particles_to_faces: non-finite value at face {} (axis {}, centre ({}))", f, axis,
                      fmt::join(at.data(), at.data() + Dim, ", "));
        out.value[f] = clamp_to(value, lo, hi, options.clamp_faces, s.report);
        out.known[f] = 1;
        out.weight[f] = static_cast<double>(nodes.size());
      },
      [&](Scratch<Dim>& s) { total += s.report; }, 256);
  return total;
}

template <int Dim>
TransferReport faces_to_points(const tree::CellGraph<Dim>& graph, std::span<const double> u,
                               std::span<const std::uint8_t> known, std::span<const Vec<Dim>> x,
                               const particles::CellBins& bins, const TransferOptions& options,
                               std::span<Vec<Dim>> v) {
  check_options(options);
  LIQUID_VERIFY(static_cast<int>(u.size()) >= graph.face_capacity(),
                "faces_to_points: {} face values for a graph of {} face ids", u.size(),
                graph.face_capacity());
  LIQUID_VERIFY(known.empty() || known.size() == u.size(), "faces_to_points: {} known flags for {} faces",
                known.size(), u.size());
  LIQUID_VERIFY(bins.n_particles() == static_cast<int>(x.size()) && v.size() == x.size(),
                "faces_to_points: {} points, {} binned, {} outputs", x.size(), bins.n_particles(), v.size());
  const rbf::Config config = options.rbf_config();
  std::unique_ptr<rbf::InterpolantCache<Dim>> cache;
  if (options.share_factors) cache = std::make_unique<rbf::InterpolantCache<Dim>>();
  // The cells that hold points, in id order.
  std::vector<tree::CellId> cells;
  for (tree::CellId c = 0; c + 1 < static_cast<tree::CellId>(bins.begin.size()); ++c)
    if (bins.begin[c + 1] > bins.begin[c]) cells.push_back(c);
  TransferReport total;
  parallel_for(
      static_cast<long>(cells.size()), [] { return Scratch<Dim>{}; },
      [&](Scratch<Dim>& s, long ci) {
        const tree::CellId c = cells[ci];
        const auto pts = bins.of(c);
        transfer::gather_face_stencil<Dim>(graph, c, options.rings, u, known, s.stencil);
        for (int axis = 0; axis < Dim; ++axis) {
          const std::vector<Vec<Dim>>& nodes = s.stencil.nodes[axis];
          const std::vector<double>& values = s.stencil.values[axis];
          s.report.targets += static_cast<long>(pts.size());
          if (nodes.empty()) {
            s.report.empty += static_cast<long>(pts.size());
            for (std::int32_t p : pts) v[p][axis] = 0.0;
            continue;
          }
          const double lo = *std::min_element(values.begin(), values.end());
          const double hi = *std::max_element(values.begin(), values.end());
          auto put = [&](std::int32_t p, double value) {
            LIQUID_VERIFY(std::isfinite(value), "faces_to_points: non-finite value at point {} in cell {}", p,
                          c);
            v[p][axis] = clamp_to(value, lo, hi, options.clamp, s.report);
          };
          if (options.scheme == Scheme::rbf) {
            const rbf::Interpolant<Dim> interp =
                transfer::fitted_interpolant<Dim>(graph, c, nodes, values, config, cache.get());
            if (interp.status().usable()) {
              if (interp.status().degree_used < options.degree) ++s.report.degree_reduced;
              s.report.max_degree_used = std::max(s.report.max_degree_used, interp.status().degree_used);
              for (std::int32_t p : pts) put(p, interp.value_at(x[p]));
              continue;
            }
            ++s.report.fallback;
            for (std::int32_t p : pts) {
              shepard<Dim>(nodes, x[p], s.w);
              double value = 0.0;
              for (std::size_t i = 0; i < nodes.size(); ++i) value += s.w[i] * values[i];
              put(p, value);
            }
            continue;
          }
          for (std::int32_t p : pts) {
            const int used = transfer::mls_weights<Dim>(nodes, x[p], options.degree, s.w);
            if (used < options.degree) ++s.report.degree_reduced;
            s.report.max_degree_used = std::max(s.report.max_degree_used, used);
            double value = 0.0;
            for (std::size_t i = 0; i < nodes.size(); ++i) value += s.w[i] * values[i];
            put(p, value);
          }
        }
      },
      [&](Scratch<Dim>& s) { total += s.report; }, 16);
  return total;
}

template <int Dim>
void flip_blend(std::span<const Vec<Dim>> pic, std::span<const Vec<Dim>> delta, double alpha,
                std::span<Vec<Dim>> v) {
  LIQUID_VERIFY(alpha >= 0.0 && alpha <= 1.0, "FLIP blend {} is outside [0, 1]", alpha);
  LIQUID_VERIFY(pic.size() == v.size() && delta.size() == v.size(), "flip_blend: {} / {} / {} particles",
                pic.size(), delta.size(), v.size());
  parallel_for(
      static_cast<long>(v.size()), [&](long i) { v[i] = alpha * (v[i] + delta[i]) + (1.0 - alpha) * pic[i]; },
      4096);
}

#define LIQUID_SCATTERED(D)                                                                                \
  template TransferReport particles_to_faces<D>(const tree::CellGraph<D>&, const particles::Particles<D>&, \
                                                const particles::CellBins&, const TransferOptions&,        \
                                                FaceValues&, std::span<const std::uint8_t>);               \
  template TransferReport faces_to_points<D>(                                                              \
      const tree::CellGraph<D>&, std::span<const double>, std::span<const std::uint8_t>,                   \
      std::span<const Vec<D>>, const particles::CellBins&, const TransferOptions&, std::span<Vec<D>>);     \
  template void flip_blend<D>(std::span<const Vec<D>>, std::span<const Vec<D>>, double, std::span<Vec<D>>);
LIQUID_SCATTERED(2)
LIQUID_SCATTERED(3)
#undef LIQUID_SCATTERED

}  // namespace liquid::transfer
