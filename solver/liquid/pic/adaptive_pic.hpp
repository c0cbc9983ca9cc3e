#pragma once
// AdaptivePic<Dim>: the liquid solver of RBF Liquids (Secs. 4-5). A Cellgraph refined in a narrow
// band around the liquid surface, particles carrying the velocity, RBF transfers between them and
// the faces, and the PPE of `mac` with the air cells at p = 0. With `adaptive = false` the same
// class runs on a uniform tree with the regular PIC/FLIP/APIC transfers: the paper's baselines.
//
// advance(dt) reads as the phases of docs/architecture.md, each timed under its name:
//   [sources] -> classify -> grid -> p2g -> forces -> laplacian -> ppe -> project -> extrapolate -> g2p ->
//   advect -> reseed
// Density is 1 (pressure in units of velocity^2). Walls are the domain's sides and the static
// solids, free-slip: the normal velocity is zero there. The divergence is the finite-volume flux sum (it
// conserves: mac/divergence.hpp); the Laplacian is mac's (FD where regular, RBF-FD at T-junctions).
//
//   PicOptions<2> o;  o.domain = ...;  o.coarse_level = 3;  o.finest_level = 6;
//   AdaptivePic<2> sim(o);
//   sim.seed(levelset::box<2>(...));
//   while (sim.time() < 2.0) sim.advance(sim.stable_dt(1.0, 0.01));

#include <functional>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "liquid/core/timer.hpp"
#include "liquid/levelset/levelset.hpp"
#include "liquid/linalg/solver.hpp"
#include "liquid/mac/laplacian.hpp"
#include "liquid/mac/poisson.hpp"
#include "liquid/particles/advect.hpp"
#include "liquid/particles/bins.hpp"
#include "liquid/particles/seeding.hpp"
#include "liquid/pic/classify.hpp"
#include "liquid/pic/surface.hpp"
#include "liquid/transfer/extrapolate.hpp"
#include "liquid/transfer/face_values.hpp"
#include "liquid/transfer/regular.hpp"
#include "liquid/transfer/scattered.hpp"
#include "liquid/transfer/velocity_field.hpp"

