#pragma once
// AdaptiveSph<Dim>: the adaptively sampled particle fluid of Adams et al. 2007. A step reads as
// named, timed phases (PhaseTimer names):
//   sources     (scenes with sources) particles inside an active source take its velocity; new
//               level-0 particles fill the free points of its lattice
//   neighbours  the symmetric neighbour lists (cell list or k-d tree, SphOptions::search; the tree
//               is built on redistancing steps either way)
//   forces      density, pressure, pair forces, gravity
//   redistance  (on pass steps: SphOptions::resample_every, resample_travel) particle-to-surface
//               distances on the distance surface
//   elfs        (pass steps, adaptive) medial axis and extended local feature size (plus the
//               distance to the view, with SphOptions::view)
//   resample    (pass steps, adaptive) split and merge
//   integrate   leap-frog: v += dt a, x += dt v (velocities live at half steps), plus the particle
//               shift (FluidConstants::shifting) away from crowded parts of the liquid
//   collisions  particles pushed out of obstacles and back into the container, inward velocity removed
//   total
// With adaptive = false every particle stays at level 0 (the single-resolution simulation the paper
// compares with); the distances are still redistanced, so both carry the same surface.

#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "liquid/core/timer.hpp"
#include "liquid/levelset/levelset.hpp"
#include "liquid/sph/boundary.hpp"
#include "liquid/sph/distance_surface.hpp"
#include "liquid/sph/feature_size.hpp"
#include "liquid/sph/forces.hpp"
#include "liquid/sph/neighbours.hpp"
#include "liquid/sph/resample.hpp"
#include "liquid/sph/sph_particles.hpp"

