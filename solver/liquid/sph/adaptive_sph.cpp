#include "liquid/sph/adaptive_sph.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>

#include <fmt/ranges.h>

#include "liquid/core/error.hpp"
#include "liquid/core/parallel.hpp"
#include "liquid/sph/kernels.hpp"

namespace liquid::sph {

namespace {
/// A restored density above this many rest densities is a damaged checkpoint (a weakly compressible
/// liquid stays within about 1% of rest).
constexpr double kMaxSavedDensity = 100.0;
}  // namespace

// The cycloidal profile: theta = A (t/T - sin(2 pi t/T) / (2 pi)); its rate and its acceleration
// are 0 at both ends.
template <int Dim>
double SphRotation<Dim>::theta(double t) const {
  if (t >= duration) return angle;
  const double u = t / duration;
  return angle * (u - std::sin(2.0 * std::numbers::pi * u) / (2.0 * std::numbers::pi));
}

template <int Dim>
double SphRotation<Dim>::omega(double t) const {
  if (t >= duration) return 0.0;
  return angle / duration * (1.0 - std::cos(2.0 * std::numbers::pi * t / duration));
}

template <int Dim>
double SphRotation<Dim>::omega_rate(double t) const {
  if (t >= duration) return 0.0;
  const double k = 2.0 * std::numbers::pi / duration;
  return angle / duration * k * std::sin(k * t);
}

template <int Dim>
Vec<Dim> SphRotation<Dim>::turn(const Vec<Dim>& v, double a) const {
  if constexpr (Dim == 2) {
    const double c = std::cos(a), s = std::sin(a);
    return Vec<2>(c * v[0] - s * v[1], s * v[0] + c * v[1]);
  } else {
    return Eigen::AngleAxisd(a, axis) * v;
  }
}

template <int Dim>
double SphView<Dim>::distance(const Vec<Dim>& x) const {
  const Vec<Dim> axis = (target - eye).normalized(), v = x - eye;
  const double h = v.dot(axis), r = (v - h * axis).norm();
  const double c = std::cos(half_angle), s = std::sin(half_angle);
  const double lateral = r * c - h * s;  // signed distance to the cone's side, negative inside
  if (lateral <= 0.0) return 0.0;
  // Outside: the nearest point is on the side when x projects onto it, else the apex.
  return r * s + h * c >= 0.0 ? lateral : v.norm();
}

template <int Dim>
void SphOptions<Dim>::check() const {
  LIQUID_VERIFY(neighbour_skin >= 0.0 && std::isfinite(neighbour_skin),
                "sph: the neighbour skin must be >= 0 level-0 spacings, not {}", neighbour_skin);
  LIQUID_VERIFY(container.valid(), "sph: the container box must have lo < hi along every axis");
  LIQUID_VERIFY(spacing > 0.0 && std::isfinite(spacing), "sph: the particle spacing must be positive, not {}",
                spacing);
  LIQUID_VERIFY(h_ratio > 1.0 && std::isfinite(h_ratio),
                "sph: h (support radius / spacing) must be above 1, not {}", h_ratio);
  LIQUID_VERIFY(fluid.rest_density > 0.0 && fluid.stiffness > 0.0 && fluid.viscosity >= 0.0,
                "sph: rest density {} and stiffness {} must be positive and viscosity {} not negative",
                fluid.rest_density, fluid.stiffness, fluid.viscosity);
  LIQUID_VERIFY(max_level >= 0 && max_level <= 12, "sph: max_level must be within 0..12, not {}", max_level);
  LIQUID_VERIFY(resample_every >= 1, "sph: resample_every must be at least 1, not {}", resample_every);
  LIQUID_VERIFY(std::isfinite(resample_travel) && resample_travel >= 0.0 && resample_travel <= 100.0,
                "sph: resample_travel must be within [0, 100] spacings, not {}", resample_travel);
  LIQUID_VERIFY(serial_below >= 0 && serial_below <= 100'000'000,
                "sph: serial_below must be within 0..100000000 particles, not {}", serial_below);
  LIQUID_VERIFY(merge_min_passes >= 0 && merge_min_passes <= 1000,
                "sph: merge_min_passes must be within 0..1000, not {}", merge_min_passes);
  LIQUID_VERIFY(resampling.alpha > 0.0 && resampling.beta > resampling.alpha,
                "sph: alpha = {} and beta = {} must satisfy 0 < alpha < beta", resampling.alpha,
                resampling.beta);
  LIQUID_VERIFY(gamma_degrees > 0.0 && gamma_degrees < 180.0,
                "sph: gamma must be within (0, 180) degrees, not {}", gamma_degrees);
  LIQUID_VERIFY(projection_bisections >= 0 && projection_bisections <= 30,
                "sph: projection_bisections must be within 0..30, not {}", projection_bisections);
  LIQUID_VERIFY(disk_radius > 0.0 && disk_radius <= 1.0,
                "sph: the footpoint disks' radius must be within (0, 1] support radii, not {}", disk_radius);
  LIQUID_VERIFY(fluid.density_diffusion >= 0.0 && fluid.density_diffusion <= 1.0,
                "sph: the density diffusion delta must be within [0, 1], not {}", fluid.density_diffusion);
  LIQUID_VERIFY(fluid.shifting >= 0.0 && fluid.shifting <= 0.1,
                "sph: the shifting coefficient must be within [0, 0.1], not {}", fluid.shifting);
  LIQUID_VERIFY(restitution >= 0.0 && restitution <= 1.0, "sph: restitution must be within [0, 1], not {}",
                restitution);
  LIQUID_VERIFY(gravity.allFinite(), "sph: gravity must be finite");
  for (std::size_t k = 0; k < sources.size(); ++k) {
    const SphSource<Dim>& src = sources[k];
    LIQUID_VERIFY(static_cast<bool>(src.region) && src.bounds.valid(),
                  "sph: source {} needs a region and bounds with lo < hi", k + 1);
    LIQUID_VERIFY(src.velocity.allFinite(), "sph: source {}'s velocity must be finite", k + 1);
    LIQUID_VERIFY(src.start >= 0.0 && src.stop > src.start,
                  "sph: source {} needs 0 <= start < stop, not {} and {}", k + 1, src.start, src.stop);
  }
  if (view.active())
    LIQUID_VERIFY(view.half_angle < std::numbers::pi / 2 && view.eye.allFinite() && view.target.allFinite() &&
                      (view.target - view.eye).norm() > 0.0,
                  "sph: the view needs a half-angle within (0, 90) degrees and an eye apart from its target");
  if (rotation.active()) {
    LIQUID_VERIFY(
        std::isfinite(rotation.angle) && rotation.duration > 0.0 && std::isfinite(rotation.duration),
        "sph: the container's turn needs a finite angle and a positive duration, not {} and {}",
        rotation.angle, rotation.duration);
    LIQUID_VERIFY(rotation.pivot.allFinite(), "sph: the container's pivot must be finite");
    LIQUID_VERIFY(std::abs(rotation.axis.norm() - 1.0) < 1e-9, "sph: the turn's axis must be a unit vector");
  }
}

template <int Dim>
Vec<Dim> AdaptiveSph<Dim>::gravity_at(double t) const {
  if (!options_.rotation.active()) return options_.gravity;
  return options_.rotation.turn(options_.gravity, -options_.rotation.theta(t));
}

template <int Dim>
void AdaptiveSph<Dim>::add_frame_accelerations(double dt) {
  const SphRotation<Dim>& rot = options_.rotation;
  const double w = rot.omega(time_), dw = rot.omega_rate(time_);
  if (w == 0.0 && dw == 0.0) return;
  const int n = p_.size();
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i) {
    const Vec<Dim> r = p_.x[i] - rot.pivot;
    // Euler and centrifugal accelerations at x_n; the Coriolis term -2 w x v_n wants the velocity at
    // the force's time, which leap-frog does not hold (v is at the half step before). v_n = v + dt/2
    // (a - 2 w x v_n) is solved for v_n exactly (a rotation-like 2 x 2 or 3 x 3 inverse). With v
    // itself the turn would be first order in dt.
    const double k = dt * w;
    if constexpr (Dim == 2) {
      // w = w e_z: w x r = w (-r_y, r_x); w x (w x r) = -w^2 r.
      const Vec<2> perp_r(-r[1], r[0]);
      p_.a[i] += -dw * perp_r + w * w * r;
      const Vec<2> b = p_.v[i] + 0.5 * dt * p_.a[i];
      const Vec<2> vn = Vec<2>(b[0] + k * b[1], b[1] - k * b[0]) / (1.0 + k * k);
      p_.a[i] += -2.0 * w * Vec<2>(-vn[1], vn[0]);
    } else {
      const Vec<3>& e = rot.axis;
      const Vec<3> wv = w * e, dwv = dw * e;
      p_.a[i] += -dwv.cross(r) - wv.cross(wv.cross(r));
      const Vec<3> b = p_.v[i] + 0.5 * dt * p_.a[i];
      const Vec<3> vn = (b - k * e.cross(b) + k * k * e.dot(b) * e) / (1.0 + k * k);
      p_.a[i] += -2.0 * wv.cross(vn);
    }
  }
}