namespace liquid::pic {

/// How velocity moves between particles and faces: rbf (the paper's, any tree), or the regular
/// baselines pic, flip and apic (multilinear weights; a uniform tree, adaptive = false).
enum class PicTransfer { rbf, pic, flip, apic };
const char* to_string(PicTransfer transfer);

/// Where the PPE takes p = 0: at the centres of the air cells next to the liquid (the paper's,
/// first order in the surface position), or at the zero set of a level set built from the particles
/// (ParticleSurface: Zhu and Bridson's construction), second order (mac's level-set Dirichlet).
enum class PicSurface { air_cells, levelset };
const char* to_string(PicSurface surface);
/// "air", "levelset"; throws naming the choices.
PicSurface parse_pic_surface(const std::string& name);

/// The inner product the pressure projection is orthogonal in (regular transfers, uniform tree):
///   volume  every face weighs its volume (the standard PPE).
///   mass    every face weighs the mass m_f the particle -> face transfer gave it, so the projection
///           never raises the faces' kinetic energy as the transfers count it: -div(beta grad p) =
///           -div u* / dt, beta_f = m_full / max(m_f, min_face_mass m_full) (m_full: a cell's seeded
///           particles' mass), u -= dt beta grad p. Faces with mass between two air cells keep their
///           transferred value. A diagnostic, not a method for scenes: beta follows the sampling, so
///           g / beta has a curl no pressure balances and a still pool does not stay still.
///   split   gravity's kick dt g is projected in volumes first (its own PPE solve), added to the
///           transferred velocity, and the sum projected in masses; the cell pressure is the sum.
///           Two solves a step; a still pool stays still. The volume-projected kick can still do work
///           on the particles (no sign); PicStepReport::pressure_work reports it.
/// Why these three: docs/findings/energy-and-projections.md.
enum class PicProjection { volume, mass, split };
const char* to_string(PicProjection projection);
/// "volume", "mass", "split"; throws naming the choices.
PicProjection parse_pic_projection(const std::string& name);
/// "rbf", "pic", "flip", "apic"; throws naming the choices.
PicTransfer parse_pic_transfer(const std::string& name);

/// An inflow: while start <= t < stop, every non-solid cell whose centre is inside `region` is
/// filled with particles and the particles inside it move at `velocity`.
template <int Dim>
struct PicSource {
  levelset::Function<Dim> region;  ///< < 0 inside
  Vec<Dim> velocity = Vec<Dim>::Zero();
  double start = 0.0, stop = std::numeric_limits<double>::infinity();
  bool active(double t) const { return t >= start && t < stop; }
};

template <int Dim>
struct PicOptions {
  Box<Dim> domain{Vec<Dim>::Zero(), Vec<Dim>::Ones()};
  bool adaptive = true;  ///< false: a uniform tree at fine_level (the regular baselines)
  int coarse_level = 3;  ///< level of the liquid's interior, far from the surface (adaptive)
  int finest_level = 6;  ///< level of the band around the surface (scene key grid.finest)
  int band = 2;          ///< cells within this many face hops of a surface cell are at fine_level
  int max_jump = 2;      ///< level jump limit between face neighbours (1-4, or unlimited_jump)
  Vec<Dim> gravity = default_gravity();
  /// Static obstacles (< 0 inside; empty: none). A cell whose centre is inside is solid: its faces
  /// keep velocity 0 (free slip), the PPE rows of its fluid neighbours take dp/dn = 0 there, and
  /// particles that enter it are pushed back out.
  levelset::Function<Dim> solid;
  std::vector<PicSource<Dim>> sources;
  /// A region kept at fine_level whatever the liquid does (< 0 inside; empty: none), with the
  /// band's hops around it: the cells it may overlap (within half a diagonal of their centre).
  /// For flows whose detail is not at the surface (a vortex in a full box, say).
  levelset::Function<Dim> refine;
  PicTransfer transfer = PicTransfer::rbf;
  double flip = 0.95;  ///< FLIP's blend for transfer = flip (1: pure FLIP, 0: PIC)
  transfer::TransferOptions rbf = stable_rbf();
  /// The RBF transfer on an adaptive tree: true takes APIC's multilinear transfers inside uniform
  /// patches (transfer::UniformPatches) and the RBF only where a stencil meets a level change; false,
  /// the paper's (scene key `[solver] patch_transfer = "rbf"`), the RBF everywhere. With the RBF
  /// gradient as C outside the patches (below) a 3D still pool's noise grows far more slowly and a
  /// vortex keeps its accuracy. A uniform tree with transfer = rbf always uses the RBF everywhere
  /// (the regular-rbf comparison row). Measured: docs/findings/transfer-stability.md.
  bool uniform_patches = true;
  /// With uniform_patches: particle -> face outside the patches by tent weights of the face's size
  /// (APIC's hat, PIC-like where particles carry no C) instead of the RBF. Steadier in a 3D still pool,
  /// less accurate in a vortex (scene key `[solver] level_change_p2g = "tent"`; measured:
  /// docs/findings/transfer-stability.md).
  bool tent_at_level_changes = false;
  /// With uniform_patches and the RBF particle -> face at level changes: the share of the tents'
  /// positive mean (C = 0) blended into each level-change face, v_f = (1 - s) v_RBF + s v_tent
  /// (transfer::blend_tent_mean). The average damps the smooth modes the RBF alone lets a 3D still
  /// pool grow, at some cost in dissipation; 2D pools do not grow, so 2D takes 0 (scene key
  /// `[solver] level_change_tent_share`; measured: docs/findings/transfer-stability.md).
  double level_change_tent_share = Dim == 3 ? 0.1 : 0.0;
  /// With uniform_patches: the particles outside the patches take the RBF interpolant's gradient as
  /// APIC's C (0 where a value was clamped) instead of C = 0, so their particle -> face keeps the
  /// flow's affine part there too (scene key `[solver] affine_outside_patches = "zero"` sets C = 0).
  bool rbf_gradient_affine = true;
  particles::Integrator integrator = particles::Integrator::rk2;
  double advect_cfl = 1.0;  ///< advection substeps keep |v| dt_sub <= advect_cfl * finest h
  int extrapolation_layers = 4;
  bool reseed = true;
  /// Adaptive runs: a cell that was fluid and not surface when the step began and that the advection
  /// left empty is refilled like a hole (the coarse interior's sparse particles cannot refill finer
  /// cells downstream; scene key `[solver] refill_emptied`; off in the paper's preset).
  /// Why: docs/findings/dam-break-convergence.md.
  bool refill_emptied = true;
  /// Ranges left at 0 take the method's default: with the RBF transfer, sparse cells topped up
  /// (lo 3 in 2D, 5 in 3D, no hi, keep); [3, 12] (2D) and [5, 15] (3D) with PIC, FLIP and APIC.
  particles::ReseedOptions reseeding;
  mac::PoissonOptions poisson = default_poisson();
  linalg::SolveOptions solver{linalg::SolverKind::bicgstab_ilut, 1e-8};
  bool continue_on_ppe_failure = false;  ///< false: a PPE that does not converge stops the run
  /// A PPE solve by a solver without AMG that does not converge (or breaks down) is retried once by
  /// BiCGSTAB + AMG, with AMG's own iteration cap, from the iterate it reached: a cheap default
  /// solver cannot stop a run that AMG would carry (scene key `[ppe] fallback`).
  bool ppe_fallback = true;
  PicSurface surface = PicSurface::air_cells;
  /// levelset surface: the particle radius r, in finest cells. A smaller r makes the surface
  /// bumpier, a larger one moves it out. Why this default: docs/findings/pic-solver.md.
  double surface_radius = 0.75;
  PicProjection projection = PicProjection::volume;
  /// projection = mass: the lightest a face is taken to be, as a fraction of a full cell's mass
  /// (faces near the surface, where few particles reach, would otherwise take unbounded beta).
  double min_face_mass = 0.1;