namespace liquid::sph {

/// An inflow. While start <= t < stop, every particle inside `region` (negative inside) moves at
/// `velocity`, and a level-0 particle is added at each point of a lattice of the level-0 spacing over
/// `bounds` that lies inside `region`, outside the solids, and has no particle closer than the two
/// particles' mean spacing: a steady inflow then enters at the rest spacing.
template <int Dim>
struct SphSource {
  levelset::Function<Dim> region;
  Box<Dim> bounds;  ///< holds the region's inside
  Vec<Dim> velocity = Vec<Dim>::Zero();
  double start = 0.0, stop = std::numeric_limits<double>::infinity();
  bool active(double t) const { return t >= start && t < stop; }
};

/// A container that turns (the paper's desk toy, Fig. 7) about `pivot`: by theta(t) = angle (u -
/// sin(2 pi u) / (2 pi)), u = t / duration, until `duration`, then it rests at `angle` (radians; about
/// the z axis in 2D, about `axis` in 3D). The turn starts and ends with no angular velocity or
/// acceleration, so leap-frog's first kick needs no half step and the turn stays second order in dt.
/// The simulation runs in the container's frame (walls and obstacles stand still): gravity turns the
/// other way and the fictitious accelerations are added (Euler -w' x r, Coriolis -2 w x v,
/// centrifugal -w x (w x r), r from the pivot), exactly. world() maps a container point to the world.
template <int Dim>
struct SphRotation {
  double angle = 0.0;     ///< radians; 0: the container stands still
  double duration = 1.0;  ///< seconds of the turn
  Vec<Dim> pivot = Vec<Dim>::Zero();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  ///< 3D only (a unit vector)
  bool active() const { return angle != 0.0; }
  double theta(double t) const;
  double omega(double t) const;       ///< d theta / dt
  double omega_rate(double t) const;  ///< d^2 theta / dt^2
  /// v turned by the angle a (about z in 2D, `axis` in 3D).
  Vec<Dim> turn(const Vec<Dim>& v, double a) const;
  /// A point of the container's frame at time t in the world's.
  Vec<Dim> world(const Vec<Dim>& x, double t) const { return pivot + turn(x - pivot, theta(t)); }
};

/// The view-dependent sampling condition of Sec. 4.3: each particle's elfs gets its distance to the
/// region in view added before the split/merge test (split when elfs + d_view < alpha r_i, merge
/// when > beta r_i), so liquid out of sight coarsens. The paper's view frustum is taken as the cone
/// of the camera's field of view (a wedge in 2D): apex `eye`, axis towards `target`, half-angle
/// `half_angle` (radians, within (0, pi/2)); d_view is the exact distance to that cone, 0 inside.
template <int Dim>
struct SphView {
  Vec<Dim> eye = Vec<Dim>::Zero(), target = Vec<Dim>::Ones();
  double half_angle = 0.0;  ///< 0: no view condition
  bool active() const { return half_angle > 0.0; }
  double distance(const Vec<Dim>& x) const;
};

/// Churn's window, in resampling passes: a particle made by a split and merged within it, or made by
/// a merge and split within it, counts as churn (ResampleStats::churn_merged, churn_split).
inline constexpr int kChurnPasses = 3;
/// How many past passes' steps a simulation keeps: the longest merge wait (1000 passes) and one more.
inline constexpr int kPassHistory = 1001;

template <int Dim>
struct SphOptions {
  Box<Dim> container;                              ///< the tank: particles stay inside it
  std::vector<levelset::Function<Dim>> obstacles;  ///< solids, negative inside
  Vec<Dim> gravity = Vec<Dim>::Unit(1) * -9.81;
  FluidConstants fluid;
  double spacing = 0.02;  ///< level-0 particle spacing (m); support radius = h_ratio * spacing
  double h_ratio = 2.5;   ///< the paper's h
  bool adaptive = true;
  int max_level = 3;       ///< coarsest level a merge may make
  int resample_every = 5;  ///< redistance / elfs / resample at most every k-th step (paper: every 5th)
  /// With a value above 0, a pass waits (at least resample_every steps) until the fastest particle may
  /// have travelled this many level-0 spacings since the last one: the sum over the steps of the
  /// largest speed times dt. The paper suggests such a criterion (Sec. 7); 0 is its fixed cadence.
  /// While a source is on, the fixed cadence holds. Why this default: docs/findings/sph.md.
  double resample_travel = 0.5;
  /// A split's children are not merged for this many resampling passes (0: the paper's, no wait).
  /// Churn (a particle made by a split merged, or one made by a merge split, within kChurnPasses
  /// passes) is counted either way. Measured: docs/findings/sph.md.
  int merge_min_passes = 0;
  /// alpha, beta (max_level is taken from above): the paper's 2 and 3 in 3D, beta 3.37 in 2D
  /// (ResampleOptions::for_dimension says why)
  ResampleOptions resampling = ResampleOptions::for_dimension(Dim);
  double gamma_degrees = 60.0;  ///< medial-axis angle
  int projection_bisections = 1;
  /// Radius of the footpoint disks, in support radii (the paper's: 1). Smaller disks keep large
  /// particles' disks, tilted by a bumpy surface, from handing interior particles footpoints on their
  /// far rims (read as medial axis, so resampling at rest never settles).
  /// Why this default: docs/findings/sph.md.
  double disk_radius = 0.5;
  /// How the neighbour lists are found; the k-d tree is built on redistancing steps either way.
  NeighbourSearch search = NeighbourSearch::automatic;
  /// Verlet skin, in level-0 spacings: the lists hold the pairs within max(r_i, r_j) + skin and are
  /// kept until a particle has moved half the skin or a source adds particles (a redistancing step
  /// rebuilds only the point tree). The sums skip pairs beyond their support, so the results are the
  /// same to the bit as with lists found every step (skin 0).
  double neighbour_skin = 0.2;
  /// true: after a split or merge the kept lists are patched (new particles' pairs found around
  /// them), and when at most a tenth of the particles have moved half the skin only theirs are found
  /// again; false: whole searches. Same bits either way. The refresh matters because the particle
  /// shift keeps moving a few large particles. Why this default: docs/findings/sph.md.
  bool patch_lists = true;
  /// Footpoints within a level-0 spacing of a solid become the solid's point nearest the particle
  /// before the feature size is estimated (false: the paper's, every footpoint on the particles'
  /// distance surface, where the layer pressed on a floor reads as medial axis and churns through
  /// splits and merges). Why this default: docs/findings/sph.md.
  bool wall_footpoints = true;
  /// How the redistancing and feature-size marches run: the paper's priority queue on one thread, or
  /// rounds on all threads (march.hpp). The queue stays the default: the rounds settle on other
  /// footpoints where the fixed point is not unique, which changes the resampling, and they pay only
  /// on large particle sets. Why: docs/findings/sph.md.
  MarchOrder march = MarchOrder::serial;
  /// A step with fewer particles than this runs on one thread (0: every step on all threads). Below
  /// it a step's parallel loops are too short to pay for a second thread, and on a machine with other
  /// load they lose to one. Same bits either way. Why this default: docs/findings/sph.md.
  int serial_below = 1000;
  double restitution = 0.0;  ///< normal velocity kept (reversed) at a wall
  std::uint64_t seed = 1;    ///< the split directions' random stream
  std::vector<SphSource<Dim>> sources;
  SphRotation<Dim> rotation;  ///< the container's turn (none by default)
  SphView<Dim> view;          ///< the view-dependent condition (none by default)