template <int Dim>
int AdaptiveSph<Dim>::apply_sources() {
  int added = 0;
  const double s = options_.spacing;
  double reach = s;  // the largest spacing of any particle
  for (int l = 0; l <= options_.max_level; ++l) reach = std::max(reach, sizes_.spacing_of<Dim>(l));
  for (const SphSource<Dim>& src : options_.sources) {
    if (!src.active(time_)) continue;
    // The particles near the source, bucketed in cells of side `reach` over its bounds (one cell wider).
    const Vec<Dim> lo = src.bounds.lo.array() - reach;
    Eigen::Matrix<long, Dim, 1> cells;
    for (int d = 0; d < Dim; ++d)
      cells[d] = static_cast<long>(std::ceil((src.bounds.size()[d] + 2 * reach) / reach)) + 1;
    const auto cell_of = [&](const Vec<Dim>& x, Eigen::Matrix<long, Dim, 1>& c) {
      for (int d = 0; d < Dim; ++d) {
        c[d] = static_cast<long>(std::floor((x[d] - lo[d]) / reach));
        if (c[d] < 0 || c[d] >= cells[d]) return false;
      }
      return true;
    };
    const auto flat = [&](const Eigen::Matrix<long, Dim, 1>& c) {
      long k = 0;
      for (int d = Dim - 1; d >= 0; --d) k = k * cells[d] + c[d];
      return k;
    };
    std::vector<std::vector<int>> bucket(static_cast<std::size_t>(cells.prod()));
    // Only particles in the grid (the bounds and one cell more) can be inside the region.
    for (int i = 0; i < p_.size(); ++i) {
      Eigen::Matrix<long, Dim, 1> c = Eigen::Matrix<long, Dim, 1>::Zero();
      if (!cell_of(p_.x[i], c)) continue;
      bucket[flat(c)].push_back(i);
      if (src.region(p_.x[i]) < 0.0) p_.v[i] = src.velocity;
    }
    // The lattice over the bounds, centred as seed() centres its lattice in the container.
    Eigen::Matrix<long, Dim, 1> n;
    for (int d = 0; d < Dim; ++d)
      n[d] = std::max<long>(1, static_cast<long>(std::floor(src.bounds.size()[d] / s + 1e-9)));
    const Vec<Dim> offset =
        src.bounds.lo + 0.5 * (src.bounds.size() - s * (n.template cast<double>() - Vec<Dim>::Ones()));
    Eigen::Matrix<long, Dim, 1> k = Eigen::Matrix<long, Dim, 1>::Zero();
    while (true) {
      const Vec<Dim> x = offset + s * k.template cast<double>();
      if (src.region(x) < 0.0 && !in_solid(x)) {
        bool free = true;
        Eigen::Matrix<long, Dim, 1> c = Eigen::Matrix<long, Dim, 1>::Zero();
        cell_of(x, c);  // inside: the grid reaches one cell past the bounds
        Eigen::Matrix<long, Dim, 1> o = Eigen::Matrix<long, Dim, 1>::Constant(-1);
        while (free) {
          Eigen::Matrix<long, Dim, 1> q = c + o;
          if ((q.array() >= 0).all() && (q.array() < cells.array()).all())
            for (int j : bucket[flat(q)]) {
              const double need = 0.99 * 0.5 * (s + p_.radius[j] / sizes_.h_ratio);
              if ((p_.x[j] - x).squaredNorm() < need * need) {
                free = false;
                break;
              }
            }
          int d = 0;
          while (d < Dim && ++o[d] > 1) o[d] = -1, ++d;
          if (d == Dim) break;
        }
        if (free) {
          const int i = p_.add(sizes_, x, src.velocity, 0, 0.0, options_.fluid.rest_density);
          if (cell_of(x, c)) bucket[flat(c)].push_back(i);
          ++added;
        }
      }
      int d = 0;
      while (d < Dim && ++k[d] >= n[d]) k[d] = 0, ++d;
      if (d == Dim) break;
    }
  }
  return added;
}