  /// The paper's operator settings for the PIC step: PHS r^3 with degree 2 for the Laplacian rows
  /// and the face gradients (mac's default of degree 3 is for the convergence studies; degree 2 is
  /// much cheaper a step). Why: docs/findings/rbf-fd-degree.md.
  /// A box full of liquid (a pure Neumann PPE) takes the zero-mean constraint, not the pin: on a
  /// tree the RBF-FD rows are not D G, so a pin drops the right-hand side's mismatch with the left
  /// null vector into the pinned cell's equation, a point source there. Why:
  /// docs/findings/flow-studies.md. `[solver] nullspace = "pin"` in a scene restores the pin.
  /// In 3D the face gradients keep at most twice their stencil size of the whole rings, the nearest
  /// (scene key `[solver] ppe_gradient_cap`; 0 keeps whole rings): the projection costs about half,
  /// p is untouched and dp/dn moves by under 5% (docs/findings/table1-scale.md, "Capped gradient
  /// stencils"). In 2D the cap would bind where it costs the dam break's energy, and saves little.
  static mac::PoissonOptions default_poisson() {
    mac::PoissonOptions p;
    p.rbf.degree = 2;
    p.gradient_degree = 2;
    p.gradient_ring_cap = Dim == 3 ? 2.0 : 0.0;
    p.nullspace = mac::Nullspace::zero_mean;  // see above
    return p;
  }
  /// The default RBF transfer: PHS r^3 with degree 1 and particle -> face clamping on. The paper's
  /// r^5 + degree 2 pair amplifies noise on 3D trees until a still pool moves; clamping keeps the
  /// interpolant's extrapolation at free-surface and hanging faces from feeding on itself. Why:
  /// docs/findings/transfer-stability.md.
  static transfer::TransferOptions stable_rbf() {
    transfer::TransferOptions t = transfer::TransferOptions::paper_rbf();
    t.exponent = 3;
    t.degree = 1;
    t.clamp_faces = true;
    return t;
  }
  /// The paper's exact transfer and reseeding (scene key `[solver] preset = "paper"`, `liquid run
  /// --paper`): PHS r^5 + degree 2 transfers, and reseeding that replaces the particles of every
  /// cell holding fewer than 3 (2D) / 5 (3D) or more than 12 / 15. The default differs (r^3 + degree
  /// 1; for the RBF transfer, reseeding that tops up sparse cells and never thins crowded ones):
  /// docs/findings/transfer-stability.md, docs/findings/dam-break-convergence.md.
  void apply_paper_preset() {
    rbf.exponent = 5;
    rbf.degree = 2;
    reseeding.lo = Dim == 2 ? 3 : 5;
    reseeding.hi = Dim == 2 ? 12 : 15;
    reseeding.keep = false;
    uniform_patches = false;
    level_change_tent_share = 0.0;
    refill_emptied = false;
    poisson.rbf.degree = 2;
    poisson.gradient_degree = 2;
    poisson.irregular = mac::IrregularRows::laplacian;
  }
  /// True when the transfer and reseeding are the paper's preset (what apply_paper_preset() sets).
  bool paper_preset() const {
    return rbf.exponent == 5 && rbf.degree == 2 && reseeding.lo == (Dim == 2 ? 3 : 5) &&
           reseeding.hi == (Dim == 2 ? 12 : 15) && !reseeding.keep && !uniform_patches && !refill_emptied &&
           poisson.rbf.degree == 2 && poisson.gradient_degree == 2 &&
           poisson.irregular == mac::IrregularRows::laplacian;
  }
  static Vec<Dim> default_gravity() {
    Vec<Dim> g = Vec<Dim>::Zero();
    g[1] = -9.81;
    return g;
  }
};

/// What one step did.
struct PicStepReport {
  long step = 0;
  double time = 0.0;  ///< after the step
  double dt = 0.0;
  long n_particles = 0, n_cells = 0, n_fluid_cells = 0, n_surface_cells = 0;
  long n_split = 0, n_merged = 0;  ///< grid changes
  long n_filled = 0;               ///< particles created in holes and in new children of interior cells
  long n_source = 0;               ///< particles created by the sources
  int n_substeps = 1;
  linalg::SolveStats ppe;
  linalg::SolveStats ppe_gravity;  ///< PicProjection::split: the gravity pass's solve (ppe: the mass pass's)
  int ppe_fallbacks = 0;           ///< solves of this step retried with AMG (PicOptions::ppe_fallback)
  transfer::TransferReport p2g, g2p;
  long unknown_faces = 0;  ///< faces no particle reached, before extrapolation
  /// PicOptions::uniform_patches: the cells near the liquid in uniform patches (APIC transfers) and
  /// those near the liquid in all; the faces transferred by APIC.
  long patch_cells = 0, near_cells = 0, patch_faces = 0;
  /// Kinetic energy of the face velocities over the wet faces, 1/2 sum of u_f^2 A_f d_f (d_f the
  /// distance between the two cell centres along the axis; density 1), before the projection (after
  /// the forces) and after it; with the mass projection each face also weighs its transferred mass
  /// over a full cell's (1 / beta), the norm that projection is orthogonal in. An orthogonal
  /// projection never raises it; the RBF-FD rows on a tree are not D G, so `after > before` is
  /// possible there and is worth watching.
  double grid_energy_before = 0.0, grid_energy_after = 0.0;
  /// The largest |div u| h over the fluid cells after the projection (finite volumes, h the cell's
  /// size): what the projection leaves, a velocity. With flux rows (mac::IrregularRows::flux) it is the
  /// solver's residual alone; with RBF-FD Laplacian rows also the rows' departure from D G.
  double divergence_after = 0.0;
  /// The work the pressure applied in volumes did this step in the particles' transferred masses:
  /// W = -dt sum_f m_f u_f d_f p over the projected faces, with m_f the face's transferred mass (a
  /// unit per particle: a full cell's seeded particles weigh 2^Dim on each of its faces), u_f after
  /// the projection and d_f p the normal derivative of the pressure that projection applied in
  /// volumes (projection volume: the whole pressure; split: the gravity pass's; mass: none, so 0).
  /// On a divergence-free field (air-cell surface) it would be 0 if every face weighed the same; it is the
  /// energy the pressure can give the particles where their masses do not follow the cells' volumes, and
  /// it bounds a PIC step's rise of the particles' energy (the kinetic-energy case asserts it; see
  /// docs/findings/energy-and-projections.md). Regular transfers only (their face masses); NaN with RBF.
  double pressure_work = std::numeric_limits<double>::quiet_NaN();
  particles::AdvectReport advect;
  particles::ReseedReport reseed;
};

/// Everything that decides the solver's future: what a checkpoint stores. Positions and velocities
/// are Dim doubles per particle; fields as the particles hold them.
template <int Dim>
struct PicState {
  tree::CellGraphState<Dim> graph;
  std::vector<double> x, v;
  std::vector<std::string> field_names;
  std::vector<int> field_components;
  std::vector<std::vector<double>> field_values;
  std::vector<tree::CellId> particle_cell;  ///< the bins
  std::vector<double> u, p;                 ///< face velocities and cell pressures by id
  std::vector<std::uint8_t> known;
  double time = 0.0;
  long step = 0;
};

template <int Dim>
class AdaptivePic {
 public:
  explicit AdaptivePic(const PicOptions<Dim>& options);
  ~AdaptivePic();
  AdaptivePic(AdaptivePic&&) noexcept;

