#include "liquid/pic/adaptive_pic.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "liquid/core/error.hpp"
#include "liquid/core/parallel.hpp"
#include "liquid/mac/divergence.hpp"
#include "liquid/transfer/extrapolate.hpp"
#include "liquid/transfer/velocity_field.hpp"
#include "liquid/tree/builders.hpp"
#include "liquid/tree/remap.hpp"

namespace liquid::pic {

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

const char* to_string(PicSurface surface) {
  return surface == PicSurface::air_cells ? "air" : "levelset";
}

const char* to_string(PicProjection projection) {
  switch (projection) {
    case PicProjection::volume:
      return "volume";
    case PicProjection::mass:
      return "mass";
    case PicProjection::split:
      return "split";
  }
  return "?";
}

PicProjection parse_pic_projection(const std::string& name) {
  if (name == "volume") return PicProjection::volume;
  if (name == "mass") return PicProjection::mass;
  if (name == "split") return PicProjection::split;
  throw Error(fmt::format("unknown projection '{}' (choices: volume, mass, split)", name));
}

PicSurface parse_pic_surface(const std::string& name) {
  if (name == "air") return PicSurface::air_cells;
  if (name == "levelset") return PicSurface::levelset;
  throw Error(fmt::format("unknown surface '{}' (choices: air, levelset)", name));
}

namespace {

template <int Dim>
tree::CellGraphOptions<Dim> graph_options(const PicOptions<Dim>& o) {
  tree::CellGraphOptions<Dim> g;
  g.max_jump = o.max_jump;
  g.min_level = o.adaptive ? std::min(o.coarse_level, o.finest_level) : o.finest_level;
  g.max_level = o.finest_level;
  return g;
}

template <int Dim>
tree::CellGraph<Dim> initial_graph(const PicOptions<Dim>& o) {
  LIQUID_VERIFY(o.domain.valid(), "PIC: the domain is empty");
  LIQUID_VERIFY(o.finest_level >= 1 && o.finest_level <= morton::max_level<Dim>,
                "PIC: fine level {} is outside [1, {}]", o.finest_level, morton::max_level<Dim>);
  LIQUID_VERIFY(!o.adaptive || (o.coarse_level >= 0 && o.coarse_level <= o.finest_level),
                "PIC: coarse level {} must be in [0, fine level {}]", o.coarse_level, o.finest_level);
  LIQUID_VERIFY(o.max_jump >= 1, "PIC: level jump limit {} (need at least 1)", o.max_jump);
  LIQUID_VERIFY(o.band >= 0, "PIC: band {} is negative", o.band);
  LIQUID_VERIFY(!o.adaptive || o.transfer == PicTransfer::rbf,
                "PIC: transfer '{}' needs a uniform tree (adaptive = false); adaptive trees use rbf",
                to_string(o.transfer));
  LIQUID_VERIFY(o.flip >= 0.0 && o.flip <= 1.0, "PIC: FLIP blend {} is outside [0, 1]", o.flip);
  LIQUID_VERIFY(o.surface_radius > 0.0 && o.surface_radius < 2.0,
                "PIC: surface radius {} (finest cells) is outside (0, 2)", o.surface_radius);
  LIQUID_VERIFY(o.projection == PicProjection::volume || o.transfer != PicTransfer::rbf,
                "PIC: the {} projection needs a regular transfer (pic, flip or apic) on a uniform tree",
                to_string(o.projection));
  LIQUID_VERIFY(
      !(o.tent_at_level_changes && o.rbf_gradient_affine && o.uniform_patches),
      "PIC: the tent particle -> face at level changes with the RBF gradient as the particles' C is "
      "unstable (a 2D still pool blew up); take one of them");
  LIQUID_VERIFY(o.level_change_tent_share >= 0.0 && o.level_change_tent_share <= 1.0,
                "PIC: level_change_tent_share {} is outside [0, 1]", o.level_change_tent_share);
  LIQUID_VERIFY(o.min_face_mass > 0.0 && o.min_face_mass <= 1.0, "PIC: min_face_mass {} is outside (0, 1]",
                o.min_face_mass);
  return tree::uniform<Dim>(o.domain, o.adaptive ? o.coarse_level : o.finest_level, graph_options(o));
}

/// The fluid cells that are not surface cells, ascending.
std::vector<tree::CellId> interior_of(const Classification& cls) {
  std::vector<tree::CellId> interior;
  std::set_difference(cls.fluid.begin(), cls.fluid.end(), cls.surface.begin(), cls.surface.end(),
                      std::back_inserter(interior));
  return interior;
}

}  // namespace

template <int Dim>
AdaptivePic<Dim>::AdaptivePic(const PicOptions<Dim>& options)
    : options_(options), graph_(initial_graph(options)) {
  if (options_.transfer == PicTransfer::rbf && options_.reseeding.lo == 0 && options_.reseeding.hi == 0) {
    // Top up sparse cells, never thin crowded ones: a cell below the paper's lower bound keeps its own
    // particles and gets new ones up to 2^Dim (docs/findings/dam-break-convergence.md).
    options_.reseeding.lo = Dim == 2 ? 3 : 5;
    options_.reseeding.hi = std::numeric_limits<int>::max();
    options_.reseeding.keep = true;
  }
  if (options_.transfer != PicTransfer::rbf)
    lattice_ = std::make_unique<transfer::RegularLattice<Dim>>(graph_);
  if (affine_particles()) apic_field_ = particles_.add_field("apic", Dim * Dim);
  u_.assign(graph_.face_capacity(), 0.0);
  known_.assign(graph_.face_capacity(), 1);
  p_.assign(graph_.cell_capacity(), 0.0);
  // At 2^-7 the RBF-FD rows meet some 7,000 new layouts a step; a bound of 2^14 dropped layouts still
  // in use every other step. Measured: docs/findings/table1-scale.md.
  weights_ = std::make_unique<rbf::WeightCache<Dim>>(0x1p-24, std::size_t{1} << 16);
  interpolants_ = std::make_unique<rbf::InterpolantCache<Dim>>(0x1p-24, std::size_t{1} << 13);
  // Made here, outside the timed phases: an AMG solver starts MPI when it is made.
  ppe_solver_ = linalg::make_solver(options_.solver);
}

template <int Dim>
AdaptivePic<Dim>::~AdaptivePic() = default;
template <int Dim>
AdaptivePic<Dim>::AdaptivePic(AdaptivePic&&) noexcept = default;

template <int Dim>
double AdaptivePic<Dim>::finest_h() const {
  return std::ldexp(graph_.domain().size().minCoeff(), -options_.finest_level);
}

template <int Dim>
void AdaptivePic<Dim>::seed(const levelset::Function<Dim>& liquid,
                            const std::function<Vec<Dim>(const Vec<Dim>&)>& velocity) {
  LIQUID_VERIFY(!seeded_, "PIC: seed() was already called");
  seeded_ = true;
  if (options_.adaptive) {
    graph_ = tree::narrow_band<Dim>(options_.domain, liquid, options_.coarse_level, options_.finest_level,
                                    options_.band + 1.0, graph_options(options_));
  }
  const particles::VelocitySource<Dim> source = [&](std::span<const Vec<Dim>> x,
                                                    std::span<const tree::CellId>, std::span<Vec<Dim>> v) {
    for (std::size_t i = 0; i < x.size(); ++i) v[i] = velocity ? velocity(x[i]) : Vec<Dim>::Zero();
  };
  solid_.clear();  // the tree was rebuilt: classify() evaluates the mask afresh
  const levelset::Function<Dim> region =
      options_.solid ? levelset::subtract<Dim>(liquid, options_.solid) : liquid;
  const long n = particles::seed_region<Dim>(graph_, region, particles::SeedOptions{}, particles_, source);
  LIQUID_VERIFY_INPUT(n > 0, "PIC: the liquid region holds no cell's sample point: nothing to simulate");
  particles::bin_particles<Dim>(graph_, particles_.x, bins_);
  u_.assign(graph_.face_capacity(), 0.0);
  known_.assign(graph_.face_capacity(), 1);
  p_.assign(graph_.cell_capacity(), 0.0);
  // Settle the band on the solver's own rule (surface cells, band hops) before the first step.
  bool changed = false;
  if (options_.adaptive)
    for (int round = 0; round <= options_.finest_level - options_.coarse_level; ++round) {
      classify();
      PicStepReport r;
      adapt_grid(r);
      if (r.n_split == 0 && r.n_merged == 0) break;
      changed = true;
    }
  if (changed) {
    // Seed again on the settled tree. The rounds above filled the children of split cells from the
    // grid, which is still at rest, and left others with one particle each: the particles would
    // start with less energy than their velocity field, which the first step's transfers restore
    // and which would read as an energy gain.
    particles_.clear();
    particles::seed_region<Dim>(graph_, region, particles::SeedOptions{}, particles_, source);
    particles::bin_particles<Dim>(graph_, particles_.x, bins_);
    u_.assign(graph_.face_capacity(), 0.0);
    known_.assign(graph_.face_capacity(), 1);
    p_.assign(graph_.cell_capacity(), 0.0);
  }
  classify();
  check_particles("seed");
}

template <int Dim>
PicState<Dim> AdaptivePic<Dim>::state() const {
  LIQUID_VERIFY(seeded_, "PIC: state() before seed()");
  PicState<Dim> s;
  s.graph = graph_.state();
  const int n = particles_.size();
  s.x.resize(static_cast<std::size_t>(n) * Dim);
  s.v.resize(static_cast<std::size_t>(n) * Dim);
  for (int i = 0; i < n; ++i)
    for (int d = 0; d < Dim; ++d) {
      s.x[static_cast<std::size_t>(i) * Dim + d] = particles_.x[i][d];
      s.v[static_cast<std::size_t>(i) * Dim + d] = particles_.v[i][d];
    }
  for (int f = 0; f < particles_.n_fields(); ++f) {
    s.field_names.push_back(particles_.field_name(f));
    s.field_components.push_back(particles_.field_components(f));
    const auto values = particles_.field(f);
    s.field_values.emplace_back(values.begin(), values.end());
  }
  s.particle_cell = bins_.cell;
  s.u = u_;
  s.p = p_;
  s.known = known_;
  s.time = time_;
  s.step = step_;
  return s;
}

template <int Dim>
void AdaptivePic<Dim>::restore(const PicState<Dim>& s) {
  LIQUID_VERIFY(!seeded_, "PIC: restore() after seed() or a restore()");
  tree::CellGraph<Dim> graph = tree::CellGraph<Dim>::from_state(s.graph);
  LIQUID_VERIFY(graph.domain().lo == options_.domain.lo && graph.domain().hi == options_.domain.hi,
                "PIC: the saved state's domain differs from the scene's");
  LIQUID_VERIFY(
      graph.options().max_jump == options_.max_jump && graph.options().max_level == options_.finest_level &&
          graph.options().min_level == graph_options(options_).min_level,
      "PIC: the saved state's tree (jump {}, finest level {}) differs from the options' (jump {}, finest {})",
      graph.options().max_jump, graph.options().max_level, options_.max_jump, options_.finest_level);
  const std::size_t n = s.particle_cell.size();
  LIQUID_VERIFY(s.x.size() == n * Dim && s.v.size() == n * Dim,
                "PIC: the saved state has {} positions and {} velocities for {} particles", s.x.size() / Dim,
                s.v.size() / Dim, n);
  LIQUID_VERIFY(
      s.u.size() == static_cast<std::size_t>(graph.face_capacity()) && s.known.size() == s.u.size() &&
          s.p.size() == static_cast<std::size_t>(graph.cell_capacity()),
      "PIC: the saved fields do not fit the saved tree ({} face and {} cell values for {} and {} ids)",
      s.u.size(), s.p.size(), graph.face_capacity(), graph.cell_capacity());
  LIQUID_VERIFY(
      s.field_names.size() == s.field_components.size() && s.field_names.size() == s.field_values.size(),
      "PIC: the saved particle fields are incomplete");
  LIQUID_VERIFY(std::isfinite(s.time) && s.time >= 0.0 && s.step >= 0,
                "PIC: the saved clock (step {}, time {}) is not a run's", s.step, s.time);
  const auto all_finite = [](const std::vector<double>& v) {
    return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
  };
  LIQUID_VERIFY(all_finite(s.u) && all_finite(s.p), "PIC: a saved face velocity or pressure is not finite");
  for (std::size_t f = 0; f < s.field_values.size(); ++f)
    LIQUID_VERIFY(all_finite(s.field_values[f]),
                  "PIC: saved particle field '{}' holds a value that is not finite", s.field_names[f]);
  graph_ = std::move(graph);
  solid_.clear();
  lattice_.reset();
  if (options_.transfer != PicTransfer::rbf)
    lattice_ = std::make_unique<transfer::RegularLattice<Dim>>(graph_);
  particles_.resize(static_cast<int>(n));
  for (std::size_t i = 0; i < n; ++i)
    for (int d = 0; d < Dim; ++d) {
      particles_.x[i][d] = s.x[i * Dim + d];
      particles_.v[i][d] = s.v[i * Dim + d];
    }
  for (std::size_t f = 0; f < s.field_names.size(); ++f) {
    int k = particles_.find_field(s.field_names[f]);
    if (k < 0) k = particles_.add_field(s.field_names[f], s.field_components[f]);
    LIQUID_VERIFY(particles_.field_components(k) == s.field_components[f] &&
                      s.field_values[f].size() == n * static_cast<std::size_t>(s.field_components[f]),
                  "PIC: saved particle field '{}' has the wrong size", s.field_names[f]);
    std::copy(s.field_values[f].begin(), s.field_values[f].end(), particles_.field(k).begin());
  }
  if (options_.transfer == PicTransfer::apic) {
    apic_field_ = particles_.find_field("apic");
    LIQUID_VERIFY(apic_field_ >= 0,
                  "PIC: the saved state has no 'apic' particle field for the APIC transfer");
  } else if (affine_particles()) {  // a state saved without patches: C = 0 is PIC's start
    apic_field_ = particles_.find_field("apic");
    if (apic_field_ < 0) apic_field_ = particles_.add_field("apic", Dim * Dim);
  }
  for (tree::CellId c : s.particle_cell)
    LIQUID_VERIFY(graph_.alive(c), "PIC: a saved particle is binned in cell {}, which is not a leaf", c);
  bins_.cell = s.particle_cell;
  bins_.sort(graph_.cell_capacity());
  u_ = s.u;
  p_ = s.p;
  known_ = s.known;
  time_ = s.time;
  step_ = s.step;
  seeded_ = true;
  classify();
  check_particles("restore");
}

template <int Dim>
particles::VelocitySource<Dim> AdaptivePic<Dim>::grid_velocity() const {
  return [this](std::span<const Vec<Dim>> x, std::span<const tree::CellId> cells, std::span<Vec<Dim>> v) {
    particles::CellBins b;
    b.cell.assign(cells.begin(), cells.end());
    b.sort(graph_.cell_capacity());
    if (lattice_) {
      transfer::linear_to_points<Dim>(*lattice_, u_, x, v);
      return;
    }
    transfer::faces_to_points<Dim>(graph_, u_, known_, x, b, options_.rbf, v);
  };
}

template <int Dim>
void AdaptivePic<Dim>::classify() {
  // The solid mask of the whole tree once (after seeding or restoring); adapt_grid() keeps it
  // current for the cells it creates, so a step does not evaluate the solid at every cell again.
  if (options_.solid && solid_.empty()) {
    solid_.assign(graph_.cell_capacity(), 0);
    graph_.for_each_cell([&](tree::CellId c) { solid_[c] = options_.solid(graph_.centre(c)) < 0.0; });
  }
  pic::classify_cells<Dim>(graph_, bins_, solid_, cls_);
}

template <int Dim>
void AdaptivePic<Dim>::apply_sources(PicStepReport& r) {
  for (const PicSource<Dim>& s : options_.sources) {
    if (!s.active(time_)) continue;
    std::vector<tree::CellId> cells;
    graph_.for_each_cell([&](tree::CellId c) {
      const Vec<Dim> x = graph_.centre(c);
      if (s.region(x) < 0.0 && !(options_.solid && options_.solid(x) < 0.0)) cells.push_back(c);
    });
    particles::ReseedOptions o = options_.reseeding;
    o.fill_empty = true;
    o.hi = std::numeric_limits<int>::max();  // only top up: never thin out what flows through
    const Vec<Dim> v = s.velocity;
    const particles::VelocitySource<Dim> inflow =
        [v](std::span<const Vec<Dim>>, std::span<const tree::CellId>, std::span<Vec<Dim>> out) {
          std::fill(out.begin(), out.end(), v);
        };
    const particles::ReseedReport rep = particles::reseed<Dim>(graph_, cells, o, inflow, particles_, bins_);
    r.n_source += rep.created - rep.deleted;
    for (tree::CellId c : cells)
      for (std::int32_t i : bins_.of(c))
        if (s.region(particles_.x[i]) < 0.0) particles_.v[i] = v;
  }
}

template <int Dim>
void AdaptivePic<Dim>::fill(std::span<const tree::CellId> cells, PicStepReport& r) {
  if (cells.empty()) return;
  particles::ReseedOptions o = options_.reseeding;
  o.fill_empty = true;
  const particles::ReseedReport rep =
      particles::reseed<Dim>(graph_, cells, o, grid_velocity(), particles_, bins_);
  r.n_filled += rep.created - rep.deleted;
}

template <int Dim>
void AdaptivePic<Dim>::adapt_grid(PicStepReport& r) {
  // The band is refined all the way to fine_level before the step goes on (adapt() splits a cell by
  // one level a round), so that the surface never enters a cell coarser than fine_level: a coarse
  // surface cell that splits later leaves its empty children as air, and the liquid loses their
  // volume (docs/findings/dam-break-convergence.md). Coarsening stays one level a step.
  // One round: mark the band (merges only when `merge`), adapt, fill; true when a cell split.
  const auto adapt_round = [&](bool merge) {
    tree::MarkList marks;
    // Active sources are kept fine like the surface: the liquid they create starts in the band. A
    // cell counts when the source may overlap it (level set within half its diagonal of the centre),
    // so that a source smaller than the coarse air cells around it is found and refined down to.
    std::vector<tree::CellId> centres = cls_.surface;
    for (const PicSource<Dim>& s : options_.sources)
      if (s.active(time_))
        graph_.for_each_cell([&](tree::CellId c) {
          if (s.region(graph_.centre(c)) < 0.5 * graph_.cell_size(c).norm() && !cls_.is_solid(c))
            centres.push_back(c);
        });
    if (options_.refine)
      graph_.for_each_cell([&](tree::CellId c) {
        if (options_.refine(graph_.centre(c)) < 0.5 * graph_.cell_size(c).norm()) centres.push_back(c);
      });
    // So is the liquid's contact with a solid, two hops wider than the band: no RBF-FD row then
    // reaches a solid cell, where fold_solid_rows() is only first order (a still pool around a
    // submerged box then stays still; docs/findings/pic-solver.md).
    if (!solid_.empty()) {
      std::vector<tree::CellId> ring;
      for (tree::CellId c : cls_.fluid)
        for (tree::FaceId f : graph_.faces(c))
          if (cls_.solid_face(graph_.face(f))) {
            graph_.k_ring(c, 2, ring);
            centres.insert(centres.end(), ring.begin(), ring.end());
            break;
          }
    }
    pic::mark_band<Dim>(graph_, centres, options_.band, options_.coarse_level, options_.finest_level, marks);
    if (!merge) marks.merge.clear();
    if (marks.split.empty() && marks.merge.empty()) return false;
    // Interior fluid cells about to split: their empty children are liquid and get particles.
    std::vector<std::uint8_t> interior(graph_.cell_capacity(), 0);
    for (tree::CellId c : cls_.fluid) interior[c] = 1;
    for (tree::CellId c : cls_.surface) interior[c] = 0;
    const tree::AdaptReport report = graph_.adapt(marks);
    r.n_split += report.n_split;
    r.n_merged += report.n_merged;
    if (report.empty()) return false;
    tree::remap::face_field(graph_, report, u_);
    std::vector<double> known(known_.begin(), known_.end());
    tree::remap::face_field(graph_, report, known);
    known_.resize(known.size());
    for (std::size_t f = 0; f < known.size(); ++f) known_[f] = known[f] > 0.5;
    tree::remap::cell_field(graph_, report, p_);
    if (!solid_.empty()) {
      solid_.resize(graph_.cell_capacity(), 0);
      for (tree::CellId c : report.new_cells) solid_[c] = options_.solid(graph_.centre(c)) < 0.0;
    }
    particles::rebin<Dim>(graph_, particles_.x, bins_, &report);
    std::vector<tree::CellId> children;
    const tree::Origins& o = report.cell_origins;
    for (std::size_t n = 0; n < report.new_cells.size(); ++n) {
      const tree::CellId c = report.new_cells[n];
      if (o.begin[n + 1] - o.begin[n] == 1 && interior[o.source[o.begin[n]]] && bins_.count(c) == 0)
        children.push_back(c);
    }
    fill(children, r);
    classify();
    return report.n_split > 0;
  };
  for (int round = 0; round <= options_.finest_level - options_.coarse_level; ++round)
    if (!adapt_round(round == 0)) break;
}

template <int Dim>
bool AdaptivePic<Dim>::affine_particles() const {
  return options_.transfer == PicTransfer::apic ||
         (options_.transfer == PicTransfer::rbf && options_.adaptive && options_.uniform_patches);
}

template <int Dim>
std::vector<tree::CellId> AdaptivePic<Dim>::near_liquid_cells() const {
  std::vector<tree::CellId> cells;  // where particles are, and one ring around
  std::vector<std::uint8_t> seen(graph_.cell_capacity(), 0);
  std::vector<tree::CellId> ring;
  for (tree::CellId c : cls_.fluid) {
    graph_.k_ring(c, 1, ring);
    for (tree::CellId q : ring)
      if (!seen[q]) seen[q] = 1, cells.push_back(q);
  }
  std::sort(cells.begin(), cells.end());
  return cells;
}

template <int Dim>
void AdaptivePic<Dim>::to_faces(PicStepReport& r) {
  transfer::FaceValues faces;
  patches_.reset();
  if (lattice_) {
    r.p2g = transfer::linear_to_faces<Dim>(
        graph_, *lattice_, particles_, bins_,
        options_.transfer == PicTransfer::apic ? transfer::RegularScheme::apic : transfer::RegularScheme::pic,
        {}, faces);
  } else if (affine_particles()) {
    near_cells_ = near_liquid_cells();
    patches_ = std::make_unique<transfer::UniformPatches<Dim>>(graph_, near_cells_);
    if (options_.tent_at_level_changes) {
      faces.reset(graph_.face_capacity());
      r.p2g = transfer::tent_to_faces<Dim>(graph_, particles_, bins_, particles_.field(apic_field_),
                                           patches_->face_mask(), faces);
    } else {
      r.p2g = transfer::particles_to_faces<Dim>(graph_, particles_, bins_, options_.rbf, faces,
                                                patches_->face_mask());
      transfer::blend_tent_mean<Dim>(graph_, particles_, bins_, patches_->face_mask(),
                                     options_.level_change_tent_share, faces);
    }
    r.p2g += patches_->to_faces(particles_, bins_, particles_.field(apic_field_), faces);
    r.patch_cells = patches_->n_cells();
    r.near_cells = static_cast<long>(near_cells_.size());
    r.patch_faces = patches_->n_faces();
  } else {
    r.p2g = transfer::particles_to_faces<Dim>(graph_, particles_, bins_, options_.rbf, faces);
  }
  r.unknown_faces = r.p2g.empty;
  // The transfer's masses are unit particle masses times weights: a full cell's seeded particles
  // (2^Dim) weigh 2^Dim on each of its faces. Kept for every regular transfer (pressure_work; the
  // mass and split projections need one, see the options' check).
  if (lattice_) face_mass_ = std::move(faces.weight);
  if (options_.projection != PicProjection::volume) {
    const double full = static_cast<double>(1 << Dim);
    face_beta_.resize(face_mass_.size());
    for (std::size_t f = 0; f < face_mass_.size(); ++f)
      face_beta_[f] = full / std::max(face_mass_[f], options_.min_face_mass * full);
  }
  u_ = std::move(faces.value);
  known_ = std::move(faces.known);
  extrapolate();
  u_transferred_ = u_;
  check_faces("p2g");
}

template <int Dim>
void AdaptivePic<Dim>::forces(double dt) {
  // Walls are at rest: the transferred normal velocity there is replaced by the wall's (0) before
  // gravity, so u* on a wall face is dt g. The PPE then takes dp/dn = u* . n / dt on the walls and
  // the projection brings the wall faces back to 0 (see assemble()).
  // Solids are at rest and take no gravity: their faces are 0, and the PPE rows beside them have no
  // flux through them (see fold_solid_rows()).
  graph_.for_each_face([&](tree::FaceId f) {
    const tree::GraphFace& g = graph_.face(f);
    u_[f] = cls_.solid_face(g) ? 0.0 : (g.is_boundary() ? 0.0 : u_[f]) + dt * options_.gravity[g.axis];
  });
  check_faces("forces");
}

template <int Dim>
void AdaptivePic<Dim>::project_gravity(double dt, PicStepReport& r) {
  // PicProjection::split: gravity's kick alone, projected in volumes (its pressure is the
  // hydrostatic one wherever the liquid is at rest), is added back to the transferred velocity,
  // which the mass projection then projects.
  std::vector<double> kick(u_.size(), 0.0);
  graph_.for_each_face([&](tree::FaceId f) {
    const tree::GraphFace& g = graph_.face(f);
    if (!cls_.solid_face(g)) kick[f] = dt * options_.gravity[g.axis];
  });
  std::vector<double> rest(u_.size());
  for (std::size_t f = 0; f < u_.size(); ++f) rest[f] = u_[f] - kick[f];
  u_ = std::move(kick);
  volume_pass_ = true;
  assemble(dt);
  // Both solves start from the step before's whole pressure (p_, which a checkpoint keeps): the
  // gravity pass's is mostly hydrostatic, and the mass pass solves for the whole pressure.
  const std::vector<double> before = p_;
  PicStepReport gravity;
  solve_pressure(gravity);
  r.ppe_gravity = gravity.ppe;
  r.ppe_fallbacks += gravity.ppe_fallbacks;
  project(dt);  // keeps the pressure's normal derivative in gravity_gradient_
  volume_pass_ = false;
  gravity_pressure_ = p_;
  p_ = before;
  for (std::size_t f = 0; f < u_.size(); ++f) u_[f] += rest[f];
  check_faces("gravity");
}

template <int Dim>
void AdaptivePic<Dim>::assemble(double dt) {
  const std::vector<double> div = mac::fv_divergence<Dim>(graph_, u_);
  mac::PoissonProblem<Dim> problem;
  problem.f_cells.assign(graph_.cell_capacity(), 0.0);
  problem.boundary.unknown_cells.assign(graph_.cell_capacity(), 0);
  if (options_.surface == PicSurface::levelset) {
    // Unknowns where the particles' level set is negative: the fluid cells and the air cells next
    // to them, by the sign at their centres; the PPE cuts every edge leaving them at its zero set.
    // The split projection's mass pass keeps the surface its gravity pass built: same particles, same step.
    const bool built_this_step = options_.projection == PicProjection::split && !volume_pass_ && surface_;
    if (!built_this_step)
      surface_ = std::make_unique<pic::ParticleSurface<Dim>>(graph_, cls_, particles_.x,
                                                             options_.finest_level, options_.surface_radius);
    std::vector<std::uint8_t> seen(graph_.cell_capacity(), 0);
    const auto consider = [&](tree::CellId c) {
      if (seen[c] || cls_.is_solid(c)) return;
      seen[c] = 1;
      if ((*surface_)(graph_.centre(c)) < 0.0) problem.boundary.unknown_cells[c] = 1;
    };
    // Two hops out, so that no unknown has a neighbour with a negative centre left outside (the
    // PPE needs a sign change on every edge it cuts).
    std::vector<tree::CellId> ring;
    for (tree::CellId c : cls_.fluid) {
      graph_.k_ring(c, 2, ring);
      for (tree::CellId n : ring) consider(n);
    }
    graph_.for_each_cell([&](tree::CellId c) {
      if (problem.boundary.unknown_cells[c]) problem.f_cells[c] = div[c] / dt;
    });
    // Every solid cell is an unknown (decoupled by fold_solid_rows()), and the level set is
    // negative inside the solid, so that each edge the PPE cuts has a sign change on it: a solid
    // cell left outside had none towards its solid neighbours (seen on dam-break-obstacles-3d).
    if (!solid_.empty()) {
      graph_.for_each_cell([&](tree::CellId c) {
        if (cls_.is_solid(c)) problem.boundary.unknown_cells[c] = 1;
      });
      problem.boundary.levelset = [s = surface_.get(), solid = options_.solid](const Vec<Dim>& x) {
        return solid(x) < 0.0 ? -s->support() : (*s)(x);
      };
    } else {
      problem.boundary.levelset = [s = surface_.get()](const Vec<Dim>& x) { return (*s)(x); };
    }
  } else {
    surface_.reset();
    for (tree::CellId c : cls_.fluid) {
      problem.f_cells[c] = div[c] / dt;
      problem.boundary.unknown_cells[c] = 1;
    }
  }
  // Solid cells within two face hops of the liquid are unknowns too, so that no row sees them as
  // air (p = 0); fold_solid_rows() then decouples them.
  if (!solid_.empty()) {
    std::vector<tree::CellId> frontier, next;
    graph_.for_each_cell([&](tree::CellId c) {
      if (problem.boundary.unknown_cells[c]) frontier.push_back(c);
    });
    for (int hop = 0; hop < 2; ++hop) {
      next.clear();
      for (tree::CellId c : frontier)
        for (tree::FaceId f : graph_.faces(c)) {
          const tree::GraphFace& g = graph_.face(f);
          const tree::CellId n = g.cell[0] == c ? g.cell[1] : g.cell[0];
          if (n != tree::no_cell && cls_.is_solid(n) && !problem.boundary.unknown_cells[n])
            problem.boundary.unknown_cells[n] = 1, next.push_back(n);
        }
      frontier.swap(next);
    }
  }
  problem.boundary.dirichlet = [](const Vec<Dim>&) { return 0.0; };
  problem.pin_value = [](const Vec<Dim>&) { return 0.0; };
  // Walls: dp/dn = (u* - u_wall) . n / dt with u_wall = 0, which is what makes the flux balance of
  // every row (FD and RBF-FD alike) hold for the hydrostatic pressure. With dp/dn = 0 the mirror
  // nodes of RBF-FD rows that reach a wall see a kinked pressure (an O(1) row error).
  const double nudge = 1e-6 * finest_h();
  problem.boundary.wall_flux = [this, dt, nudge](const Vec<Dim>& x, const Vec<Dim>& n) {
    int axis = 0;
    for (int k = 0; k < Dim; ++k)
      if (n[k] != 0.0) axis = k;
    const int side = 2 * axis + (n[axis] > 0 ? 1 : 0);
    const tree::CellId c = graph_.locate(Vec<Dim>(x - nudge * n));
    for (tree::FaceId f : graph_.faces(c))
      if (graph_.face(f).boundary == side) return n[axis] * u_[f] / dt;
    return 0.0;
  };
  if (options_.projection != PicProjection::volume && !volume_pass_) problem.face_coefficient = face_beta_;
  system_ = mac::assemble_poisson<Dim>(graph_, problem, options_.poisson, weights_.get());
  if (!solid_.empty()) fold_solid_rows();
}

template <int Dim>
void AdaptivePic<Dim>::fold_solid_rows() {
  // A liquid row's coefficient on a solid cell moves to its diagonal: p_solid = p_cell in that row,
  // which is exactly dp/dn = 0 (no flux) through the face of an FD row, and a first-order mirror in
  // an RBF-FD row that reaches a solid cell. A solid unknown's row becomes p = 0; its value for the
  // gradients is set after the solve (extend_into_solid). The matrix stays symmetric when it was.
  linalg::SparseMatrix& A = system_.A;
  const auto& cell_of = system_.layout.cell_of_dof;
  const auto solid_dof = [&](long j) { return j < system_.n_unknowns() && cls_.is_solid(cell_of[j]); };
  for (long i = 0; i < system_.n_unknowns(); ++i) {
    const bool solid_row = cls_.is_solid(cell_of[i]);
    double folded = 0.0;
    for (linalg::SparseMatrix::InnerIterator it(A, i); it; ++it) {
      if (solid_row) {
        it.valueRef() = it.col() == i ? 1.0 : 0.0;
      } else if (solid_dof(it.col())) {
        folded += it.value();
        it.valueRef() = 0.0;
      }
    }
    if (solid_row)
      system_.b[i] = 0.0;
    else if (folded != 0.0)
      A.coeffRef(i, i) += folded;
  }
  A.prune(0.0);
}

template <int Dim>
void AdaptivePic<Dim>::interface_gradients(double, std::vector<double>& dn) const {
  // A face between an unknown and a cell outside the liquid: the ghost-fluid gradient from p = 0
  // at the interface crossing (mac::ghost_face). Second order in the surface position.
  const auto& layout = system_.layout;
  const linalg::Vector& p = system_.b;
  graph_.for_each_face([&](tree::FaceId f) {
    const tree::GraphFace& g = graph_.face(f);
    if (g.is_boundary() || std::isfinite(dn[f]) || cls_.solid_face(g)) return;
    const int i0 = layout.dof_of_cell[g.cell[0]], i1 = layout.dof_of_cell[g.cell[1]];
    if ((i0 >= 0) == (i1 >= 0)) return;
    const int in = i0 >= 0 ? 0 : 1;
    const mac::GhostFace ghost = mac::ghost_face<Dim>(system_.boundary, graph_.centre(g.cell[in]),
                                                      graph_.centre(g.cell[1 - in]), g.axis);
    const double p_in = p[in == 0 ? i0 : i1];
    // Along +axis: from cell[0] to cell[1].
    const double towards_outside = (ghost.value - p_in) / ghost.distance;
    dn[f] = in == 0 ? towards_outside : -towards_outside;
  });
}

template <int Dim>
void AdaptivePic<Dim>::extend_into_solid(linalg::Vector& x) const {
  // Two Jacobi sweeps of the mean over liquid (then already extended) face neighbours: the solid
  // unknowns that gradient stencils of liquid faces may reach carry the liquid's pressure.
  const auto& layout = system_.layout;
  std::vector<std::uint8_t> set(graph_.cell_capacity(), 0);
  for (long i = 0; i < system_.n_unknowns(); ++i)
    if (!cls_.is_solid(layout.cell_of_dof[i])) set[layout.cell_of_dof[i]] = 1;
  for (int sweep = 0; sweep < 2; ++sweep) {
    std::vector<std::pair<long, double>> update;
    for (long i = 0; i < system_.n_unknowns(); ++i) {
      const tree::CellId c = layout.cell_of_dof[i];
      if (!cls_.is_solid(c) || set[c]) continue;
      double sum = 0.0;
      int n = 0;
      for (tree::FaceId f : graph_.faces(c)) {
        const tree::GraphFace& g = graph_.face(f);
        const tree::CellId q = g.cell[0] == c ? g.cell[1] : g.cell[0];
        if (q != tree::no_cell && set[q] && layout.is_unknown(q)) sum += x[layout.dof_of_cell[q]], ++n;
      }
      if (n > 0) update.emplace_back(i, sum / n);
    }
    for (const auto& [i, v] : update) x[i] = v, set[layout.cell_of_dof[i]] = 1;
  }
}

template <int Dim>
void AdaptivePic<Dim>::solve_pressure(PicStepReport& r) {
  // The guess: the last step's pressure (p_ holds it until the solve is done).
  const auto guess = [this](linalg::Vector& x) {
    x.setZero(system_.A.rows());
    for (long i = 0; i < system_.n_unknowns(); ++i) x[i] = p_[system_.layout.cell_of_dof[i]];
  };
  linalg::Vector x;
  guess(x);
  linalg::LinearSolver* solver = ppe_solver_.get();
  if (system_.bordered && linalg::needs_symmetric(options_.solver.kind)) {
    if (!bordered_ppe_solver_) {
      linalg::SolveOptions o = options_.solver;
      o.kind = linalg::nonsymmetric_counterpart(o.kind);
      bordered_ppe_solver_ = linalg::make_solver(o);
    }
    solver = bordered_ppe_solver_.get();
  }
  r.ppe = solver->solve(system_.A, system_.b, x);
  if (!r.ppe.converged() && options_.ppe_fallback && !linalg::uses_amg(options_.solver.kind)) {
    // Once more with AMG, from where the first solver got to (or from the guess after a breakdown).
    if (!fallback_ppe_solver_) {
      linalg::SolveOptions o = options_.solver;
      o.kind = linalg::SolverKind::bicgstab_amg;
      o.max_iterations = linalg::SolveOptions{}.max_iterations;  // AMG's own cap, not the first solver's
      fallback_ppe_solver_ = linalg::make_solver(o);
    }
    if (!x.allFinite()) guess(x);
    const linalg::SolveStats first = r.ppe;
    r.ppe = fallback_ppe_solver_->solve(system_.A, system_.b, x);
    r.ppe.solver = first.solver + ", then " + r.ppe.solver;
    r.ppe.iterations += first.iterations;
    r.ppe.setup_seconds += first.setup_seconds;
    r.ppe.solve_seconds += first.solve_seconds;
    ++r.ppe_fallbacks;
  }
  if (!solid_.empty()) extend_into_solid(x);
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
double AdaptivePic<Dim>::project(double dt) {
  std::vector<double> dn =
      mac::face_normal_derivative<Dim>(graph_, system_, options_.poisson, system_.b, weights_.get());
  if (surface_) interface_gradients(dt, dn);
  // The mass and split projections keep the transferred value of faces that hold mass (see below).
  const bool keep_massed = options_.projection != PicProjection::volume && !face_mass_.empty();
  if (volume_pass_) gravity_gradient_.assign(u_.size(), 0.0);
  // pressure_work: what the pressure applied in volumes does in the transferred masses.
  const bool in_volumes = options_.projection == PicProjection::volume;
  const bool has_masses = face_mass_.size() == u_.size();
  double work = has_masses ? 0.0 : std::numeric_limits<double>::quiet_NaN();
  graph_.for_each_face([&](tree::FaceId f) {
    const tree::GraphFace& g = graph_.face(f);
    if (g.is_boundary() || cls_.solid_face(g)) {
      u_[f] = 0.0;
      known_[f] = 1;
      return;
    }
    // Air-cell surface: the faces next to fluid cells. Level-set surface: the faces next to an
    // unknown, whose gradient mac or interface_gradients() gave. The mass projection also keeps the
    // transferred value (with gravity) of every other face that holds mass: p = 0 on both its sides,
    // and extrapolated values there raised the particles' energy (see PicProjection).
    const bool wet = surface_ ? std::isfinite(dn[f]) : cls_.wet(g);
    if (!volume_pass_) known_[f] = wet || (keep_massed && face_mass_[f] > 0.0);
    if (wet) u_[f] -= dt * (face_beta_.empty() || volume_pass_ ? 1.0 : face_beta_[f]) * dn[f];
    if (volume_pass_ && wet) gravity_gradient_[f] = dn[f];
    if (!has_masses || volume_pass_) return;
    if (in_volumes && wet) work -= dt * face_mass_[f] * u_[f] * dn[f];
    if (options_.projection == PicProjection::split)
      work -= dt * face_mass_[f] * u_[f] * gravity_gradient_[f];
  });
  check_faces("project");
  return volume_pass_ ? std::numeric_limits<double>::quiet_NaN() : work;
}

template <int Dim>
double AdaptivePic<Dim>::grid_energy() const {
  double sum = 0.0;
  graph_.for_each_face([&](tree::FaceId f) {
    const tree::GraphFace& g = graph_.face(f);
    if (g.is_boundary() || !cls_.wet(g)) return;
    const double d = std::abs(graph_.centre(g.cell[1])[g.axis] - graph_.centre(g.cell[0])[g.axis]);
    // The mass projection's norm: each face's volume times its mass over a full cell's (1 / beta).
    const double weight = face_beta_.empty() ? 1.0 : 1.0 / face_beta_[f];
    sum += weight * u_[f] * u_[f] * graph_.face_area(f) * d;
  });
  return 0.5 * sum;
}

template <int Dim>
void AdaptivePic<Dim>::extrapolate() {
  if (lattice_)
    transfer::extrapolate_lattice<Dim>(*lattice_, options_.extrapolation_layers, u_, known_);
  else
    transfer::extrapolate_faces<Dim>(graph_, options_.extrapolation_layers, u_, known_, &adjacency_);
}

template <int Dim>
void AdaptivePic<Dim>::to_particles(PicStepReport& r) {
  const int n = particles_.size();
  std::vector<Vec<Dim>> grid(n);
  if (lattice_) {
    std::span<double> affine;
    if (options_.transfer == PicTransfer::apic) affine = particles_.field(apic_field_);
    r.g2p = transfer::linear_to_points<Dim>(*lattice_, u_, particles_.x, grid, affine, bins_.index);
  } else {
    // One RBF field serves g2p and the advection after it: each cell's interpolants are factorised
    // once a step instead of twice (the same stencils and values as faces_to_points). With uniform
    // patches, a particle in a patch cell takes APIC's interpolation and matrix C; the others C = 0.
    if (!patches_) near_cells_ = near_liquid_cells();
    field_ = std::make_unique<transfer::FaceVelocityField<Dim>>(graph_, u_, known_, options_.rbf, near_cells_,
                                                                patches_.get(), interpolants_.get());
    std::span<double> affine;
    if (patches_) affine = particles_.field(apic_field_);
    // Cell by cell (the bins' order): a cell's particles read the same faces one after another.
    LIQUID_ASSERT(static_cast<int>(bins_.index.size()) == n, "g2p: {} binned particles, {} particles",
                  bins_.index.size(), n);
    parallel_for(
        static_cast<long>(n),
        [&](long q) {
          const long i = bins_.index[q];
          if (patches_ && patches_->cell(bins_.cell[i])) {
            grid[i] = patches_->value(bins_.cell[i], particles_.x[i], u_, affine.data() + i * Dim * Dim);
            return;
          }
          if (!affine.empty() && options_.rbf_gradient_affine) {
            grid[i] = field_->with_gradient(particles_.x[i], affine.data() + i * Dim * Dim);
            return;
          }
          grid[i] = (*field_)(particles_.x[i]);
          if (!affine.empty()) std::fill_n(affine.data() + i * Dim * Dim, Dim * Dim, 0.0);
        },
        1024);
    r.g2p.targets = static_cast<long>(n) * Dim;
  }
  if (options_.transfer == PicTransfer::flip) {
    std::vector<double> du(u_.size());
    for (std::size_t f = 0; f < u_.size(); ++f) du[f] = u_[f] - u_transferred_[f];
    std::vector<Vec<Dim>> delta(n);
    transfer::linear_to_points<Dim>(*lattice_, du, particles_.x, delta, {}, bins_.index);
    transfer::flip_blend<Dim>(grid, delta, options_.flip, particles_.v);
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
      const particles::AdvectReport a = particles::advect<Dim>(
          particles_.x, dt / n_sub, options_.integrator, field, graph_.domain(), options_.solid, bins_.index);
      r.advect.clamped += a.clamped;
      r.advect.pushed += a.pushed;
      r.advect.stuck += a.stuck;
    }
  };
  if (lattice_) {
    run(transfer::FaceVelocityField<Dim>(graph_, *lattice_, u_));
  } else {
    run(*field_);  // built by g2p from the same face velocities
  }
  particles::rebin<Dim>(graph_, particles_.x, bins_);
  check_particles("advect");
}

template <int Dim>
void AdaptivePic<Dim>::reseed(PicStepReport& r, std::span<const tree::CellId> was_interior) {
  classify();
  std::vector<tree::CellId> interior = interior_of(cls_);
  // Cells inside the liquid at the step's start that it left empty: refilled as the holes are.
  std::vector<tree::CellId> emptied;
  for (tree::CellId c : was_interior)
    if (cls_.type[c] == CellType::air) emptied.push_back(c);
  if (!emptied.empty()) {
    std::vector<tree::CellId> all(interior.size() + emptied.size());
    std::merge(interior.begin(), interior.end(), emptied.begin(), emptied.end(), all.begin());
    interior.swap(all);
  }
  // Holes opened by this step's advection are refilled with the rest.
  particles::ReseedOptions o = options_.reseeding;
  o.fill_empty = true;
  r.reseed = particles::reseed<Dim>(graph_, interior, o, grid_velocity(), particles_, bins_);
  if (options_.solid) {  // a new particle in the solid part of a fluid cell is pushed out at once
    const double eps = 1e-6 * graph_.domain().size().maxCoeff();
    long moved = 0;
    for (int i = particles_.size() - static_cast<int>(r.reseed.created); i < particles_.size(); ++i)
      moved += particles::detail::push_out<Dim>(options_.solid, eps, particles_.x[i]) > 0;
    if (moved > 0) particles::rebin<Dim>(graph_, particles_.x, bins_);
    r.advect.pushed += moved;
  }
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
    if (!options_.sources.empty()) phase("sources", [&] { apply_sources(r); });
    phase("classify", [&] { classify(); });
    if (options_.adaptive) phase("grid", [&] { adapt_grid(r); });
    const std::vector<tree::CellId> was_interior =
        options_.adaptive && options_.reseed && options_.refill_emptied ? interior_of(cls_)
                                                                        : std::vector<tree::CellId>{};
    phase("p2g", [&] { to_faces(r); });
    phase("forces", [&] { forces(dt); });
    if (options_.projection == PicProjection::split) phase("gravity", [&] { project_gravity(dt, r); });
    phase("laplacian", [&] { assemble(dt); });
    phase("ppe", [&] {
      if (options_.projection != PicProjection::split) {
        solve_pressure(r);
        return;
      }
      // The mass pass solves for the whole pressure q = p + p_g (A q = b + A p_g): its tolerance is
      // then relative to the whole step's right-hand side, as one solve's would be, not to its own
      // (round-off in a pool at rest, where the solver would iterate on noise).
      linalg::Vector gravity = linalg::Vector::Zero(system_.A.rows());
      for (long i = 0; i < system_.n_unknowns(); ++i)
        gravity[i] = gravity_pressure_[system_.layout.cell_of_dof[i]];
      system_.b += system_.A * gravity;
      solve_pressure(r);
      system_.b -= gravity;  // the mass pass's own pressure, which project() applies
    });
    phase("project", [&] {
      r.grid_energy_before = grid_energy();
      r.pressure_work = project(dt);
      r.grid_energy_after = grid_energy();
      for (tree::CellId c : cls_.fluid)
        r.divergence_after = std::max(
            r.divergence_after, std::abs(mac::fv_divergence_at<Dim>(graph_, u_, c)) * graph_.cell_size(c)[0]);
    });
    phase("extrapolate", [&] { extrapolate(); });
    phase("g2p", [&] { to_particles(r); });
    phase("advect", [&] { advect(dt, r); });
    if (options_.reseed) phase("reseed", [&] { reseed(r, was_interior); });
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
  graph_.for_each_face([&](tree::FaceId f) {
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

}  // namespace liquid::pic