template <int Dim>
AdaptiveSph<Dim>::AdaptiveSph(SphOptions<Dim> options) : options_(std::move(options)), rng_(options_.seed) {
  options_.check();
  options_.resampling.max_level = options_.max_level;
  walls_ = Boundary<Dim>(options_.container, options_.obstacles);
  sizes_.radius = options_.h_ratio * options_.spacing;
  sizes_.h_ratio = options_.h_ratio;
  // The level-0 mass that gives a full lattice of spacing s the density rho_0.
  const double s = options_.spacing, r = sizes_.radius;
  const int reach = static_cast<int>(std::ceil(options_.h_ratio));
  double sum = 0.0;
  Eigen::Matrix<int, Dim, 1> k = Eigen::Matrix<int, Dim, 1>::Constant(-reach);
  while (true) {
    sum += density_kernel<Dim>(options_.fluid, s * k.template cast<double>().norm(), r);
    int d = 0;
    while (d < Dim && ++k[d] > reach) k[d] = -reach, ++d;
    if (d == Dim) break;
  }
  sizes_.mass = options_.fluid.rest_density / sum;
}

template <int Dim>
bool AdaptiveSph<Dim>::in_solid(const Vec<Dim>& x) const {
  const double tol = 1e-12 * options_.container.size().maxCoeff();
  if ((x.array() < options_.container.lo.array() - tol).any() ||
      (x.array() > options_.container.hi.array() + tol).any())
    return true;
  for (const auto& obstacle : options_.obstacles)
    if (obstacle(x) < 0.0) return true;
  return false;
}

template <int Dim>
bool AdaptiveSph<Dim>::in_collision_margin(const Vec<Dim>& x) const {
  const double tol = 1e-12 * options_.container.size().maxCoeff(), margin = collision_margin() - tol;
  if ((x.array() < options_.container.lo.array() + margin).any() ||
      (x.array() > options_.container.hi.array() - margin).any())
    return true;
  for (const auto& obstacle : options_.obstacles)
    if (obstacle(x) < margin) return true;
  return false;
}

template <int Dim>
void AdaptiveSph<Dim>::footpoints_onto_walls() {
  const int n = p_.size();
  const double reach = options_.spacing;
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(walls_.nearest(p_.foot[i], reach))) continue;
    // The solid near the footpoint is within |x - y| + reach of the particle: so is its nearest one.
    Vec<Dim> y;
    if (std::isfinite(walls_.nearest(p_.x[i], (p_.x[i] - p_.foot[i]).norm() + reach, &y))) p_.foot[i] = y;
  }
}

template <int Dim>
void AdaptiveSph<Dim>::seed(const levelset::Function<Dim>& liquid, const Vec<Dim>& velocity) {
  const double s = options_.spacing;
  const Box<Dim>& box = options_.container;
  Eigen::Matrix<long, Dim, 1> n;
  for (int d = 0; d < Dim; ++d) n[d] = static_cast<long>(std::floor(box.size()[d] / s + 1e-9));
  LIQUID_VERIFY(n.minCoeff() >= 1, "sph: the container is narrower than one particle spacing ({})", s);
  Eigen::Matrix<long, Dim, 1> k = Eigen::Matrix<long, Dim, 1>::Zero();
  const Vec<Dim> offset = box.lo + 0.5 * (box.size() - s * (n.template cast<double>() - Vec<Dim>::Ones()));
  while (true) {
    const Vec<Dim> x = offset + s * k.template cast<double>();
    const double phi = liquid(x);
    LIQUID_VERIFY(std::isfinite(phi), "sph: the liquid's level set is not finite at the lattice point ({})",
                  fmt::join(x, ", "));
    if (phi < 0.0 && !in_solid(x)) p_.add(sizes_, x, velocity, 0, -phi, options_.fluid.rest_density);
    int d = 0;
    while (d < Dim && ++k[d] >= n[d]) k[d] = 0, ++d;
    if (d == Dim) break;
  }
  LIQUID_VERIFY_INPUT(p_.size() > 0,
                      "sph: the liquid region holds no lattice point of spacing {} inside the container", s);
  if (!options_.adaptive) return;
  for (int round = 0; round < 2 * options_.max_level + 2; ++round) {
    const SphStepReport r = adapt_now();
    if (r.resampling.split + r.resampling.merged == 0) break;
  }
}

template <int Dim>
void AdaptiveSph<Dim>::find_neighbours_now(bool with_tree) {
  const bool kd = options_.search == NeighbourSearch::kd_tree ||
                  (options_.search == NeighbourSearch::automatic && Dim == 3 && options_.adaptive);
  if (kd || with_tree) tree_.build(p_.x);
  const double skin = options_.neighbour_skin * options_.spacing;
  std::vector<double> reach(p_.radius);
  if (skin > 0.0)
    for (double& r : reach) r += skin;
  nbrs_ = kd ? find_neighbours<Dim>(tree_, p_.x, reach) : find_neighbours_cells<Dim>(p_.x, reach);
  built_at_ = p_.x;
}

template <int Dim>
double AdaptiveSph<Dim>::skin_used() const {
  const int n = p_.size();
  if (options_.neighbour_skin <= 0.0 || static_cast<int>(built_at_.size()) != n)
    return std::numeric_limits<double>::infinity();
  const double half = 0.5 * options_.neighbour_skin * options_.spacing;
  double moved = 0.0;
#pragma omp parallel for schedule(static) reduction(max : moved)
  for (int i = 0; i < n; ++i) moved = std::max(moved, (p_.x[i] - built_at_[i]).squaredNorm());
  return std::sqrt(moved) / half;
}

template <int Dim>
bool AdaptiveSph<Dim>::lists_hold() const {
  return skin_used() < 1.0;
}

template <int Dim>
void AdaptiveSph<Dim>::within_support(NeighbourLists& exact) const {
  // Two passes over the rows (count, then fill at the counted offsets), so both run in parallel.
  // `exact` is a member's storage, kept from one resampling to the next (fresh pages cost more).
  const int n = p_.size();
  exact.begin.assign(n + 1, 0);
  auto within = [&](int i, int j) {
    const double r = std::max(p_.radius[i], p_.radius[j]);
    return (p_.x[i] - p_.x[j]).squaredNorm() < r * r;
  };
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i) {
    std::int64_t count = 0;
    for (int j : nbrs_.of(i)) count += within(i, j) ? 1 : 0;
    exact.begin[i + 1] = count;
  }
  for (int i = 0; i < n; ++i) exact.begin[i + 1] += exact.begin[i];
  exact.index.resize(static_cast<std::size_t>(exact.begin[n]));
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i) {
    std::int64_t at = exact.begin[i];
    for (int j : nbrs_.of(i))
      if (within(i, j)) exact.index[static_cast<std::size_t>(at++)] = j;
  }
}