  /// Fills the liquid region (level set < 0) with 2^Dim Halton particles per cell of a tree refined
  /// around its surface; velocities from `velocity` (zero when empty). Call once, before advance().
  void seed(const levelset::Function<Dim>& liquid,
            const std::function<Vec<Dim>(const Vec<Dim>&)>& velocity = {});
  /// One time step of length dt (> 0). Throws liquid::Error naming the phase and the cell or particle
  /// when a field becomes NaN or infinite, and when the PPE does not converge (unless the options
  /// say to go on; the report then says so).
  PicStepReport advance(double dt);
  /// The state after the last step, and back: a solver built with the same options and given
  /// restore(state()) (instead of seed()) takes the same steps bit for bit. Throws naming the
  /// mismatch when the state does not fit the options (a field the transfer needs, array sizes).
  PicState<Dim> state() const;
  void restore(const PicState<Dim>& state);
  /// cfl * finest h / (largest particle speed), at most max_dt.
  double stable_dt(double cfl, double max_dt) const;

  const PicOptions<Dim>& options() const { return options_; }
  const tree::CellGraph<Dim>& graph() const { return graph_; }
  const particles::Particles<Dim>& particles() const { return particles_; }
  const particles::CellBins& bins() const { return bins_; }
  const pic::Classification& classification() const { return cls_; }
  /// Face velocities after the last step (normal components, by face id) and which are known.
  std::span<const double> face_velocity() const { return u_; }
  std::span<const std::uint8_t> face_known() const { return known_; }
  /// Pressure by cell id after the last step (0 in air cells).
  std::span<const double> pressure() const { return p_; }
  const PhaseTimer& timer() const { return timer_; }
  /// The last step's PPE: its matrix A over system.layout's unknowns; after advance() its b holds
  /// the solution (the pressure), not the right-hand side.
  const mac::PoissonSystem<Dim>& pressure_system() const { return system_; }
  double time() const { return time_; }
  long steps() const { return step_; }  ///< steps taken
  double finest_h() const;