  /// Throws liquid::Error naming the first impossible value.
  void check() const;
};

struct SphStepReport {
  double dt = 0.0;
  int particles = 0;
  std::vector<int> per_level;  ///< particles of each level after the step
  long pairs = 0;              ///< pairs in the step's neighbour lists (the skin's included)
  bool searched = false;       ///< the lists were found this step (not kept from an earlier one)
  /// Particles whose lists were found again alone this step: they had moved half the skin while
  /// the rest had not (SphOptions::patch_lists).
  int refreshed = 0;
  bool resampled = false;  ///< this step redistanced (and, adaptive, resampled)
  RedistanceStats redistancing;
  FeatureStats features;
  ResampleStats resampling;
  double max_speed = 0.0;
  double max_density_error = 0.0;  ///< max |rho_i / rho_0 - 1| over particles, at the forces
  /// max (rho_i / rho_0 - 1, 0) over particles, at the forces: the compression that makes pressure.
  /// The density error also counts spray and fragments, which expand freely at zero pressure.
  double max_compression = 0.0;
  int emitted = 0;  ///< particles the sources added this step
  /// Particles alone (no particle or wall within their support) whose density was set to rho_0
  /// (FluidConstants::free_particles_at_rest).
  int rested = 0;
};

/// What a checkpoint keeps of an AdaptiveSph: its particles, clock and split directions' random
/// stream (as text). The neighbour lists and the tree are rebuilt by every step, so a restored
/// simulation continues bit for bit.
template <int Dim>
struct SphState {
  SphParticles<Dim> particles;
  double time = 0.0;
  long steps = 0;
  std::string rng;
  double travel = 0.0;  ///< the travel bound since the last resampling pass (SphOptions::resample_travel)
  /// The steps of the last resampling passes, oldest first (at most kPassHistory): churn and the merge
  /// wait count in passes.
  std::vector<std::int64_t> pass_steps;
};

template <int Dim>
class AdaptiveSph {
 public:
  explicit AdaptiveSph(SphOptions<Dim> options);

  /// Fills the liquid region (phi < 0) inside the container and outside the obstacles with a lattice
  /// of level-0 particles (spacing `spacing`, half a spacing from the container's walls), distances
  /// from phi; (the level-0 mass, from the constructor, gives a full lattice density rho_0); when adaptive,
  /// resamples at rest until no particle changes (at most 2 max_level + 2 rounds).
  void seed(const levelset::Function<Dim>& liquid, const Vec<Dim>& velocity = Vec<Dim>::Zero());

  SphStepReport advance(double dt);

  /// Lets the seeded liquid settle into its compressed state before t = 0: `duration` seconds of
  /// steps at stable_dt() with every velocity damped by exp(-dt / tau) per step (tau = duration / 8),
  /// then velocities zeroed and the clock, step count and timers reset. A lattice seeded at rho_0
  /// otherwise starts by falling into its hydrostatic compression, and the acoustic oscillation
  /// that follows lasts for seconds. With `hold`, the liquid settles inside that box instead of the
  /// container (a dam's gate, removed when relax() returns). Sources and the container's turn are off
  /// while it settles.
  void relax(double duration, const Box<Dim>* hold = nullptr);
  /// dt by the speed of sound, the fastest particle, the largest acceleration and the viscosity:
  /// min(cfl s / (c + |v|max), 0.25 sqrt(s / |a|max), 0.125 rho_0 s^2 / mu), capped at max_dt, with
  /// s the level-0 spacing (the paper's fixed step is dictated by the smallest particles too).
  double stable_dt(double cfl = 0.25, double max_dt = 1e-3) const;

  const SphParticles<Dim>& particles() const { return p_; }
  SphParticles<Dim>& particles() { return p_; }
  const Sizes& sizes() const { return sizes_; }
  const SphOptions<Dim>& options() const { return options_; }
  const PhaseTimer& timer() const { return timer_; }
  /// The kept neighbour lists (with the skin's pairs) and the positions they were found at (empty
  /// when no lists are current): what the tests hold against a whole search.
  const NeighbourLists& neighbour_lists() const { return nbrs_; }
  std::span<const Vec<Dim>> built_positions() const { return built_at_; }
  double time() const { return time_; }
  long steps() const { return steps_; }
  /// Gravity in the container's frame at time t (turned against the container's turn).
  Vec<Dim> gravity_at(double t) const;
  /// True when x is inside an obstacle or outside the container (by more than round-off).
  bool in_solid(const Vec<Dim>& x) const;
  /// True where the collisions would move a particle (closer than their margin, half a level-0
  /// spacing, to a wall or an obstacle; by more than round-off): no split or merge places one there.
  bool in_collision_margin(const Vec<Dim>& x) const;
  /// The total volume the particles stand for: sum m_i / rho_0.
  double volume() const { return p_.total_mass() / options_.fluid.rest_density; }

  /// One redistance + feature size + resample pass at the current positions (what a pass step does);
  /// returns what it did. Public for the cases that resample without moving.
  SphStepReport adapt_now();

  SphState<Dim> state() const;
  /// Continues from `state` (taken from a simulation with the same options); throws liquid::Error
  /// naming what does not fit (array sizes, a level above max_level, a bad random stream).
  void restore(SphState<Dim> state);