template <int Dim>
SphStepReport AdaptiveSph<Dim>::adapt_now() {
  SphStepReport report;
  {
    auto t = timer_.scope("neighbours");
    if (lists_hold())
      tree_.build(p_.x);
    else
      find_neighbours_now(true);
  }
  redistance_and_resample(report);
  report.particles = p_.size();
  return report;
}

template <int Dim>
void AdaptiveSph<Dim>::redistance_and_resample(SphStepReport& report) {
  if (options_.neighbour_skin > 0.0) {
    auto t = timer_.scope("neighbours");
    within_support(skinless_);
  }
  const NeighbourLists& exact = options_.neighbour_skin > 0.0 ? skinless_ : nbrs_;
  {
    auto t = timer_.scope("redistance");
    report.redistancing = redistance<Dim>(p_, exact, tree_, options_.projection_bisections,
                                          options_.disk_radius, options_.march);
  }
  report.resampled = true;
  if (!options_.adaptive) return;
  {
    auto t = timer_.scope("elfs");
    if (options_.wall_footpoints) footpoints_onto_walls();
    report.features = feature_size<Dim>(p_, exact, options_.gamma_degrees, nullptr, options_.march);
    if (options_.view.active()) {
      const int n = p_.size();
#pragma omp parallel for schedule(static)
      for (int i = 0; i < n; ++i) p_.elfs[i] += options_.view.distance(p_.x[i]);
    }
  }
  // Patched lists stay right however much of the skin is used: a survivor that has moved half the
  // skin is refreshed alone at the next step (refresh_movers), which costs less than a new search.
  const bool patch = options_.neighbour_skin > 0.0 && options_.patch_lists;
  std::vector<std::int32_t> origin;
  {
    auto t = timer_.scope("resample");
    // A child inside the collisions' margin would be moved there before the next step: closer to its
    // neighbours than the split allows, and away from the position its kept list was built at.
    const SolidTest<Dim> solid = [this](const Vec<Dim>& x) { return in_collision_margin(x); };
    ResampleOptions o = options_.resampling;
    o.now = steps_;
    // "Within N passes", in steps: back to the N-th last pass (all of the run while there were fewer).
    const auto window = [this](int passes) -> std::int64_t {
      if (passes <= 0) return 0;
      if (pass_steps_.size() < static_cast<std::size_t>(passes)) return steps_ + 1;
      return steps_ - pass_steps_[pass_steps_.size() - passes];
    };
    o.merge_min_age = window(options_.merge_min_passes);
    o.churn_window = window(kChurnPasses);
    report.resampling = resample<Dim>(p_, exact, sizes_, o, solid, rng_, &origin);
  }
  if (report.resampling.split + report.resampling.merged == 0) return;
  if (patch) {
    auto t = timer_.scope("neighbours");
    patch_lists(origin);
  } else {
    built_at_.clear();
  }
}

template <int Dim>
CellGrid<Dim> AdaptiveSph<Dim>::grid_of(std::span<const Vec<Dim>> built) const {
  double max_reach = 0.0;
  for (double r : p_.radius) max_reach = std::max(max_reach, r);
  CellGrid<Dim> grid;
  grid.build(built, max_reach + options_.neighbour_skin * options_.spacing);
  return grid;
}

template <int Dim>
template <class Skip>
void AdaptiveSph<Dim>::partners_of(const CellGrid<Dim>& grid, std::span<const Vec<Dim>> built, int k,
                                   Skip skip, std::vector<std::int32_t>& out) const {
  const double skin = options_.neighbour_skin * options_.spacing;
  grid.candidates(built[k], [&](int j) {
    if (j == k || skip(j)) return;
    const double reach = std::max(p_.radius[k], p_.radius[j]) + skin;
    if ((built[k] - built[j]).squaredNorm() < reach * reach) out.push_back(j);
  });
}

template <int Dim>
void AdaptiveSph<Dim>::patch_lists(const std::vector<std::int32_t>& origin) {
  // Kept lists hold every pair within max(r_i, r_j) + skin at the built positions, and stay valid
  // while no particle has moved half the skin from its own. Survivors keep their built positions
  // and rows (renumbered, removed particles dropped). A new particle (origin -1: born in a split or
  // merge, or one that has moved half the skin, refresh_movers) is built where it is now,
  // with every pair within max(r_i, r_j) + skin between its position and the others' built
  // positions: at any later time both have moved less than half the skin, so a pair within
  // max(r_i, r_j) then is in the list. The results are those of a new search, to the bit.
  const int n = p_.size(), n_old = nbrs_.n_particles();
  std::vector<std::int32_t> renumber(n_old, -1);
  std::vector<Vec<Dim>> built(n);
  std::vector<std::int32_t> born;
  std::vector<char> is_born(n, 0);
  for (int k = 0; k < n; ++k) {
    if (origin[k] >= 0) {
      renumber[origin[k]] = k, built[k] = built_at_[origin[k]];
    } else {
      built[k] = p_.x[k], is_born[k] = 1;
      born.push_back(k);
    }
  }
  // The new particles' pairs, each found once: from the new particle's side, or from the lower
  // index's when both are new.
  const CellGrid<Dim> grid = grid_of(built);
  std::vector<std::vector<std::int32_t>> partners(born.size());
#pragma omp parallel for schedule(dynamic, 64)
  for (int b = 0; b < static_cast<int>(born.size()); ++b)
    partners_of(
        grid, built, born[b], [&](int j) { return is_born[j] && j < born[b]; }, partners[b]);
  // The rows are written into the spare lists, whose storage is kept between patches: fresh pages
  // for every patch cost more than the copy itself. Survivors keep their order (resampling compacts
  // in place), so a survivor's kept entries stay ascending and only the rows that gained a new
  // particle's pair need sorting.
  bool in_order = true;
  for (int k = 0, last = -1; k < n; ++k) {
    if (origin[k] < 0) continue;
    in_order = in_order && origin[k] > last;
    last = origin[k];
  }
  std::vector<char> gained(n, in_order ? 0 : 1);
  NeighbourLists& lists = spare_;
  // Each row gets room to grow (row_room), so that refresh_movers can rewrite a few rows in place.
  std::vector<std::int64_t> size(n, 0);
#pragma omp parallel for schedule(static)
  for (int k = 0; k < n; ++k) {
    std::int64_t kept = 0;
    if (origin[k] >= 0)
      for (int j : nbrs_.of(origin[k])) kept += renumber[j] >= 0 ? 1 : 0;
    size[k] = kept;
  }
  for (std::size_t b = 0; b < born.size(); ++b) {
    gained[born[b]] = 1;
    for (std::int32_t j : partners[b]) ++size[born[b]], ++size[j], gained[j] = 1;
  }
  lists.begin.resize(n + 1);
  lists.end.resize(n);
  lists.room.resize(n);
  lists.begin[0] = 0;
  for (int k = 0; k < n; ++k) {
    lists.end[k] = lists.begin[k] + size[k];
    lists.room[k] = lists.end[k] + row_room(size[k]);
    lists.begin[k + 1] = lists.room[k];
  }
  lists.index.reserve(static_cast<std::size_t>(lists.begin[n] + lists.begin[n] / 4));
  lists.index.resize(static_cast<std::size_t>(lists.begin[n]));
  packed_entries_ = lists.begin[n];
  std::vector<std::int64_t> at(lists.begin.begin(), lists.begin.end() - 1);
#pragma omp parallel for schedule(static)
  for (int k = 0; k < n; ++k)
    if (origin[k] >= 0)
      for (int j : nbrs_.of(origin[k]))
        if (renumber[j] >= 0) lists.index[static_cast<std::size_t>(at[k]++)] = renumber[j];
  const std::vector<std::int64_t> kept_end = at;
  for (std::size_t b = 0; b < born.size(); ++b)
    for (std::int32_t j : partners[b]) {
      lists.index[static_cast<std::size_t>(at[born[b]]++)] = j;
      lists.index[static_cast<std::size_t>(at[j]++)] = born[b];
    }
#pragma omp parallel for schedule(dynamic, 1024)
  for (int k = 0; k < n; ++k) {
    if (!gained[k]) continue;
    // A survivor's gained pairs come after its kept ones, in ascending order (the new particles are
    // visited in it): each is moved down into place (an insertion merge; std::inplace_merge would
    // allocate a buffer per row). A new particle's row is sorted whole.
    const auto first = lists.index.begin() + lists.begin[k], last = lists.index.begin() + lists.end[k];
    if (is_born[k] || !in_order) {
      std::sort(first, last);
      continue;
    }
    for (auto it = lists.index.begin() + kept_end[k]; it != last; ++it) {
      const std::int32_t j = *it;
      auto hole = it;
      for (; hole != first && *(hole - 1) > j; --hole) *hole = *(hole - 1);
      *hole = j;
    }
  }
  std::swap(nbrs_, spare_);
  built_at_ = std::move(built);
}

