#include "liquid/particles/seeding.hpp"

#include <gsl/gsl_qrng.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "liquid/core/error.hpp"
#include "liquid/core/hash.hpp"
#include "liquid/core/parallel.hpp"

namespace liquid::particles {

namespace {

/// The pattern points of one cell, in physical coordinates.
template <int Dim>
void cell_points(const tree::CellGraph<Dim>& graph, tree::CellId c, const std::vector<Vec<Dim>>& pattern,
                 double jitter, std::uint64_t seed, std::vector<Vec<Dim>>& out) {
  const Box<Dim> b = graph.box(c);
  const double spacing = std::pow(static_cast<double>(pattern.size()), -1.0 / Dim);
  out.clear();
  for (std::size_t k = 0; k < pattern.size(); ++k) {
    Vec<Dim> u = pattern[k];
    if (jitter > 0.0) {
      std::uint64_t h = mix64(seed ^ mix64(graph.key(c) ^ mix64(k)));
      for (int a = 0; a < Dim; ++a) {
        h = mix64(h);
        const double r = unit_interval(h) - 0.5;  // in [-0.5, 0.5)
        u[a] += jitter * spacing * r;
        if (u[a] < 0.0) u[a] = -u[a];  // reflected back into the cell, not piled up on its side
        if (u[a] >= 1.0) u[a] = 2.0 - u[a];
        u[a] = std::clamp(u[a], 1e-9, 1.0 - 1e-9);
      }
    }
    out.push_back(b.lo + u.cwiseProduct(b.size()));
  }
}

template <int Dim>
int default_count(int n) {
  return n > 0 ? n : (1 << Dim);
}

}  // namespace

template <int Dim>
std::vector<Vec<Dim>> halton_points(int n) {
  LIQUID_VERIFY(n >= 0, "halton_points: negative count {}", n);
  std::unique_ptr<gsl_qrng, decltype(&gsl_qrng_free)> q(gsl_qrng_alloc(gsl_qrng_halton, Dim), &gsl_qrng_free);
  LIQUID_VERIFY(q != nullptr, "GSL could not allocate a {}-dimensional Halton generator", Dim);
  std::vector<Vec<Dim>> out(n);
  double v[Dim];
  for (int i = 0; i < n; ++i) {
    gsl_qrng_get(q.get(), v);
    for (int a = 0; a < Dim; ++a) out[i][a] = v[a];
  }
  return out;
}

template <int Dim>
long seed_region(const tree::CellGraph<Dim>& graph, const levelset::Function<Dim>& region,
                 const SeedOptions& options, Particles<Dim>& particles, const VelocitySource<Dim>& velocity) {
  LIQUID_VERIFY(options.jitter >= 0.0 && options.jitter < 1.0, "seed: jitter {} is outside [0, 1)",
                options.jitter);
  LIQUID_VERIFY(static_cast<bool>(region), "seed: no region given");
  const int per_cell = default_count<Dim>(options.per_cell);
  LIQUID_VERIFY(per_cell >= 1 && per_cell <= 4096, "seed: {} points per cell is outside [1, 4096]", per_cell);
  const auto pattern = halton_points<Dim>(per_cell);
  const std::vector<tree::CellId> cells = graph.cell_ids();
  // Per cell, the points inside the region; then appended in cell order.
  std::vector<std::vector<Vec<Dim>>> kept(cells.size());
  parallel_for(
      static_cast<long>(cells.size()), [] { return std::vector<Vec<Dim>>{}; },
      [&](std::vector<Vec<Dim>>& pts, long i) {
        cell_points(graph, cells[i], pattern, options.jitter, options.seed, pts);
        for (const auto& p : pts) {
          const double phi = region(p);
          LIQUID_VERIFY(std::isfinite(phi), "seed: the region's level set is not finite at ({})",
                        fmt::join(p.data(), p.data() + Dim, ", "));
          if (phi < 0.0) kept[i].push_back(p);
        }
      },
      [](std::vector<Vec<Dim>>&) {}, 64);
  const int first = particles.size();
  std::vector<tree::CellId> owner;
  for (std::size_t i = 0; i < cells.size(); ++i)
    for (const auto& p : kept[i]) {
      particles.push_back(p, Vec<Dim>::Zero());
      owner.push_back(cells[i]);
    }
  const long added = particles.size() - first;
  if (velocity && added > 0)
    velocity(std::span<const Vec<Dim>>(particles.x).subspan(first), owner,
             std::span<Vec<Dim>>(particles.v).subspan(first));
  return added;
}

template <int Dim>
ReseedReport reseed(const tree::CellGraph<Dim>& graph, std::span<const tree::CellId> cells,
                    const ReseedOptions& options, const VelocitySource<Dim>& velocity,
                    Particles<Dim>& particles, CellBins& bins) {
  const int lo = options.lo > 0 ? options.lo : (Dim == 2 ? 3 : 5);
  const int hi = options.hi > 0 ? options.hi : (Dim == 2 ? 12 : 15);
  const int per_cell = default_count<Dim>(options.per_cell);
  LIQUID_VERIFY(lo <= hi, "reseed: range [{}, {}] is empty", lo, hi);
  LIQUID_VERIFY(per_cell >= lo && per_cell <= hi,
                "reseed: {} new particles per cell would leave the range [{}, {}] at once", per_cell, lo, hi);
  LIQUID_VERIFY(static_cast<bool>(velocity), "reseed: no velocity source for the new particles");
  LIQUID_VERIFY(bins.n_particles() == particles.size(), "reseed: bins hold {} particles, there are {}",
                bins.n_particles(), particles.size());
  ReseedReport report;
  std::vector<tree::CellId> chosen;
  for (tree::CellId c : cells) {
    if (!graph.alive(c)) continue;
    const int n = bins.count(c);
    if ((n == 0 && !options.fill_empty) || (n >= lo && n <= hi)) continue;
    chosen.push_back(c);
  }
  std::sort(chosen.begin(), chosen.end());
  chosen.erase(std::unique(chosen.begin(), chosen.end()), chosen.end());
  report.cells = static_cast<long>(chosen.size());
  if (chosen.empty()) return report;
  const auto pattern = halton_points<Dim>(per_cell);
  // Per chosen cell, the pattern points that get a new particle; the particles to remove are marked.
  std::vector<std::uint8_t> remove(particles.size(), 0);
  std::vector<std::vector<Vec<Dim>>> added(chosen.size());
  std::vector<Vec<Dim>> pts;
  for (std::size_t k = 0; k < chosen.size(); ++k) {
    const tree::CellId c = chosen[k];
    const auto own = bins.of(c);
    cell_points(graph, c, pattern, options.jitter, options.seed, pts);
    if (!options.keep) {
      for (std::int32_t p : own) remove[p] = 1;
      report.deleted += static_cast<long>(own.size());
      added[k] = pts;
    } else if (static_cast<int>(own.size()) > per_cell) {
      // Crowded: keep, for each pattern point in turn, the nearest particle not kept yet.
      std::vector<std::uint8_t> kept(own.size(), 0);
      for (const auto& q : pts) {
        std::size_t best = own.size();
        double best_d = std::numeric_limits<double>::infinity();
        for (std::size_t i = 0; i < own.size(); ++i) {
          const double d = (particles.x[own[i]] - q).squaredNorm();
          if (!kept[i] && d < best_d) best = i, best_d = d;
        }
        kept[best] = 1;
      }
      for (std::size_t i = 0; i < own.size(); ++i)
        if (!kept[i]) remove[own[i]] = 1, ++report.deleted;
    } else {
      // Sparse: add at the pattern points farthest from the particles there so far.
      std::vector<Vec<Dim>> have;
      for (std::int32_t p : own) have.push_back(particles.x[p]);
      std::vector<std::uint8_t> used(pts.size(), 0);
      for (int n = static_cast<int>(own.size()); n < per_cell; ++n) {
        std::size_t best = 0;
        double best_d = -1.0;
        for (std::size_t j = 0; j < pts.size(); ++j) {
          if (used[j]) continue;
          double d = std::numeric_limits<double>::infinity();
          for (const auto& h : have) d = std::min(d, (h - pts[j]).squaredNorm());
          if (d > best_d) best = j, best_d = d;
        }
        used[best] = 1;
        have.push_back(pts[best]);
        added[k].push_back(pts[best]);
      }
    }
  }

  std::vector<std::int32_t> new_index;
  particles.compact(remove, &new_index);
  std::vector<tree::CellId> cell_of(particles.size());
  for (std::size_t i = 0; i < new_index.size(); ++i)
    if (new_index[i] >= 0) cell_of[new_index[i]] = bins.cell[i];
  const int first = particles.size();
  for (std::size_t k = 0; k < chosen.size(); ++k)
    for (const auto& p : added[k]) {
      particles.push_back(p, Vec<Dim>::Zero());
      cell_of.push_back(chosen[k]);
    }
  report.created = particles.size() - first;
  velocity(std::span<const Vec<Dim>>(particles.x).subspan(first),
           std::span<const tree::CellId>(cell_of).subspan(first),
           std::span<Vec<Dim>>(particles.v).subspan(first));
  bins.cell = std::move(cell_of);
  bins.sort(graph.cell_capacity());
  return report;
}

#define LIQUID_SEEDING(D)                                                                                   \
  template std::vector<Vec<D>> halton_points<D>(int);                                                       \
  template long seed_region<D>(const tree::CellGraph<D>&, const levelset::Function<D>&, const SeedOptions&, \
                               Particles<D>&, const VelocitySource<D>&);                                    \
  template ReseedReport reseed<D>(const tree::CellGraph<D>&, std::span<const tree::CellId>,                 \
                                  const ReseedOptions&, const VelocitySource<D>&, Particles<D>&, CellBins&);
LIQUID_SEEDING(2)
LIQUID_SEEDING(3)
#undef LIQUID_SEEDING

}  // namespace liquid::particles
