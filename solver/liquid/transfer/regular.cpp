#include "liquid/transfer/regular.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <mutex>

#include <fmt/format.h>
#include <Eigen/Geometry>

#include "liquid/core/error.hpp"
#include "liquid/core/parallel.hpp"

namespace liquid::transfer {

namespace {

Eigen::Vector3d lift(const Vec<2>& a) {
  return {a[0], a[1], 0.0};
}
Eigen::Vector3d lift(const Vec<3>& a) {
  return a;
}

template <int Dim>
Eigen::Vector3d axis_vector(int k) {
  Eigen::Vector3d e = Eigen::Vector3d::Zero();
  e[k] = 1.0;
  return e;
}

}  // namespace

template <int Dim>
RegularLattice<Dim>::RegularLattice(const tree::CellGraph<Dim>& graph) {
  LIQUID_VERIFY(graph.n_cells() > 0, "RegularLattice: the graph has no cells");
  level_ = graph.deepest_level();
  LIQUID_VERIFY(level_ >= 1,
                "RegularLattice: the tree is a single cell; the baselines need level 1 or finer");
  graph.for_each_cell([&](tree::CellId c) {
    LIQUID_VERIFY(graph.level(c) == level_,
                  "the regular PIC/FLIP/APIC transfers need a uniform tree: cell {} is at level {}, not {}",
                  c, graph.level(c), level_);
  });
  n_ = 1L << level_;
  lo_ = graph.domain().lo;
  h_ = graph.domain().size() / static_cast<double>(n_);
  long n_cells = 1;
  for (int j = 0; j < Dim; ++j) n_cells *= n_;
  cells_.assign(n_cells, tree::no_cell);
  for (int k = 0; k < Dim; ++k) {
    long m = 1;
    for (int j = 0; j < Dim; ++j) m *= extent(k, j);
    faces_[k].assign(m, tree::no_face);
  }
  graph.for_each_cell([&](tree::CellId c) {
    const IVec<Dim> a = graph.address(c);
    cells_[flat_cell(a)] = c;
    for (int k = 0; k < Dim; ++k)
      for (int dir : {-1, 1})
        graph.for_each_side_face(c, k, dir, [&](const tree::SideFace& s) {
          IVec<Dim> b = a;
          if (dir > 0) ++b[k];
          faces_[k][flat_face(k, b)] = s.face;
        });
  });
}

template <int Dim>
long RegularLattice<Dim>::flat_cell(const IVec<Dim>& a) const {
  long i = 0;
  for (int j = Dim - 1; j >= 0; --j) i = i * n_ + a[j];
  return i;
}

template <int Dim>
long RegularLattice<Dim>::flat_face(int k, const IVec<Dim>& a) const {
  long i = 0;
  for (int j = Dim - 1; j >= 0; --j) i = i * extent(k, j) + a[j];
  return i;
}

template <int Dim>
tree::CellId RegularLattice<Dim>::cell(const IVec<Dim>& a) const {
  for (int j = 0; j < Dim; ++j)
    if (a[j] < 0 || a[j] >= n_) return tree::no_cell;
  return cells_[flat_cell(a)];
}

template <int Dim>
tree::FaceId RegularLattice<Dim>::face(int k, const IVec<Dim>& a) const {
  for (int j = 0; j < Dim; ++j)
    if (a[j] < 0 || a[j] >= extent(k, j)) return tree::no_face;
  return faces_[k][flat_face(k, a)];
}

template <int Dim>
Vec<Dim> RegularLattice<Dim>::face_position(int k, const IVec<Dim>& a) const {
  Vec<Dim> x;
  for (int j = 0; j < Dim; ++j) x[j] = lo_[j] + h_[j] * (static_cast<double>(a[j]) + (j == k ? 0.0 : 0.5));
  return x;
}

template <int Dim>
LinearStencil<Dim>::LinearStencil(const RegularLattice<Dim>& lattice, int k, const Vec<Dim>& x) {
  for (int j = 0; j < Dim; ++j) {
    const double s = (x[j] - lattice.origin()[j]) / lattice.h()[j] - (j == k ? 0.0 : 0.5);
    const long last = lattice.extent(k, j) - 1;  // >= 1
    if (s <= 0.0) {
      base[j] = 0, t[j] = 0.0, clamped[j] = s < 0.0;
    } else if (s >= static_cast<double>(last)) {
      base[j] = last - 1, t[j] = 1.0, clamped[j] = s > static_cast<double>(last);
    } else {
      base[j] = std::min(static_cast<long>(std::floor(s)), last - 1);
      t[j] = s - static_cast<double>(base[j]);
    }
  }
}

template <int Dim>
double LinearStencil<Dim>::weight(int corner) const {
  return multilinear_weight<Dim>(t, corner);
}

template <int Dim>
Vec<Dim> LinearStencil<Dim>::gradient(int corner, const Vec<Dim>& h) const {
  return multilinear_gradient<Dim>(t, clamped, corner, h);
}

namespace {

/// The particle -> face transfers' checks and set-up: the bins and masses match the particles;
/// `out` is reset. Returns APIC's affine field (empty for PIC).
template <int Dim>
std::span<const double> p2g_inputs(const char* name, const tree::CellGraph<Dim>& graph,
                                   const particles::Particles<Dim>& particles,
                                   const particles::CellBins& bins, RegularScheme scheme,
                                   std::span<const double> masses, FaceValues& out) {
  LIQUID_VERIFY(bins.n_particles() == particles.size(), "{}: bins hold {} particles, there are {}", name,
                bins.n_particles(), particles.size());
  LIQUID_VERIFY(masses.empty() || static_cast<int>(masses.size()) == particles.size(),
                "{}: {} masses for {} particles", name, masses.size(), particles.size());
  out.reset(graph.face_capacity());
  if (scheme == RegularScheme::apic) return particles.field(particles.field_index("apic"));
  return {};
}

}  // namespace

template <int Dim>
TransferReport linear_to_faces(const tree::CellGraph<Dim>& graph, const RegularLattice<Dim>& lattice,
                               const particles::Particles<Dim>& particles, const particles::CellBins& bins,
                               RegularScheme scheme, std::span<const double> masses, FaceValues& out) {
  const std::span<const double> affine =
      p2g_inputs<Dim>("linear_to_faces", graph, particles, bins, scheme, masses, out);
  // A scatter: each particle is read once and adds its weight and momentum to the 2^Dim lattice
  // faces of each component. A particle in lattice cell z (along the slowest axis, Dim - 1) reaches
  // faces z - 1 .. z + 1 there, so slabs two cells thick that are two slabs apart never share a
  // face: the even slabs run in parallel, then the odd ones. A face's sum then takes its particles
  // in a fixed order (even slab, then odd; cells in lattice order; particles in bin order), the same
  // on any thread count.
  constexpr int top = Dim - 1;
  const long n = lattice.n();
  std::array<std::vector<double>, Dim> sum, mass;
  for (int k = 0; k < Dim; ++k) {
    sum[k].assign(lattice.face_count(k), 0.0);
    mass[k].assign(lattice.face_count(k), 0.0);
  }
  long cells_per_layer = 1;
  for (int j = 0; j < top; ++j) cells_per_layer *= n;
  const auto cell_layer = [&](const Vec<Dim>& x) {
    const double s = std::floor((x[top] - lattice.origin()[top]) / lattice.h()[top]);
    return static_cast<long>(std::clamp(s, 0.0, static_cast<double>(n - 1)));
  };
  const auto add = [&](std::int32_t p) {
    const Vec<Dim>& xp = particles.x[p];
    const double m = masses.empty() ? 1.0 : masses[p];
    for (int k = 0; k < Dim; ++k) {
      const LinearStencil<Dim> st(lattice, k, xp);
      double* const s_k = sum[k].data();
      double* const m_k = mass[k].data();
      for (int corner = 0; corner < (1 << Dim); ++corner) {
        const double w = multilinear_weight<Dim>(st.t, corner) * m;
        if (w == 0.0) continue;
        IVec<Dim> a = st.base;
        for (int j = 0; j < Dim; ++j) a[j] += (corner >> j) & 1;
        double u = particles.v[p][k];
        if (!affine.empty()) {
          const Vec<Dim> xf = lattice.face_position(k, a);
          for (int j = 0; j < Dim; ++j) u += affine[(p * Dim + k) * Dim + j] * (xf[j] - xp[j]);
        }
        const long flat = lattice.flat_face(k, a);
        s_k[flat] += w * u;
        m_k[flat] += w;
      }
    }
  };
  // A particle binned in a cell it is not inside (round-off at a face) may reach past its slab's
  // margin: those few are added serially after the slabs.
  std::vector<std::int32_t> strays;
  std::mutex strays_mutex;
  const long n_slabs = (n + 1) / 2;
  for (int colour = 0; colour < 2; ++colour) {
    const long n_coloured = (n_slabs - colour + 1) / 2;
    parallel_for(
        n_coloured, [] { return std::vector<std::int32_t>{}; },
        [&](std::vector<std::int32_t>& mine, long q) {
          const long slab = 2 * q + colour;
          for (long z = 2 * slab; z < std::min(2 * slab + 2, n); ++z)
            for (long i = 0; i < cells_per_layer; ++i) {
              IVec<Dim> a;
              long rest = i;
              for (int j = 0; j < top; ++j) a[j] = rest % n, rest /= n;
              a[top] = z;
              for (std::int32_t p : bins.of(lattice.cell(a))) {
                if (cell_layer(particles.x[p]) != z) {
                  mine.push_back(p);
                  continue;
                }
                add(p);
              }
            }
        },
        [&](std::vector<std::int32_t>& mine) {
          std::lock_guard lock(strays_mutex);
          strays.insert(strays.end(), mine.begin(), mine.end());
        },
        1);
  }
  std::sort(strays.begin(), strays.end());
  for (std::int32_t p : strays) add(p);

  TransferReport total;
  for (int k = 0; k < Dim; ++k)
    parallel_for(
        lattice.face_count(k), [] { return TransferReport{}; },
        [&](TransferReport& r, long flat) {
          ++r.targets;
          if (!(mass[k][flat] > 0.0)) {
            ++r.empty;
            return;
          }
          const tree::FaceId f = lattice.face_at(k, flat);
          out.value[f] = sum[k][flat] / mass[k][flat];
          out.known[f] = 1;
          out.weight[f] = mass[k][flat];
        },
        [&](TransferReport& r) { total += r; }, 4096);
  total.max_degree_used = 1;
  return total;
}

template <int Dim>
TransferReport linear_to_faces_gather(const tree::CellGraph<Dim>& graph, const RegularLattice<Dim>& lattice,
                                      const particles::Particles<Dim>& particles,
                                      const particles::CellBins& bins, RegularScheme scheme,
                                      std::span<const double> masses, FaceValues& out) {
  const std::span<const double> affine =
      p2g_inputs<Dim>("linear_to_faces_gather", graph, particles, bins, scheme, masses, out);
  TransferReport total;
  // Each face gathers from the particles of the 2 x 3^(Dim-1) cells around it, so a particle is
  // visited 2 x 3^(Dim-1) times per axis: its stencil (base corner and fractions) is computed once
  // per axis here instead, and the gather reads it (the same arithmetic, so the same bits).
  const long n_particles = particles.size();
  std::vector<IVec<Dim>> bases(static_cast<std::size_t>(n_particles));
  std::vector<Vec<Dim>> fractions(static_cast<std::size_t>(n_particles));
  for (int k = 0; k < Dim; ++k) {
    parallel_for(n_particles, [&](long p) {
      const LinearStencil<Dim> st(lattice, k, particles.x[p]);
      bases[p] = st.base;
      fractions[p] = st.t;
    });
    IVec<Dim> extent;
    long n_faces = 1;
    for (int j = 0; j < Dim; ++j) n_faces *= (extent[j] = lattice.extent(k, j));
    parallel_for(
        n_faces, [] { return TransferReport{}; },
        [&](TransferReport& r, long flat) {
          IVec<Dim> a;
          for (int j = 0; j < Dim; ++j) {
            a[j] = flat % extent[j];
            flat /= extent[j];
          }
          const tree::FaceId f = lattice.face(k, a);
          const Vec<Dim> xf = lattice.face_position(k, a);
          IVec<Dim> lo, hi;
          for (int j = 0; j < Dim; ++j) {
            lo[j] = std::max<long>(a[j] - 1, 0);
            hi[j] = std::min<long>(j == k ? a[j] : a[j] + 1, lattice.n() - 1);
          }
          double sum = 0.0, mass = 0.0;
          IVec<Dim> c = lo;
          while (true) {
            for (std::int32_t p : bins.of(lattice.cell(c))) {
              const IVec<Dim>& base = bases[p];
              int corner = 0;
              bool inside = true;
              for (int j = 0; j < Dim; ++j) {
                const long d = a[j] - base[j];
                inside = inside && (d == 0 || d == 1);
                corner |= static_cast<int>(d & 1) << j;
              }
              if (!inside) continue;
              const Vec<Dim>& xp = particles.x[p];
              const double w =
                  multilinear_weight<Dim>(fractions[p], corner) * (masses.empty() ? 1.0 : masses[p]);
              if (w == 0.0) continue;
              double u = particles.v[p][k];
              if (!affine.empty())
                for (int j = 0; j < Dim; ++j) u += affine[(p * Dim + k) * Dim + j] * (xf[j] - xp[j]);
              sum += w * u;
              mass += w;
            }
            int j = 0;  // next cell of the box, axis 0 fastest
            for (; j < Dim; ++j) {
              if (++c[j] <= hi[j]) break;
              c[j] = lo[j];
            }
            if (j == Dim) break;
          }
          store_mean(out, f, sum, mass, r);
        },
        [&](TransferReport& r) { total += r; }, 256);
  }
  total.max_degree_used = 1;
  return total;
}

template <int Dim>
TransferReport linear_to_points(const RegularLattice<Dim>& lattice, std::span<const double> u,
                                std::span<const Vec<Dim>> x, std::span<Vec<Dim>> v, std::span<double> affine,
                                std::span<const std::int32_t> order) {
  LIQUID_VERIFY(v.size() == x.size(), "linear_to_points: {} outputs for {} points", v.size(), x.size());
  LIQUID_VERIFY(affine.empty() || affine.size() == x.size() * Dim * Dim,
                "linear_to_points: affine field of {} doubles for {} points", affine.size(), x.size());
  LIQUID_VERIFY(order.empty() || order.size() == x.size(), "linear_to_points: an order of {} for {} points",
                order.size(), x.size());
  parallel_for(
      static_cast<long>(x.size()),
      [&](long q) {
        const long p = order.empty() ? q : order[q];
        for (int k = 0; k < Dim; ++k) {
          const LinearStencil<Dim> st(lattice, k, x[p]);
          double value = 0.0;
          Vec<Dim> grad = Vec<Dim>::Zero();
          for (int corner = 0; corner < (1 << Dim); ++corner) {
            IVec<Dim> a = st.base;
            for (int j = 0; j < Dim; ++j) a[j] += (corner >> j) & 1;
            const double uf = u[lattice.face(k, a)];
            value += st.weight(corner) * uf;
            if (!affine.empty()) grad += st.gradient(corner, lattice.h()) * uf;
          }
          LIQUID_VERIFY(std::isfinite(value), "linear_to_points: non-finite velocity at point {}", p);
          v[p][k] = value;
          if (!affine.empty())
            for (int j = 0; j < Dim; ++j) affine[(p * Dim + k) * Dim + j] = grad[j];
        }
      },
      1024);
  TransferReport r;
  r.targets = static_cast<long>(x.size()) * Dim;
  r.max_degree_used = 1;
  return r;
}

template <int Dim>
Vec<Dim> particle_momentum(const particles::Particles<Dim>& particles, std::span<const double> masses) {
  Vec<Dim> m = Vec<Dim>::Zero();
  for (int p = 0; p < particles.size(); ++p) m += (masses.empty() ? 1.0 : masses[p]) * particles.v[p];
  return m;
}

template <int Dim>
Vec<Dim> face_momentum(const tree::CellGraph<Dim>& graph, const FaceValues& faces) {
  Vec<Dim> m = Vec<Dim>::Zero();
  graph.for_each_face([&](tree::FaceId f) { m[graph.face(f).axis] += faces.weight[f] * faces.value[f]; });
  return m;
}

namespace {

/// D_k of APIC: sum over the axis-k stencil of w_f (x_f - x_p)(x_f - x_p)^T.
template <int Dim>
Eigen::Matrix<double, Dim, Dim> inertia(const RegularLattice<Dim>& lattice, int k, const Vec<Dim>& xp) {
  const LinearStencil<Dim> st(lattice, k, xp);
  Eigen::Matrix<double, Dim, Dim> d = Eigen::Matrix<double, Dim, Dim>::Zero();
  for (int corner = 0; corner < (1 << Dim); ++corner) {
    IVec<Dim> a = st.base;
    for (int j = 0; j < Dim; ++j) a[j] += (corner >> j) & 1;
    const Vec<Dim> r = lattice.face_position(k, a) - xp;
    d += st.weight(corner) * r * r.transpose();
  }
  return d;
}

}  // namespace

template <int Dim>
double particle_affine_energy(const RegularLattice<Dim>& lattice, const particles::Particles<Dim>& particles,
                              std::span<const double> affine, std::span<const double> masses) {
  double total = 0.0;
  for (int p = 0; p < particles.size(); ++p)
    for (int k = 0; k < Dim; ++k) {
      const Vec<Dim> c = Eigen::Map<const Vec<Dim>>(affine.data() + (p * Dim + k) * Dim);
      total += 0.5 * (masses.empty() ? 1.0 : masses[p]) * c.dot(inertia(lattice, k, particles.x[p]) * c);
    }
  return total;
}

template <int Dim>
Eigen::Vector3d particle_angular_momentum(const RegularLattice<Dim>& lattice,
                                          const particles::Particles<Dim>& particles,
                                          std::span<const double> affine, std::span<const double> masses) {
  Eigen::Vector3d total = Eigen::Vector3d::Zero();
  for (int p = 0; p < particles.size(); ++p) {
    const double m = masses.empty() ? 1.0 : masses[p];
    const Vec<Dim>& xp = particles.x[p];
    Eigen::Vector3d l = lift(xp).cross(lift(particles.v[p]));
    if (!affine.empty())
      for (int k = 0; k < Dim; ++k) {
        const Vec<Dim> c = Eigen::Map<const Vec<Dim>>(affine.data() + (p * Dim + k) * Dim);
        l += lift(Vec<Dim>(inertia(lattice, k, xp) * c)).cross(axis_vector<Dim>(k));
      }
    total += m * l;
  }
  return total;
}

template <int Dim>
Eigen::Vector3d face_angular_momentum(const tree::CellGraph<Dim>& graph, const FaceValues& faces) {
  Eigen::Vector3d total = Eigen::Vector3d::Zero();
  graph.for_each_face([&](tree::FaceId f) {
    const int k = graph.face(f).axis;
    total += faces.weight[f] * faces.value[f] * lift(graph.face_centre(f)).cross(axis_vector<Dim>(k));
  });
  return total;
}

#define LIQUID_REGULAR(D)                                                                                    \
  template class RegularLattice<D>;                                                                          \
  template struct LinearStencil<D>;                                                                          \
  template TransferReport linear_to_faces<D>(const tree::CellGraph<D>&, const RegularLattice<D>&,            \
                                             const particles::Particles<D>&, const particles::CellBins&,     \
                                             RegularScheme, std::span<const double>, FaceValues&);           \
  template TransferReport linear_to_faces_gather<D>(                                                         \
      const tree::CellGraph<D>&, const RegularLattice<D>&, const particles::Particles<D>&,                   \
      const particles::CellBins&, RegularScheme, std::span<const double>, FaceValues&);                      \
  template TransferReport linear_to_points<D>(const RegularLattice<D>&, std::span<const double>,             \
                                              std::span<const Vec<D>>, std::span<Vec<D>>, std::span<double>, \
                                              std::span<const std::int32_t>);                                \
  template Vec<D> particle_momentum<D>(const particles::Particles<D>&, std::span<const double>);             \
  template Vec<D> face_momentum<D>(const tree::CellGraph<D>&, const FaceValues&);                            \
  template Eigen::Vector3d particle_angular_momentum<D>(const RegularLattice<D>&,                            \
                                                        const particles::Particles<D>&,                      \
                                                        std::span<const double>, std::span<const double>);   \
  template Eigen::Vector3d face_angular_momentum<D>(const tree::CellGraph<D>&, const FaceValues&);           \
  template double particle_affine_energy<D>(const RegularLattice<D>&, const particles::Particles<D>&,        \
                                            std::span<const double>, std::span<const double>);
LIQUID_REGULAR(2)
LIQUID_REGULAR(3)
#undef LIQUID_REGULAR

}  // namespace liquid::transfer