template <int Dim>
int AdaptiveSph<Dim>::refresh_movers() {
  const int n = p_.size();
  if (!(options_.neighbour_skin > 0.0 && options_.patch_lists) || static_cast<int>(built_at_.size()) != n ||
      nbrs_.n_particles() != n)
    return 0;
  // A particle that has moved half the skin is treated as born where it is now; the others keep
  // their rows and built positions (see patch_lists).
  const double half = 0.5 * options_.neighbour_skin * options_.spacing;
  std::vector<std::int32_t> origin(n);
  int movers = 0;
  for (int i = 0; i < n; ++i) {
    const bool moved = (p_.x[i] - built_at_[i]).squaredNorm() >= half * half;
    origin[i] = moved ? -1 : i;
    movers += moved ? 1 : 0;
  }
  if (movers == 0 || movers > n / 10) return 0;
  if (nbrs_.packed()) {
    // Lists of a whole search: every row gets its own storage as its room (none to spare).
    nbrs_.end.assign(nbrs_.begin.begin() + 1, nbrs_.begin.end());
    nbrs_.room = nbrs_.end;
    packed_entries_ = static_cast<std::int64_t>(nbrs_.index.size());
  }
  // Rows that outgrow their room move to the end of the storage; past a quarter more than packed,
  // the whole lists are written again (patch_lists packs them, each row with its room).
  if (static_cast<std::int64_t>(nbrs_.index.size()) > packed_entries_ + packed_entries_ / 4) {
    patch_lists(origin);
    return movers;
  }
  std::vector<std::int32_t> moved;
  moved.reserve(static_cast<std::size_t>(movers));
  for (int i = 0; i < n; ++i)
    if (origin[i] < 0) moved.push_back(i);
  refresh_in_place(moved);
  return movers;
}