 private:
  void classify();
  void apply_sources(PicStepReport& r);
  void fold_solid_rows();
  void interface_gradients(double dt, std::vector<double>& dn) const;
  void extend_into_solid(linalg::Vector& x) const;
  void adapt_grid(PicStepReport& r);
  void fill(std::span<const tree::CellId> cells, PicStepReport& r);
  void to_faces(PicStepReport& r);
  bool affine_particles() const;  ///< particles carry APIC's C (apic, or rbf with uniform patches)
  std::vector<tree::CellId> near_liquid_cells() const;  ///< fluid cells and one ring, sorted
  void forces(double dt);
  void assemble(double dt);
  void solve_pressure(PicStepReport& r);
  /// Applies the solved pressure; returns PicStepReport::pressure_work (NaN from the split
  /// projection's gravity pass, whose work advance() takes from the mass pass's return).
  double project(double dt);
  /// PicProjection::split's first pass (see there).
  void project_gravity(double dt, PicStepReport& r);
  void extrapolate();
  double grid_energy() const;  ///< see PicStepReport::grid_energy_before
  void to_particles(PicStepReport& r);
  void advect(double dt, PicStepReport& r);
  /// was_interior (adaptive runs; ascending, or empty): the cells that were fluid and not surface
  /// when the step began. Such a cell left empty by the advection is refilled: with the step's CFL
  /// the air cannot have reached it, so it was emptied by the sparse particles of coarser cells
  /// upstream, not by the surface.
  void reseed(PicStepReport& r, std::span<const tree::CellId> was_interior);
  particles::VelocitySource<Dim> grid_velocity() const;
  void check_faces(const char* phase) const;
  void check_particles(const char* phase) const;

