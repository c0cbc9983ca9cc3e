#include "liquid/pic/adaptive_pic.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "liquid/core/error.hpp"
#include "liquid/mac/divergence.hpp"
#include "liquid/transfer/extrapolate.hpp"
#include "liquid/transfer/velocity_field.hpp"
#include "liquid/tree/builders.hpp"
#include "liquid/tree/remap.hpp"

namespace liquid {

const char* to_string(PicTransfer transfer) {
  switch (transfer) {
    case PicTransfer::rbf:
      return "rbf";
    case PicTransfer::pic:
      return "pic";
    case PicTransfer::flip:
      return "flip";
    case PicTransfer::apic:
      return "apic";
  }
  return "?";
}

PicTransfer parse_pic_transfer(const std::string& name) {
  for (PicTransfer t : {PicTransfer::rbf, PicTransfer::pic, PicTransfer::flip, PicTransfer::apic})
    if (name == to_string(t)) return t;
  throw Error(fmt::format("unknown transfer '{}' (choices: rbf, pic, flip, apic)", name));
}

namespace {

template <int Dim>
CellGraphOptions<Dim> graph_options(const PicOptions<Dim>& o) {
  CellGraphOptions<Dim> g;
  g.max_jump = o.max_jump;
  g.min_level = o.adaptive ? std::min(o.coarse_level, o.fine_level) : o.fine_level;
  g.max_level = o.fine_level;
  return g;
}

template <int Dim>
CellGraph<Dim> initial_graph(const PicOptions<Dim>& o) {
  LIQUID_VERIFY(o.domain.valid(), "PIC: the domain is empty");
  LIQUID_VERIFY(o.fine_level >= 1 && o.fine_level <= morton::max_level<Dim>,
                "PIC: fine level {} is outside [1, {}]", o.fine_level, morton::max_level<Dim>);
  LIQUID_VERIFY(!o.adaptive || (o.coarse_level >= 0 && o.coarse_level <= o.fine_level),
                "PIC: coarse level {} must be in [0, fine level {}]", o.coarse_level, o.fine_level);
  LIQUID_VERIFY(o.max_jump >= 1, "PIC: level jump limit {} (need at least 1)", o.max_jump);
  LIQUID_VERIFY(o.band >= 0, "PIC: band {} is negative", o.band);
  LIQUID_VERIFY(!o.adaptive || o.transfer == PicTransfer::rbf,
                "PIC: transfer '{}' needs a uniform tree (adaptive = false); adaptive trees use rbf",
                to_string(o.transfer));
  LIQUID_VERIFY(o.flip >= 0.0 && o.flip <= 1.0, "PIC: FLIP blend {} is outside [0, 1]", o.flip);
  return tree::uniform<Dim>(o.domain, o.adaptive ? o.coarse_level : o.fine_level, graph_options(o));
}

}  // namespace

template <int Dim>
AdaptivePic<Dim>::AdaptivePic(const PicOptions<Dim>& options)
    : options_(options), graph_(initial_graph(options)) {
  if (!options_.adaptive) lattice_ = std::make_unique<RegularLattice<Dim>>(graph_);
  if (options_.transfer == PicTransfer::apic) apic_field_ = particles_.add_field("apic", Dim * Dim);
  u_.assign(graph_.face_capacity(), 0.0);
  known_.assign(graph_.face_capacity(), 1);
  p_.assign(graph_.cell_capacity(), 0.0);
}

template <int Dim>
AdaptivePic<Dim>::~AdaptivePic() = default;
template <int Dim>
AdaptivePic<Dim>::AdaptivePic(AdaptivePic&&) noexcept = default;

template <int Dim>
double AdaptivePic<Dim>::finest_h() const {
  return std::ldexp(graph_.domain().size().minCoeff(), -options_.fine_level);
}

template <int Dim>
void AdaptivePic<Dim>::seed(const levelset::Function<Dim>& liquid,
                            const std::function<Vec<Dim>(const Vec<Dim>&)>& velocity) {
  LIQUID_VERIFY(!seeded_, "PIC: seed() was already called");
  seeded_ = true;
  if (options_.adaptive) {
    graph_ = tree::narrow_band<Dim>(options_.domain, liquid, options_.coarse_level, options_.fine_level,
                                    options_.band + 1.0, graph_options(options_));
  }
  const VelocitySource<Dim> source = [&](std::span<const Vec<Dim>> x, std::span<const CellId>,
                                         std::span<Vec<Dim>> v) {
    for (std::size_t i = 0; i < x.size(); ++i) v[i] = velocity ? velocity(x[i]) : Vec<Dim>::Zero();
  };
  const long n = seed_region<Dim>(graph_, liquid, SeedOptions{}, particles_, source);
  LIQUID_VERIFY(n > 0, "PIC: the liquid region holds no cell's sample point: nothing to simulate");
  bin_particles<Dim>(graph_, particles_.x, bins_);
  u_.assign(graph_.face_capacity(), 0.0);
  known_.assign(graph_.face_capacity(), 1);
  p_.assign(graph_.cell_capacity(), 0.0);
  // Settle the band on the solver's own rule (surface cells, band hops) before the first step.
  if (options_.adaptive)
    for (int round = 0; round <= options_.fine_level - options_.coarse_level; ++round) {
      classify();
      PicStepReport r;
      adapt_grid(r);
      if (r.n_split == 0 && r.n_merged == 0) break;
    }
  classify();
  check_particles("seed");
}

template <int Dim>
VelocitySource<Dim> AdaptivePic<Dim>::grid_velocity() const {
  return [this](std::span<const Vec<Dim>> x, std::span<const CellId> cells, std::span<Vec<Dim>> v) {
    CellBins b;
    b.cell.assign(cells.begin(), cells.end());
    b.sort(graph_.cell_capacity());
    if (lattice_) {
      linear_to_points<Dim>(*lattice_, u_, x, v);
      return;
    }
    faces_to_points<Dim>(graph_, u_, known_, x, b, options_.rbf, v);
  };
}

template <int Dim>
void AdaptivePic<Dim>::classify() {
  pic::classify_cells<Dim>(graph_, bins_, cls_);
}

template <int Dim>
void AdaptivePic<Dim>::fill(std::span<const CellId> cells, PicStepReport& r) {
  if (cells.empty()) return;
  ReseedOptions o = options_.reseeding;
  o.fill_empty = true;
  const ReseedReport rep = liquid::reseed<Dim>(graph_, cells, o, grid_velocity(), particles_, bins_);
  r.n_filled += rep.created - rep.deleted;
}

template <int Dim>
void AdaptivePic<Dim>::adapt_grid(PicStepReport& r) {
  MarkList marks;
  pic::mark_band<Dim>(graph_, cls_, options_.band, options_.coarse_level, options_.fine_level, marks);
  if (marks.empty()) return;
  // Interior fluid cells about to split: their empty children are liquid and get particles.
  std::vector<std::uint8_t> interior(graph_.cell_capacity(), 0);
  for (CellId c : cls_.fluid) interior[c] = 1;
  for (CellId c : cls_.surface) interior[c] = 0;
  const AdaptReport report = graph_.adapt(marks);
  r.n_split += report.n_split;
  r.n_merged += report.n_merged;
  if (report.empty()) return;
  remap::face_field(graph_, report, u_);
  std::vector<double> known(known_.begin(), known_.end());
  remap::face_field(graph_, report, known);
  known_.resize(known.size());
  for (std::size_t f = 0; f < known.size(); ++f) known_[f] = known[f] > 0.5;
  remap::cell_field(graph_, report, p_);
  rebin<Dim>(graph_, particles_.x, bins_, &report);
  std::vector<CellId> children;
  const Origins& o = report.cell_origins;
  for (std::size_t n = 0; n < report.new_cells.size(); ++n) {
    const CellId c = report.new_cells[n];
    if (o.begin[n + 1] - o.begin[n] == 1 && interior[o.source[o.begin[n]]] && bins_.count(c) == 0)
      children.push_back(c);
  }
  fill(children, r);
  classify();
}

template <int Dim>
void AdaptivePic<Dim>::to_faces(PicStepReport& r) {
  FaceValues faces;
  if (lattice_)
    r.p2g = linear_to_faces<Dim>(
        graph_, *lattice_, particles_, bins_,
        options_.transfer == PicTransfer::apic ? RegularScheme::apic : RegularScheme::pic, {}, faces);
  else
    r.p2g = particles_to_faces<Dim>(graph_, particles_, bins_, options_.rbf, faces);
  r.unknown_faces = r.p2g.empty;
  u_ = std::move(faces.value);
  known_ = std::move(faces.known);
  extrapolate_faces<Dim>(graph_, options_.extrapolation_layers, u_, known_);
  u_transferred_ = u_;
  check_faces("p2g");
}

template <int Dim>
void AdaptivePic<Dim>::forces(double dt) {
  // Walls are at rest: the transferred normal velocity there is replaced by the wall's (0) before
  // gravity, so u* on a wall face is dt g. The PPE then takes dp/dn = u* . n / dt on the walls and
  // the projection brings the wall faces back to 0 (see assemble()).
  graph_.for_each_face([&](FaceId f) {
    const GraphFace& g = graph_.face(f);
    u_[f] = (g.is_boundary() ? 0.0 : u_[f]) + dt * options_.gravity[g.axis];
  });
  check_faces("forces");
}

template <int Dim>
void AdaptivePic<Dim>::assemble(double dt) {
  const std::vector<double> div = mac::fv_divergence<Dim>(graph_, u_);
  mac::PoissonProblem<Dim> problem;
  problem.f_cells.assign(graph_.cell_capacity(), 0.0);
  problem.boundary.unknown_cells.assign(graph_.cell_capacity(), 0);
  for (CellId c : cls_.fluid) {
    problem.f_cells[c] = div[c] / dt;
    problem.boundary.unknown_cells[c] = 1;
  }
  problem.boundary.dirichlet = [](const Vec<Dim>&) { return 0.0; };
  problem.pin_value = [](const Vec<Dim>&) { return 0.0; };
  // Walls: dp/dn = (u* - u_wall) . n / dt with u_wall = 0, which is what makes the flux balance of
  // every row (FD and RBF-FD alike) hold for the hydrostatic pressure. With dp/dn = 0 the mirror
  // nodes of RBF-FD rows that reach a wall see a kinked pressure (an O(1) row error, measured on
  // the still pool).
  const double nudge = 1e-6 * finest_h();
  problem.boundary.wall_flux = [this, dt, nudge](const Vec<Dim>& x, const Vec<Dim>& n) {
    int axis = 0;
    for (int k = 0; k < Dim; ++k)
      if (n[k] != 0.0) axis = k;
    const int side = 2 * axis + (n[axis] > 0 ? 1 : 0);
    const CellId c = graph_.locate(Vec<Dim>(x - nudge * n));
    for (FaceId f : graph_.faces(c))
      if (graph_.face(f).boundary == side) return n[axis] * u_[f] / dt;
    return 0.0;
  };
  system_ = mac::assemble_poisson<Dim>(graph_, problem, options_.poisson);
}

template <int Dim>
void AdaptivePic<Dim>::solve_pressure(PicStepReport& r) {
  linalg::Vector x(system_.A.rows());
  x.setZero();
  for (long i = 0; i < system_.n_unknowns(); ++i) x[i] = p_[system_.layout.cell_of_dof[i]];
  r.ppe = linalg::solve(system_.A, system_.b, x, options_.solver);
  if (!r.ppe.converged() && !options_.continue_on_ppe_failure)
    throw Error(
        fmt::format("step {}: the pressure solve did not converge ({}); set continue_on_ppe_failure to go on",
                    step_, r.ppe.describe()));
  std::fill(p_.begin(), p_.end(), 0.0);
  for (long i = 0; i < system_.n_unknowns(); ++i) {
    LIQUID_VERIFY(std::isfinite(x[i]), "step {}, phase ppe: pressure {} in cell {}", step_, x[i],
                  system_.layout.cell_of_dof[i]);
    p_[system_.layout.cell_of_dof[i]] = x[i];
  }
  system_.b = std::move(x);  // keep the solution beside the system for project()
}

template <int Dim>
void AdaptivePic<Dim>::project(double dt) {
  const std::vector<double> dn =
      mac::face_normal_derivative<Dim>(graph_, system_, options_.poisson, system_.b);
  graph_.for_each_face([&](FaceId f) {
    const GraphFace& g = graph_.face(f);
    if (g.is_boundary()) {
      u_[f] = 0.0;
      known_[f] = 1;
      return;
    }
    const bool wet = cls_.wet(g);
    known_[f] = wet;
    if (wet) u_[f] -= dt * dn[f];
  });
  check_faces("project");
}

template <int Dim>
void AdaptivePic<Dim>::extrapolate() {
  extrapolate_faces<Dim>(graph_, options_.extrapolation_layers, u_, known_);
}

template <int Dim>
void AdaptivePic<Dim>::to_particles(PicStepReport& r) {
  const int n = particles_.size();
  std::vector<Vec<Dim>> grid(n);
  if (lattice_) {
    std::span<double> affine;
    if (options_.transfer == PicTransfer::apic) affine = particles_.field(apic_field_);
    r.g2p = linear_to_points<Dim>(*lattice_, u_, particles_.x, grid, affine);
  } else {
    r.g2p = faces_to_points<Dim>(graph_, u_, known_, particles_.x, bins_, options_.rbf, grid);
  }
  if (options_.transfer == PicTransfer::flip) {
    std::vector<double> du(u_.size());
    for (std::size_t f = 0; f < u_.size(); ++f) du[f] = u_[f] - u_transferred_[f];
    std::vector<Vec<Dim>> delta(n);
    linear_to_points<Dim>(*lattice_, du, particles_.x, delta);
    flip_blend<Dim>(grid, delta, options_.flip, particles_.v);
  } else {
    particles_.v = std::move(grid);
  }
  check_particles("g2p");
}

template <int Dim>
void AdaptivePic<Dim>::advect(double dt, PicStepReport& r) {
  double vmax = 0.0;
  for (const auto& v : particles_.v) vmax = std::max(vmax, v.norm());
  const double steps = std::ceil(vmax * dt / (options_.advect_cfl * finest_h()));
  LIQUID_VERIFY(
      steps <= 64,
      "step {}, phase advect: the fastest particle ({:.3g}) would need {:.0f} substeps of the CFL limit in a "
      "step of {:.3g} s; take smaller steps (stable_dt) or look for the cause of that speed",
      step_, vmax, steps, dt);
  const int n_sub = std::max(1, static_cast<int>(steps));
  r.n_substeps = n_sub;
  const auto run = [&](const auto& field) {
    for (int s = 0; s < n_sub; ++s) {
      const AdvectReport a =
          liquid::advect<Dim>(particles_.x, dt / n_sub, options_.integrator, field, graph_.domain());
      r.advect.clamped += a.clamped;
      r.advect.pushed += a.pushed;
      r.advect.stuck += a.stuck;
    }
  };
  if (lattice_) {
    run(FaceVelocityField<Dim>(graph_, *lattice_, u_));
  } else {
    std::vector<CellId> cells;  // where particles are, and one ring around
    std::vector<std::uint8_t> seen(graph_.cell_capacity(), 0);
    std::vector<CellId> ring;
    for (CellId c : cls_.fluid) {
      graph_.k_ring(c, 1, ring);
      for (CellId q : ring)
        if (!seen[q]) seen[q] = 1, cells.push_back(q);
    }
    std::sort(cells.begin(), cells.end());
    run(FaceVelocityField<Dim>(graph_, u_, known_, options_.rbf, cells));
  }
  rebin<Dim>(graph_, particles_.x, bins_);
  check_particles("advect");
}

template <int Dim>
void AdaptivePic<Dim>::reseed(PicStepReport& r) {
  classify();
  std::vector<CellId> interior;
  std::set_difference(cls_.fluid.begin(), cls_.fluid.end(), cls_.surface.begin(), cls_.surface.end(),
                      std::back_inserter(interior));
  // Holes opened by this step's advection are refilled with the rest.
  ReseedOptions o = options_.reseeding;
  o.fill_empty = true;
  r.reseed = liquid::reseed<Dim>(graph_, interior, o, grid_velocity(), particles_, bins_);
  // New particles start with a zero affine part (APIC): fields of new particles are zero.
}

template <int Dim>
PicStepReport AdaptivePic<Dim>::advance(double dt) {
  LIQUID_VERIFY(seeded_, "PIC: advance() before seed()");
  LIQUID_VERIFY(std::isfinite(dt) && dt > 0.0, "PIC: time step {} is not a positive number", dt);
  PicStepReport r;
  r.step = step_;
  r.dt = dt;
  const auto phase = [this](const char* name, auto&& body) {
    const auto t = timer_.scope(name);
    body();
  };
  {
    const auto total = timer_.scope("total");
    phase("classify", [&] { classify(); });
    if (options_.adaptive) phase("grid", [&] { adapt_grid(r); });
    phase("p2g", [&] { to_faces(r); });
    phase("forces", [&] { forces(dt); });
    phase("laplacian", [&] { assemble(dt); });
    phase("ppe", [&] { solve_pressure(r); });
    phase("project", [&] { project(dt); });
    phase("extrapolate", [&] { extrapolate(); });
    phase("g2p", [&] { to_particles(r); });
    phase("advect", [&] { advect(dt, r); });
    if (options_.reseed) phase("reseed", [&] { reseed(r); });
  }
  ++step_;
  time_ += dt;
  r.time = time_;
  r.n_particles = particles_.size();
  r.n_cells = graph_.n_cells();
  r.n_fluid_cells = static_cast<long>(cls_.fluid.size());
  r.n_surface_cells = static_cast<long>(cls_.surface.size());
  return r;
}

template <int Dim>
double AdaptivePic<Dim>::stable_dt(double cfl, double max_dt) const {
  LIQUID_VERIFY(cfl > 0.0 && max_dt > 0.0, "PIC: CFL number {} and largest time step {} must be positive",
                cfl, max_dt);
  double vmax = 0.0;
  for (const auto& v : particles_.v) vmax = std::max(vmax, v.norm());
  // Gravity accelerates a particle at rest by |g| dt within the step: include it.
  vmax += std::sqrt(options_.gravity.norm() * finest_h());
  return vmax > 0.0 ? std::min(max_dt, cfl * finest_h() / vmax) : max_dt;
}

template <int Dim>
void AdaptivePic<Dim>::check_faces(const char* phase) const {
  graph_.for_each_face([&](FaceId f) {
    if (!std::isfinite(u_[f])) {
      const Vec<Dim> x = graph_.face_centre(f);
      throw Error(fmt::format("step {}, phase {}: face velocity {} at face {} (centre ({:.6g}))", step_,
                              phase, u_[f], f, fmt::join(x.data(), x.data() + Dim, ", ")));
    }
  });
}

template <int Dim>
void AdaptivePic<Dim>::check_particles(const char* phase) const {
  for (int i = 0; i < particles_.size(); ++i)
    if (!particles_.x[i].allFinite() || !particles_.v[i].allFinite()) {
      const Vec<Dim>& x = particles_.x[i];
      throw Error(fmt::format("step {}, phase {}: particle {} has position ({:.6g}) and velocity ({:.6g})",
                              step_, phase, i, fmt::join(x.data(), x.data() + Dim, ", "),
                              fmt::join(particles_.v[i].data(), particles_.v[i].data() + Dim, ", ")));
    }
}

template class AdaptivePic<2>;
template class AdaptivePic<3>;

}  // namespace liquid