template <int Dim>
void AdaptiveSph<Dim>::refresh_in_place(const std::vector<std::int32_t>& movers) {
  // The movers are built where they are now, their rows found again around them in a grid of the
  // built positions (as in patch_lists). A survivor's row changes only by the movers that entered or
  // left its reach: those entries are put in or taken out in place, keeping the row ascending. The
  // lists are then exactly those a whole search at the built positions would give.
  const int n = p_.size(), n_movers = static_cast<int>(movers.size());
  LIQUID_VERIFY(n < (1 << 30), "sph: {} particles are too many for the refresh's edit keys (2 index + 1)", n);
  std::vector<char> is_mover(n, 0);
  for (std::int32_t k : movers) is_mover[k] = 1, built_at_[k] = p_.x[k];
  const CellGrid<Dim> grid = grid_of(built_at_);
  std::vector<std::vector<std::int32_t>> partners(n_movers);
  // Survivors' edits: (row, 2 mover + 1 if it leaves the row, + 0 if it enters it), so that sorting
  // puts each row's edits in the movers' order.
  using Edit = std::pair<std::int32_t, std::int32_t>;
  std::vector<std::vector<Edit>> edits(n_movers);
#pragma omp parallel for schedule(dynamic, 16)
  for (int m = 0; m < n_movers; ++m) {
    const int k = movers[m];
    std::vector<std::int32_t>& row = partners[m];
    partners_of(
        grid, built_at_, k, [](int) { return false; }, row);
    std::sort(row.begin(), row.end());
    const auto old = nbrs_.of(k);
    std::size_t a = 0, b = 0;
    while (a < old.size() || b < row.size()) {
      if (b == row.size() || (a < old.size() && old[a] < row[b])) {
        if (!is_mover[old[a]]) edits[m].emplace_back(old[a], 2 * k + 1);
        ++a;
      } else if (a == old.size() || row[b] < old[a]) {
        if (!is_mover[row[b]]) edits[m].emplace_back(row[b], 2 * k);
        ++b;
      } else {
        ++a, ++b;
      }
    }
  }
  std::vector<Edit> all;
  for (const auto& e : edits) all.insert(all.end(), e.begin(), e.end());
  std::sort(all.begin(), all.end());
  // Where each changed row goes: in its own storage when it fits, else at the end.
  std::vector<std::int32_t> edited;  // the first edit of each survivor's row in `all`
  for (std::size_t e = 0; e < all.size(); ++e)
    if (e == 0 || all[e].first != all[e - 1].first) edited.push_back(static_cast<std::int32_t>(e));
  const int n_edited = static_cast<int>(edited.size());
  std::vector<std::int64_t> from(n_edited), new_size(n_edited);
  std::int64_t tail = static_cast<std::int64_t>(nbrs_.index.size());
  auto place = [&](int row, std::int64_t need) {
    if (nbrs_.begin[row] + need <= nbrs_.room[row]) return;
    nbrs_.begin[row] = tail;
    nbrs_.room[row] = tail + need + row_room(need);
    tail = nbrs_.room[row];
  };
  for (int m = 0; m < n_movers; ++m) place(movers[m], static_cast<std::int64_t>(partners[m].size()));
  for (int r = 0; r < n_edited; ++r) {
    const std::size_t first = static_cast<std::size_t>(edited[r]);
    const std::size_t last = r + 1 < n_edited ? static_cast<std::size_t>(edited[r + 1]) : all.size();
    const int row = all[first].first;
    std::int64_t grow = 0;
    for (std::size_t e = first; e < last; ++e) grow += (all[e].second & 1) ? -1 : 1;
    from[r] = nbrs_.begin[row];
    new_size[r] = nbrs_.end[row] - nbrs_.begin[row] + grow;
    place(row, new_size[r]);
  }
  nbrs_.index.resize(static_cast<std::size_t>(tail));
#pragma omp parallel for schedule(dynamic, 16)
  for (int m = 0; m < n_movers; ++m) {
    const int k = movers[m];
    std::copy(partners[m].begin(), partners[m].end(), nbrs_.index.begin() + nbrs_.begin[k]);
    nbrs_.end[k] = nbrs_.begin[k] + static_cast<std::int64_t>(partners[m].size());
  }
#pragma omp parallel
  {
    std::vector<std::int32_t> merged;
#pragma omp for schedule(dynamic, 64)
    for (int r = 0; r < n_edited; ++r) {
      const std::size_t first = static_cast<std::size_t>(edited[r]);
      const std::size_t last = r + 1 < n_edited ? static_cast<std::size_t>(edited[r + 1]) : all.size();
      const int row = all[first].first;
      merged.clear();
      std::size_t e = first;
      for (std::int64_t q = from[r]; q < nbrs_.end[row]; ++q) {
        const std::int32_t j = nbrs_.index[static_cast<std::size_t>(q)];
        // Movers entering before j (one leaving lies at its own entry: the row holds it).
        for (; e < last && all[e].second < 2 * j; ++e) {
          LIQUID_ASSERT(all[e].second % 2 == 0, "sph: mover {} left a row ({}) that did not hold it",
                        all[e].second / 2, row);
          merged.push_back(all[e].second / 2);
        }
        if (e < last && all[e].second == 2 * j + 1) {
          ++e;  // j left this row's reach
          continue;
        }
        merged.push_back(j);
      }
      for (; e < last; ++e) {
        LIQUID_ASSERT(all[e].second % 2 == 0, "sph: mover {} left a row ({}) that did not hold it",
                      all[e].second / 2, row);
        merged.push_back(all[e].second / 2);
      }
      LIQUID_ASSERT(static_cast<std::int64_t>(merged.size()) == new_size[r],
                    "sph: a refreshed row lost count");
      std::copy(merged.begin(), merged.end(), nbrs_.index.begin() + nbrs_.begin[row]);
      nbrs_.end[row] = nbrs_.begin[row] + new_size[r];
    }
  }
}

template <int Dim>
void AdaptiveSph<Dim>::collide() {
  const double margin = collision_margin(), e = options_.restitution;
  const Box<Dim>& box = options_.container;
  const int n = p_.size();
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i) {
    Vec<Dim>& x = p_.x[i];
    Vec<Dim>& v = p_.v[i];
    for (const auto& obstacle : options_.obstacles) {
      const double phi = obstacle(x);
      if (phi >= margin) continue;
      const Vec<Dim> g = levelset::gradient(obstacle, x, 1e-6 * options_.spacing);
      const double gn = g.norm();
      if (!(gn > 0.0)) continue;
      const Vec<Dim> nrm = g / gn;
      x += (margin - phi) * nrm;
      const double vn = v.dot(nrm);
      if (vn < 0.0) v -= (1.0 + e) * vn * nrm;
    }
    for (int d = 0; d < Dim; ++d) {
      if (x[d] < box.lo[d] + margin) {
        x[d] = box.lo[d] + margin;
        if (v[d] < 0.0) v[d] = -e * v[d];
      } else if (x[d] > box.hi[d] - margin) {
        x[d] = box.hi[d] - margin;
        if (v[d] > 0.0) v[d] = -e * v[d];
      }
    }
  }
}

template <int Dim>
bool AdaptiveSph<Dim>::resampling_due() const {
  if (options_.resample_travel <= 0.0) return steps_ % options_.resample_every == 0;  // the paper's cadence
  if (pass_steps_.empty()) return true;
  const std::int64_t since = steps_ - pass_steps_.back();
  if (since < options_.resample_every) return false;
  for (const SphSource<Dim>& src : options_.sources)
    if (src.active(time_)) return since % options_.resample_every == 0;
  return travel_ >= options_.resample_travel * options_.spacing;
}

template <int Dim>
SphStepReport AdaptiveSph<Dim>::advance(double dt) {
  LIQUID_VERIFY(dt > 0.0 && std::isfinite(dt), "sph: the time step must be positive and finite, not {}", dt);
  auto total = timer_.scope("total");
  const SerialScope one_thread(p_.size() < options_.serial_below);
  const bool resampling = resampling_due();
  SphStepReport report;
  const auto phase = [this](const char* name, auto&& body) {
    const auto t = timer_.scope(name);
    body();
  };
  if (!options_.sources.empty()) phase("sources", [&] { report.emitted = apply_sources(); });
  phase("neighbours", [&] { update_neighbours(resampling, report); });
  std::vector<Vec<Dim>> shift;  // FluidConstants::shifting: from the rate's pairs
  phase("forces", [&] { forces(dt, report, shift); });
  if (resampling) {
    redistance_and_resample(report);  // timed as redistance, elfs and resample
    travel_ = 0.0;
    pass_steps_.push_back(steps_);
    if (pass_steps_.size() > static_cast<std::size_t>(kPassHistory)) pass_steps_.erase(pass_steps_.begin());
  }
  // Split or merged particles have no shift of their own: none this step.
  if (static_cast<int>(shift.size()) != p_.size() || report.resampling.split + report.resampling.merged > 0)
    shift.clear();
  phase("integrate", [&] { integrate(dt, shift); });
  phase("collisions", [&] { collide(); });
  time_ += dt;
  ++steps_;
  tally(dt, report);
  travel_ += report.max_speed * dt;
  return report;
}