 private:
  void find_neighbours_now(bool with_tree);
  /// The largest move since the lists were built, in half skins (infinite: no lists for these
  /// particles).
  double skin_used() const;
  /// True when nbrs_ still holds every pair within reach: the same particles, none moved half the skin.
  bool lists_hold() const;
  /// nbrs_ without the skin's pairs (what redistancing, elfs and resampling read).
  void within_support(NeighbourLists& exact) const;
  /// After splits and merges (`origin`: each particle's index before them, -1 if new), keeps the
  /// lists instead of searching again: survivors keep their rows and built positions, and the new
  /// particles' pairs are found around them.
  void patch_lists(const std::vector<std::int32_t>& origin);
  /// With patch_lists: when at most a tenth of the particles have moved half the skin, their lists
  /// are found again around them (in place, or by patch_lists when the rows' storage has grown past
  /// 5/4 of its packed size) and their number returned; otherwise 0, nothing done.
  int refresh_movers();
  /// refresh_movers' work when the lists have room: only the movers' rows and the rows they enter or
  /// leave are rewritten (`movers` ascending, each moved half the skin).
  void refresh_in_place(const std::vector<std::int32_t>& movers);
  /// The built positions binned in cells as wide as the largest reach (radius + skin).
  CellGrid<Dim> grid_of(std::span<const Vec<Dim>> built) const;
  /// Appends to `out` every j (not k, not skip(j)) within max(r_k, r_j) + skin of particle k, at the
  /// built positions `grid` holds.
  template <class Skip>
  void partners_of(const CellGrid<Dim>& grid, std::span<const Vec<Dim>> built, int k, Skip skip,
                   std::vector<std::int32_t>& out) const;
  /// The room a row of `size` entries is given to grow into when the lists are written whole.
  static std::int64_t row_room(std::int64_t size) { return 2 + size / 16; }
  void collide();
  /// How close to a wall or an obstacle collide() lets a particle come: half a level-0 spacing.
  double collision_margin() const { return 0.5 * options_.spacing; }
  /// SphOptions::wall_footpoints: every footpoint within a level-0 spacing of a solid becomes the
  /// point of the solid nearest its particle.
  void footpoints_onto_walls();
  /// The sources' phase: imposed velocities, then new particles; returns how many were added.
  int apply_sources();
  /// Adds the turning frame's fictitious accelerations to p.a (dt: the step's, for the Coriolis term).
  void add_frame_accelerations(double dt);
  // The phases of advance(), in order (each timed under its name; docs/architecture.md).
  /// neighbours: keeps the lists while they hold, refreshes the movers' rows or searches afresh.
  void update_neighbours(bool resampling, SphStepReport& report);
  /// forces: density (summation) or pressure from the carried density, accelerations, the density
  /// rate (continuity) and the shifting gradient; throws naming a particle whose terms are not finite.
  void forces(double dt, SphStepReport& report, std::vector<Vec<Dim>>& shift);
  /// The every-k-th-step phases on the current neighbour lists: redistance, and when adaptive elfs
  /// and resample (timed under those names).
  void redistance_and_resample(SphStepReport& report);
  /// Whether this step runs the redistancing, feature-size and resampling pass (SphOptions::resample_every,
  /// resample_travel).
  bool resampling_due() const;
  /// integrate: symplectic Euler (v, then x, then the continuity density); shift may be empty.
  void integrate(double dt, const std::vector<Vec<Dim>>& shift);
  /// The step's tallies: particles per level, the largest speed.
  void tally(double dt, SphStepReport& report) const;
  /// Throws liquid::Error naming particle i, its state and the term of its acceleration that is not
  /// finite.
  [[noreturn]] void throw_not_finite(int i) const;

  SphOptions<Dim> options_;
  Sizes sizes_;
  SphParticles<Dim> p_;
  Boundary<Dim> walls_;
  PointTree<Dim> tree_;
  NeighbourLists nbrs_;              ///< the pairs within max(r_i, r_j) + skin at built_at_
  std::vector<Vec<Dim>> built_at_;   ///< the positions nbrs_ were found at (empty: none current)
  NeighbourLists spare_;             ///< patch_lists' output storage, kept between patches
  std::int64_t packed_entries_ = 0;  ///< nbrs_'s storage when last written whole
  NeighbourLists skinless_;          ///< within_support's output, kept between resamplings
  PhaseTimer timer_;
  std::mt19937_64 rng_;
  double time_ = 0.0;
  long steps_ = 0;
  double travel_ = 0.0;                   ///< largest speed x dt summed since the last resampling pass
  std::vector<std::int64_t> pass_steps_;  ///< SphState::pass_steps
};

}  // namespace liquid::sph