  PicOptions<Dim> options_;
  tree::CellGraph<Dim> graph_;
  std::unique_ptr<transfer::RegularLattice<Dim>> lattice_;   // the multilinear transfers (pic, flip, apic)
  std::unique_ptr<transfer::FaceVelocityField<Dim>> field_;  // the RBF velocity of this step (g2p, advect)
  std::unique_ptr<transfer::UniformPatches<Dim>> patches_;   // this step's uniform patches (p2g to advect)
  std::vector<tree::CellId> near_cells_;                     // this step's cells near the liquid
  tree::CellAdjacency<Dim> adjacency_;                       // this step's faces by cell and axis
  particles::Particles<Dim> particles_;
  particles::CellBins bins_;
  pic::Classification cls_;
  std::unique_ptr<pic::ParticleSurface<Dim>> surface_;  // the step's liquid level set (levelset surface)
  std::vector<std::uint8_t> solid_;  // per cell id: centre inside the solid (empty: no solid)
  std::vector<double> u_, u_transferred_, p_;
  /// The transfer's mass per face id (this step's; regular transfers) and, with the mass and split
  /// projections, beta
  std::vector<double> face_beta_, face_mass_;
  std::vector<double> gravity_pressure_;  ///< split: the pressure of gravity's kick, by cell
  std::vector<double> gravity_gradient_;  ///< split: its normal derivative by face id (0 where not applied)
  bool volume_pass_ = false;              ///< split: assemble and project in volumes
  std::vector<std::uint8_t> known_;
  mac::PoissonSystem<Dim> system_;
  /// The RBF-FD weights of the PPE rows and face gradients, kept across steps: a step's tree keeps
  /// most of the last step's T-junction layouts, and an entry is a function of its layout alone.
  /// At most about 2^16 layouts (two generations; about 160 MB in 3D).
  std::unique_ptr<rbf::WeightCache<Dim>> weights_;
  std::unique_ptr<rbf::InterpolantCache<Dim>> interpolants_;  // the RBF transfer's factors, kept across steps
  // The PPE solver, kept across steps: an AMG solver keeps its hierarchy while the layout stays.
  std::unique_ptr<linalg::LinearSolver> ppe_solver_;
  /// A box full of liquid makes the PPE a bordered system (zero mean), symmetric but indefinite:
  /// a conjugate-gradient solver cannot take it, so those steps use BiCGSTAB with the same
  /// preconditioner (made when first needed).
  std::unique_ptr<linalg::LinearSolver> bordered_ppe_solver_;
  /// PicOptions::ppe_fallback's BiCGSTAB + AMG, made when first needed.
  std::unique_ptr<linalg::LinearSolver> fallback_ppe_solver_;
  PhaseTimer timer_;
  double time_ = 0.0;
  long step_ = 0;
  int apic_field_ = -1;
  bool seeded_ = false;
};

extern template class AdaptivePic<2>;
extern template class AdaptivePic<3>;

}  // namespace liquid::pic