template <int Dim>
void AdaptiveSph<Dim>::update_neighbours(bool resampling, SphStepReport& report) {
  // Lists that still hold serve a resampling step too (every sum skips the skin's pairs, so the
  // results are the same to the bit); redistancing needs only the point tree at today's positions.
  report.searched = !lists_hold();
  if (report.searched) {
    report.refreshed = refresh_movers();
    report.searched = report.refreshed == 0;
  }
  if (report.searched)
    find_neighbours_now(resampling);
  else if (resampling)
    tree_.build(p_.x);
  report.pairs = nbrs_.n_pairs();
}

template <int Dim>
void AdaptiveSph<Dim>::forces(double dt, SphStepReport& report, std::vector<Vec<Dim>>& shift) {
  const Vec<Dim> gravity = gravity_at(time_);
  if (options_.fluid.density_update == DensityUpdate::summation) {
    compute_density<Dim>(p_, nbrs_, options_.fluid, &walls_);
  } else {
    if (options_.fluid.free_particles_at_rest)
      report.rested = rest_free_particles<Dim>(p_, nbrs_, options_.fluid, &walls_);
    compute_pressure<Dim>(p_, options_.fluid);
  }
  compute_accelerations<Dim>(p_, nbrs_, options_.fluid, gravity, &walls_);
  if (options_.rotation.active()) add_frame_accelerations(dt);
  if (options_.fluid.density_update == DensityUpdate::continuity)
    compute_density_rate<Dim>(p_, nbrs_, options_.fluid, gravity, &walls_,
                              options_.fluid.kicked_density_rate ? dt : 0.0,
                              options_.fluid.shifting > 0.0 ? &shift : nullptr);
  for (int i = 0; i < p_.size(); ++i) {
    if (!std::isfinite(p_.density[i]) || !std::isfinite(p_.drho[i]) || !p_.a[i].allFinite())
      throw_not_finite(i);
    const double excess = p_.density[i] / options_.fluid.rest_density - 1.0;
    report.max_density_error = std::max(report.max_density_error, std::abs(excess));
    report.max_compression = std::max(report.max_compression, excess);
  }
}

template <int Dim>
void AdaptiveSph<Dim>::integrate(double dt, const std::vector<Vec<Dim>>& shift) {
  const int n = p_.size();
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i) {
    p_.v[i] += dt * p_.a[i];
    p_.x[i] += dt * p_.v[i];
    if (!shift.empty() && p_.distance[i] >= p_.radius[i])
      p_.x[i] -= (options_.fluid.shifting * p_.radius[i] * p_.radius[i]) * shift[i];
  }
  if (options_.fluid.density_update != DensityUpdate::continuity) return;
  for (int i = 0; i < n; ++i) {
    const double before = p_.density[i];
    p_.density[i] += dt * p_.drho[i];
    // A density at or below zero makes the particle's volume infinite and every pair with it
    // NaN: stop here, at the particle, rather than at the first neighbour the NaN reaches.
    if (!(p_.density[i] > 0.0))
      throw Error(fmt::format(
          "sph: particle {} (level {}) at step {}, t = {} s: its density fell from {:.6g} to {:.6g} "
          "(rate {:.6g} over dt = {:.3g} s); the step is too large for this flow (lower the scene's "
          "[time] cfl); position ({}), velocity ({})",
          i, int(p_.level[i]), steps_, time_, before, p_.density[i], p_.drho[i], dt, fmt::join(p_.x[i], ", "),
          fmt::join(p_.v[i], ", ")));
  }
}

template <int Dim>
void AdaptiveSph<Dim>::tally(double dt, SphStepReport& report) const {
  report.dt = dt;
  report.particles = p_.size();
  report.per_level.assign(options_.max_level + 1, 0);
  for (int i = 0; i < p_.size(); ++i) {
    ++report.per_level[std::min<int>(p_.level[i], options_.max_level)];
    report.max_speed = std::max(report.max_speed, p_.v[i].norm());
  }
}

template <int Dim>
void AdaptiveSph<Dim>::throw_not_finite(int i) const {
  // Names the particle and the first of its terms that is not finite.
  std::string culprit;
  if (!std::isfinite(p_.density[i]))
    culprit = "its own density (carried from the last step)";
  else if (!std::isfinite(p_.drho[i]))
    culprit = "its density rate (continuity and density diffusion)";
  else
    for (int j : nbrs_.of(i))
      if (!pair_force<Dim>(p_, i, j, options_.fluid).allFinite()) {
        culprit = fmt::format(
            "the pair force from particle {} (level {}, {:.3g} away, density {:.6g}, velocity {})", j,
            int(p_.level[j]), (p_.x[i] - p_.x[j]).norm(), p_.density[j], fmt::join(p_.v[j], ", "));
        break;
      }
  if (culprit.empty() && !walls_.share_gradient(p_.x[i], p_.radius[i], options_.fluid.kernels).allFinite())
    culprit = "the walls' push";
  else if (culprit.empty() && !p_.v[i].allFinite())
    culprit = "its own velocity (the last step's kick)";
  else if (culprit.empty())
    culprit = "none found among its pair forces, the walls and its velocity";
  throw Error(fmt::format(
      "sph: particle {} (level {}) at step {}, t = {} s: density {}, its rate {}, acceleration ({}): not all "
      "finite; position ({}), velocity ({}), pressure {}; not finite: {}",
      i, int(p_.level[i]), steps_, time_, p_.density[i], p_.drho[i], fmt::join(p_.a[i], ", "),
      fmt::join(p_.x[i], ", "), fmt::join(p_.v[i], ", "), p_.pressure[i], culprit));
}

template <int Dim>
void AdaptiveSph<Dim>::relax(double duration, const Box<Dim>* hold) {
  LIQUID_VERIFY(duration >= 0.0 && std::isfinite(duration), "sph: the relaxation time must be >= 0, not {}",
                duration);
  const Box<Dim> container = options_.container;
  // The liquid settles in a still container without inflow; whatever happens (a step may throw),
  // the container, its sources and its turn come back.
  struct Restore {
    AdaptiveSph& sim;
    const Box<Dim>& box;
    bool held;
    std::vector<SphSource<Dim>> sources;
    SphRotation<Dim> rotation;
    ~Restore() {
      sim.options_.sources = std::move(sources);
      sim.options_.rotation = rotation;
      if (!held) return;
      sim.options_.container = box;
      sim.walls_ = Boundary<Dim>(box, sim.options_.obstacles);
    }
  } restore{*this, container, hold != nullptr, std::move(options_.sources), options_.rotation};
  options_.sources.clear();
  options_.rotation.angle = 0.0;
  if (hold) {
    LIQUID_VERIFY(hold->valid(), "sph: the box that holds the liquid while it settles must have lo < hi");
    options_.container = *hold;
    walls_ = Boundary<Dim>(*hold, options_.obstacles);
  }
  const double tau = duration / 8.0;
  double t = 0.0;
  while (t < duration) {
    const double dt = std::min(stable_dt(), duration - t);
    if (dt <= 0.0) break;
    advance(dt);
    const double damp = std::exp(-dt / tau);
    for (auto& v : p_.v) v *= damp;
    t += dt;
  }
  for (auto& v : p_.v) v.setZero();
  time_ = 0.0, steps_ = 0, travel_ = 0.0;
  pass_steps_.clear();
  // The clock restarts: nothing is young at t = 0 (the resampling at rest made what it made).
  std::fill(p_.born.begin(), p_.born.end(), -1);
  std::fill(p_.birth.begin(), p_.birth.end(), SphParticles<Dim>::Birth::seeded);
  timer_.clear();
}

template <int Dim>
double AdaptiveSph<Dim>::stable_dt(double cfl, double max_dt) const {
  const double s = options_.spacing;
  const double c = std::sqrt(options_.fluid.stiffness / options_.fluid.rest_density);
  double vmax = 0.0, amax = 0.0;
  for (int i = 0; i < p_.size(); ++i)
    vmax = std::max(vmax, p_.v[i].norm()), amax = std::max(amax, p_.a[i].norm());
  double dt = std::min(max_dt, cfl * s / (c + vmax));
  if (amax > 0.0) dt = std::min(dt, 0.25 * std::sqrt(s / amax));
  if (options_.fluid.viscosity > 0.0)
    dt = std::min(dt, 0.125 * options_.fluid.rest_density * s * s / options_.fluid.viscosity);
  return dt;
}

template <int Dim>
SphState<Dim> AdaptiveSph<Dim>::state() const {
  SphState<Dim> st;
  st.particles = p_;
  st.time = time_;
  st.steps = steps_;
  st.travel = travel_;
  st.pass_steps = pass_steps_;
  std::ostringstream text;
  text << rng_;
  st.rng = text.str();
  return st;
}

template <int Dim>
void AdaptiveSph<Dim>::restore(SphState<Dim> st) {
  built_at_.clear();
  const SphParticles<Dim>& q = st.particles;
  const std::size_t n = q.x.size();
  LIQUID_VERIFY(q.v.size() == n && q.a.size() == n && q.level.size() == n && q.mass.size() == n &&
                    q.radius.size() == n && q.density.size() == n && q.drho.size() == n &&
                    q.pressure.size() == n && q.distance.size() == n && q.foot.size() == n &&
                    q.elfs.size() == n && q.birth.size() == n && q.born.size() == n,
                "sph: the saved particle arrays differ in length");
  for (std::size_t i = 0; i < n; ++i) {
    LIQUID_VERIFY(q.level[i] >= 0 && q.level[i] <= options_.max_level,
                  "sph: saved particle {} has level {}, outside 0..{}", i, int(q.level[i]),
                  options_.max_level);
    LIQUID_VERIFY(
        q.mass[i] == sizes_.mass_of(q.level[i]),
        "sph: saved particle {} has mass {}, not its level's {} (other fluid constants or spacing?)", i,
        q.mass[i], sizes_.mass_of(q.level[i]));
    LIQUID_VERIFY(q.radius[i] == sizes_.radius_of<Dim>(q.level[i]),
                  "sph: saved particle {} has radius {}, not its level's {}", i, q.radius[i],
                  sizes_.radius_of<Dim>(q.level[i]));
    // Inside the container (within a tenth of its size), finite, and a density a weakly
    // compressible liquid can hold: anything else is a damaged checkpoint, not a state to run.
    const Vec<Dim> slack = 0.1 * options_.container.size();
    bool inside = true;
    for (int k = 0; k < Dim; ++k)
      inside = inside && q.x[i][k] >= options_.container.lo[k] - slack[k] &&
               q.x[i][k] <= options_.container.hi[k] + slack[k];
    LIQUID_VERIFY(inside, "sph: saved particle {} at ({:.6g}) lies outside the container", i,
                  fmt::join(q.x[i].data(), q.x[i].data() + Dim, ", "));
    // The distance and the feature size are infinite until a surface is found: NaN alone is damage.
    LIQUID_VERIFY(q.v[i].allFinite() && q.a[i].allFinite() && q.foot[i].allFinite() &&
                      std::isfinite(q.drho[i]) && std::isfinite(q.pressure[i]) &&
                      !std::isnan(q.distance[i]) && !std::isnan(q.elfs[i]),
                  "sph: saved particle {} has a value that is not finite (velocity, acceleration, footpoint, "
                  "density rate, pressure; or a NaN distance or feature size)",
                  i);
    LIQUID_VERIFY(static_cast<int>(q.birth[i]) >= 0 && static_cast<int>(q.birth[i]) <= 2 && q.born[i] >= -1 &&
                      q.born[i] <= st.steps &&
                      (q.born[i] >= 0) == (q.birth[i] != SphParticles<Dim>::Birth::seeded),
                  "sph: saved particle {} has birth {} at step {}, not a split or merge at or before step {} "
                  "(or a seeded particle, at -1)",
                  i, static_cast<int>(q.birth[i]), q.born[i], st.steps);
    const double rho0 = options_.fluid.rest_density;
    LIQUID_VERIFY(q.density[i] > 0.0 && q.density[i] <= kMaxSavedDensity * rho0,
                  "sph: saved particle {} has density {}, outside (0, {} rest densities]", i, q.density[i],
                  kMaxSavedDensity);
  }
  LIQUID_VERIFY(std::isfinite(st.time) && st.time >= 0.0 && st.steps >= 0,
                "sph: the saved clock is not valid");
  LIQUID_VERIFY(
      std::isfinite(st.travel) && st.travel >= 0.0 &&
          st.pass_steps.size() <= static_cast<std::size_t>(kPassHistory) &&
          std::is_sorted(st.pass_steps.begin(), st.pass_steps.end()) &&
          (st.pass_steps.empty() || (st.pass_steps.front() >= 0 && st.pass_steps.back() <= st.steps)),
      "sph: the saved resampling clock is not valid (travel {}, {} past passes, step {})", st.travel,
      st.pass_steps.size(), st.steps);
  std::istringstream text(st.rng);
  std::mt19937_64 rng;
  text >> rng;
  LIQUID_VERIFY(!text.fail(), "sph: the saved random stream cannot be read");
  p_ = std::move(st.particles);
  time_ = st.time;
  steps_ = st.steps;
  travel_ = st.travel;
  pass_steps_ = std::move(st.pass_steps);
  rng_ = rng;
}

template struct SphView<2>;
template struct SphView<3>;
template struct SphRotation<2>;
template struct SphRotation<3>;
template struct SphOptions<2>;
template struct SphOptions<3>;
template class AdaptiveSph<2>;
template class AdaptiveSph<3>;

}  // namespace liquid::sph
