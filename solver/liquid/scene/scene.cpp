// Reading a scene file: one TableReader per TOML table knows the table's keys, reads each as its
// type with the file and line in every message, and refuses the keys it does not know.
#include "liquid/scene/scene.hpp"

#include <fmt/format.h>

#include <toml++/toml.h>
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>

#include "liquid/core/error.hpp"
#include "liquid/scene/expression.hpp"

#ifndef LIQUID_SCENES_DIR
#define LIQUID_SCENES_DIR "solver/scenes"
#endif

namespace liquid::scene {

namespace {

int edit_distance(const std::string& a, const std::string& b) {
  std::vector<int> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = static_cast<int>(j);
  for (std::size_t i = 1; i <= a.size(); ++i) {
    int diagonal = row[0];
    row[0] = static_cast<int>(i);
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const int up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

toml::table parse(const std::string& path) {
  LIQUID_VERIFY(std::filesystem::is_regular_file(path), "scene file '{}' does not exist or is not a file",
                path);
  try {
    return toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    throw Error(
        fmt::format("{}:{}:{}: {}", path, e.source().begin.line, e.source().begin.column, e.description()));
  }
}

/// Reads the keys of one table. Every read names "FILE:LINE: key 'PREFIX.KEY'" on failure.
class TableReader {
 public:
  TableReader(const toml::table& table, std::string path, std::string prefix, std::vector<std::string> known)
      : table_(table), path_(std::move(path)), prefix_(std::move(prefix)), known_(std::move(known)) {
    for (const auto& [key, node] : table_) {
      const std::string k(key.str());
      if (std::find(known_.begin(), known_.end(), k) != known_.end()) continue;
      std::string hint;
      int best = 3;
      for (const std::string& candidate : known_)
        if (const int d = edit_distance(k, candidate); d < best) best = d, hint = candidate;
      throw Error(fmt::format("{}: unknown key '{}'{} (known here: {})", line(node), name(k),
                              hint.empty() ? "" : fmt::format(" (did you mean '{}'?)", hint),
                              fmt::join(known_, ", ")));
    }
  }

  bool has(const char* key) const { return table_.contains(key); }
  std::string name(const std::string& key) const { return prefix_.empty() ? key : prefix_ + "." + key; }
  std::string line(const toml::node& node) const {
    return fmt::format("{}:{}", path_, node.source().begin.line);
  }
  std::string where(const char* key) const {
    const toml::node* n = table_.get(key);
    return fmt::format("{}: key '{}'", n ? line(*n) : line(table_), name(key));
  }
  std::string where_table() const { return fmt::format("{}: [{}]", line(table_), prefix_); }

  double number(const char* key, std::optional<double> fallback = std::nullopt) const {
    const toml::node* n = table_.get(key);
    if (!n) return required(key, fallback);
    std::optional<double> v;
    if (n->is_floating_point()) v = n->as_floating_point()->get();
    if (n->is_integer()) v = static_cast<double>(n->as_integer()->get());
    LIQUID_VERIFY(v.has_value(), "{}: expected a number, found {}", where(key), type_name(*n));
    LIQUID_VERIFY(std::isfinite(*v), "{}: expected a finite number, found {}", where(key), *v);
    return *v;
  }
  double positive(const char* key, std::optional<double> fallback = std::nullopt) const {
    const double v = number(key, fallback);
    LIQUID_VERIFY(v > 0.0, "{}: must be positive (found {})", where(key), v);
    return v;
  }
  long integer(const char* key, std::optional<long> fallback = std::nullopt) const {
    const toml::node* n = table_.get(key);
    if (!n) return required(key, fallback);
    LIQUID_VERIFY(n->is_integer(), "{}: expected an integer, found {}", where(key), type_name(*n));
    return static_cast<long>(n->as_integer()->get());
  }
  long integer_in(const char* key, long lo, long hi, std::optional<long> fallback = std::nullopt) const {
    const long v = integer(key, fallback);
    LIQUID_VERIFY(v >= lo && v <= hi, "{}: {} is outside [{}, {}]", where(key), v, lo, hi);
    return v;
  }
  bool boolean(const char* key, bool fallback) const {
    const toml::node* n = table_.get(key);
    if (!n) return fallback;
    LIQUID_VERIFY(n->is_boolean(), "{}: expected true or false, found {}", where(key), type_name(*n));
    return n->as_boolean()->get();
  }
  std::string string(const char* key, std::optional<std::string> fallback = std::nullopt) const {
    const toml::node* n = table_.get(key);
    if (!n) return required(key, fallback);
    LIQUID_VERIFY(n->is_string(), "{}: expected a string, found {}", where(key), type_name(*n));
    return n->as_string()->get();
  }
  /// A string that must be one of `choices`.
  std::string choice(const char* key, const std::vector<std::string>& choices,
                     std::optional<std::string> fallback = std::nullopt) const {
    const std::string v = string(key, fallback);
    LIQUID_VERIFY(std::find(choices.begin(), choices.end(), v) != choices.end(), "{}: '{}' is not one of {}",
                  where(key), v, fmt::join(choices, ", "));
    return v;
  }
  /// An array of strings, each one of `choices`, no repeats.
  std::vector<std::string> strings(const char* key, const std::vector<std::string>& choices,
                                   std::vector<std::string> fallback) const {
    const toml::node* n = table_.get(key);
    if (!n) return fallback;
    const toml::array* a = n->as_array();
    LIQUID_VERIFY(a != nullptr, "{}: expected an array of strings, found {}", where(key), type_name(*n));
    std::vector<std::string> out;
    for (const toml::node& e : *a) {
      LIQUID_VERIFY(e.is_string(), "{}: every entry must be a string, found {}", where(key), type_name(e));
      const std::string v = e.as_string()->get();
      LIQUID_VERIFY(std::find(choices.begin(), choices.end(), v) != choices.end(),
                    "{}: '{}' is not one of {}", where(key), v, fmt::join(choices, ", "));
      LIQUID_VERIFY(std::find(out.begin(), out.end(), v) == out.end(), "{}: '{}' is listed twice", where(key),
                    v);
      out.push_back(v);
    }
    return out;
  }
  template <int Dim>
  Vec<Dim> vec(const char* key, std::optional<Vec<Dim>> fallback = std::nullopt) const {
    const toml::node* n = table_.get(key);
    if (!n) return required(key, fallback);
    const toml::array* a = n->as_array();
    LIQUID_VERIFY(a != nullptr, "{}: expected an array of {} numbers, found {}", where(key), Dim,
                  type_name(*n));
    LIQUID_VERIFY(static_cast<int>(a->size()) == Dim, "{}: expected {} numbers (the scene is {}D), found {}",
                  where(key), Dim, Dim, a->size());
    Vec<Dim> v;
    for (int d = 0; d < Dim; ++d) {
      const toml::node& e = *a->get(d);
      std::optional<double> x;
      if (e.is_floating_point()) x = e.as_floating_point()->get();
      if (e.is_integer()) x = static_cast<double>(e.as_integer()->get());
      LIQUID_VERIFY(x && std::isfinite(*x), "{}: entry {} is not a finite number", where(key), d + 1);
      v[d] = *x;
    }
    return v;
  }
  const toml::table* table(const char* key) const {
    const toml::node* n = table_.get(key);
    if (!n) return nullptr;
    LIQUID_VERIFY(n->is_table(), "{}: expected a table [{}], found {}", where(key), name(key), type_name(*n));
    return n->as_table();
  }
  /// The tables of an array of tables [[key]] (empty when absent).
  std::vector<const toml::table*> tables(const char* key) const {
    std::vector<const toml::table*> out;
    const toml::node* n = table_.get(key);
    if (!n) return out;
    const toml::array* a = n->as_array();
    LIQUID_VERIFY(a != nullptr, "{}: expected an array of tables [[{}]], found {}", where(key), name(key),
                  type_name(*n));
    for (const toml::node& e : *a) {
      LIQUID_VERIFY(e.is_table(), "{}: every entry of [[{}]] must be a table", line(e), name(key));
      out.push_back(e.as_table());
    }
    return out;
  }
  const std::string& path() const { return path_; }

 private:
  template <class T>
  T required(const char* key, const std::optional<T>& fallback) const {
    LIQUID_VERIFY(fallback.has_value(), "{}: missing key '{}'", prefix_.empty() ? path_ : where_table(),
                  name(key));
    return *fallback;
  }
  static const char* type_name(const toml::node& n) {
    switch (n.type()) {
      case toml::node_type::string:
        return "a string";
      case toml::node_type::integer:
        return "an integer";
      case toml::node_type::floating_point:
        return "a number";
      case toml::node_type::boolean:
        return "a boolean";
      case toml::node_type::array:
        return "an array";
      case toml::node_type::table:
        return "a table";
      default:
        return "a date or time";
    }
  }

  const toml::table& table_;
  std::string path_, prefix_;
  std::vector<std::string> known_;
};

template <int Dim>
levelset::Function<Dim> cylinder(const Vec<Dim>& centre, double radius, int axis, double half_length) {
  return [=](const Vec<Dim>& x) {
    Vec<Dim> r = x - centre;
    const double along = std::abs(r[axis]);
    r[axis] = 0.0;
    return std::max(r.norm() - radius, along - half_length);
  };
}

/// One shape of [[fluid]], [[solid]] or [[source]]: its level set and bounding box.
template <int Dim>
struct Shape {
  levelset::Function<Dim> phi;
  Box<Dim> bounds;
  std::string op;
};

const std::vector<std::string> shape_keys = {"shape", "op", "lo", "hi", "centre", "radius", "axis", "length"};

template <int Dim>
Shape<Dim> read_shape(const TableReader& r, bool with_op) {
  Shape<Dim> s;
  s.op = with_op ? r.choice("op", {"add", "subtract", "intersect"}, std::string("add")) : "add";
  const std::vector<std::string> kinds = Dim == 3 ? std::vector<std::string>{"box", "sphere", "cylinder"}
                                                  : std::vector<std::string>{"box", "sphere"};
  const std::string kind = r.choice("shape", kinds);
  const auto refuse = [&](const char* key) {
    LIQUID_VERIFY(!r.has(key), "{}: a {} has no '{}'", r.where(key), kind, key);
  };
  if (kind == "box") {
    for (const char* k : {"centre", "radius", "axis", "length"}) refuse(k);
    s.bounds = {r.vec<Dim>("lo"), r.vec<Dim>("hi")};
    for (int d = 0; d < Dim; ++d)
      LIQUID_VERIFY(s.bounds.lo[d] < s.bounds.hi[d],
                    "{}: hi must exceed lo on every axis (axis {}: {} <= {})", r.where("hi"), d,
                    s.bounds.hi[d], s.bounds.lo[d]);
    s.phi = levelset::box<Dim>(s.bounds);
  } else if (kind == "sphere") {
    for (const char* k : {"lo", "hi", "axis", "length"}) refuse(k);
    const Vec<Dim> c = r.vec<Dim>("centre");
    const double radius = r.positive("radius");
    s.bounds = {c.array() - radius, c.array() + radius};
    s.phi = levelset::sphere<Dim>(c, radius);
  } else {
    for (const char* k : {"lo", "hi"}) refuse(k);
    const Vec<Dim> c = r.vec<Dim>("centre");
    const double radius = r.positive("radius");
    const std::string axis = r.choice("axis", {"x", "y", "z"});
    const int a = axis[0] - 'x';
    const double half = 0.5 * r.positive("length", std::numeric_limits<double>::infinity());
    s.bounds = {c.array() - radius, c.array() + radius};
    s.bounds.lo[a] = c[a] - half, s.bounds.hi[a] = c[a] + half;
    s.phi = cylinder<Dim>(c, radius, a, half);
  }
  return s;
}

template <int Dim>
levelset::Function<Dim> combine(levelset::Function<Dim> so_far, const Shape<Dim>& s) {
  if (!so_far) return s.phi;
  if (s.op == "subtract") return levelset::subtract<Dim>(so_far, s.phi);
  if (s.op == "intersect") return levelset::intersect<Dim>(so_far, s.phi);
  return levelset::unite<Dim>(so_far, s.phi);
}

template <int Dim>
bool inside(const Box<Dim>& inner, const Box<Dim>& outer) {
  const double tol = 1e-12 * outer.size().maxCoeff();
  return (inner.lo.array() >= outer.lo.array() - tol).all() &&
         (inner.hi.array() <= outer.hi.array() + tol).all();
}

template <int Dim>
std::string format_box(const Box<Dim>& b) {
  return fmt::format("[{}] to [{}]", fmt::join(b.lo.data(), b.lo.data() + Dim, ", "),
                     fmt::join(b.hi.data(), b.hi.data() + Dim, ", "));
}

const std::vector<std::string> sph_keys = {"spacing",
                                           "levels",
                                           "resample_every",
                                           "resample_travel",
                                           "merge_min_passes",
                                           "serial_below",
                                           "alpha",
                                           "beta",
                                           "kernel",
                                           "pressure",
                                           "density",
                                           "density_diffusion",
                                           "rest_density",
                                           "sound_speed",
                                           "viscosity",
                                           "search",
                                           "surface",
                                           "settle",
                                           "gate_lo",
                                           "gate_hi",
                                           "restitution",
                                           "seed",
                                           "turn_angle",
                                           "turn_duration",
                                           "turn_pivot",
                                           "turn_axis",
                                           "view_eye",
                                           "view_target",
                                           "view_angle",
                                           "neighbour_skin",
                                           "wall_footpoints",
                                           "march",
                                           "mirror_walls",
                                           "kicked_density_rate",
                                           "mean_radius_gradient",
                                           "free_particles_at_rest",
                                           "shifting"};

/// The value of `choices` whose name (to_string) is `name`.
template <class E>
E by_name(const std::string& name, std::initializer_list<E> choices) {
  for (E e : choices)
    if (name == sph::to_string(e)) return e;
  return *choices.begin();
}

template <class E>
std::vector<std::string> names_of(std::initializer_list<E> choices) {
  std::vector<std::string> out;
  for (E e : choices) out.emplace_back(sph::to_string(e));
  return out;
}

template <int Dim>
void read_sph(const TableReader& r, Scene<Dim>& s) {
  SphScene<Dim>& sc = s.sph_scene;
  sph::SphOptions<Dim>& o = sc.options;
  sc.spacing_given = r.has("spacing");
  if (sc.spacing_given) {
    o.spacing = r.positive("spacing");
    sc.spacing_where = r.where("spacing");
  }
  o.max_level = static_cast<int>(r.integer_in("levels", 0, 12, o.max_level));
  o.resample_every = static_cast<int>(r.integer_in("resample_every", 1, 100000, o.resample_every));
  o.resample_travel = r.number("resample_travel", o.resample_travel);
  LIQUID_VERIFY(std::isfinite(o.resample_travel) && o.resample_travel >= 0.0 && o.resample_travel <= 100.0,
                "{}: {} is outside [0, 100] (level-0 spacings; 0: every resample_every-th step)",
                r.where("resample_travel"), o.resample_travel);
  o.merge_min_passes = static_cast<int>(r.integer_in("merge_min_passes", 0, 1000, o.merge_min_passes));
  o.serial_below = static_cast<int>(r.integer_in("serial_below", 0, 100'000'000, o.serial_below));
  o.resampling.alpha = r.positive("alpha", o.resampling.alpha);
  o.resampling.beta = r.positive("beta", o.resampling.beta);
  LIQUID_VERIFY(o.resampling.alpha < o.resampling.beta, "{}: alpha {} must be below beta {}", r.where("beta"),
                o.resampling.alpha, o.resampling.beta);
  using K = sph::KernelSet;
  using P = sph::PressureForm;
  using D = sph::DensityUpdate;
  using N = sph::NeighbourSearch;
  using S = sph::SurfaceModel;
  const auto kernels = {K::wendland, K::spiky, K::mueller};
  const auto forms = {P::paper, P::variational};
  const auto updates = {D::continuity, D::summation};
  const auto searches = {N::automatic, N::cell_list, N::kd_tree};
  const auto surfaces = {S::distance, S::zhu_bridson, S::blobby};
  o.fluid.kernels = by_name(r.choice("kernel", names_of(kernels), sph::to_string(o.fluid.kernels)), kernels);
  o.fluid.pressure_form =
      by_name(r.choice("pressure", names_of(forms), sph::to_string(o.fluid.pressure_form)), forms);
  o.fluid.density_update =
      by_name(r.choice("density", names_of(updates), sph::to_string(o.fluid.density_update)), updates);
  o.fluid.density_diffusion = r.number("density_diffusion", o.fluid.density_diffusion);
  LIQUID_VERIFY(o.fluid.density_diffusion >= 0.0 && o.fluid.density_diffusion <= 1.0,
                "{}: {} is outside [0, 1]", r.where("density_diffusion"), o.fluid.density_diffusion);
  o.neighbour_skin = r.number("neighbour_skin", o.neighbour_skin);
  LIQUID_VERIFY(o.neighbour_skin >= 0.0 && o.neighbour_skin <= 10.0, "{}: {} is outside [0, 10] spacings",
                r.where("neighbour_skin"), o.neighbour_skin);
  o.wall_footpoints = r.boolean("wall_footpoints", o.wall_footpoints);
  o.march = r.choice("march", {"parallel", "queue"},
                     o.march == sph::MarchOrder::parallel ? "parallel" : "queue") == "parallel"
                ? sph::MarchOrder::parallel
                : sph::MarchOrder::serial;
  o.fluid.mirror_walls = r.boolean("mirror_walls", o.fluid.mirror_walls);
  o.fluid.kicked_density_rate = r.boolean("kicked_density_rate", o.fluid.kicked_density_rate);
  o.fluid.mean_radius_gradient = r.boolean("mean_radius_gradient", o.fluid.mean_radius_gradient);
  o.fluid.free_particles_at_rest = r.boolean("free_particles_at_rest", o.fluid.free_particles_at_rest);
  o.fluid.shifting = r.number("shifting", o.fluid.shifting);
  LIQUID_VERIFY(o.fluid.shifting >= 0.0 && o.fluid.shifting <= 0.1, "{}: {} is outside [0, 0.1]",
                r.where("shifting"), o.fluid.shifting);
  o.fluid.rest_density = r.positive("rest_density", o.fluid.rest_density);
  if (r.has("sound_speed")) sc.sound_speed = r.positive("sound_speed");
  o.fluid.viscosity = r.number("viscosity", o.fluid.viscosity);
  LIQUID_VERIFY(o.fluid.viscosity >= 0.0, "{}: must not be negative (found {})", r.where("viscosity"),
                o.fluid.viscosity);
  o.search = by_name(r.choice("search", names_of(searches), sph::to_string(o.search)), searches);
  sc.surface = by_name(r.choice("surface", names_of(surfaces), sph::to_string(sc.surface)), surfaces);
  sc.settle = r.number("settle", 0.0);
  LIQUID_VERIFY(sc.settle >= 0.0, "{}: must not be negative (found {})", r.where("settle"), sc.settle);
  LIQUID_VERIFY(r.has("gate_lo") == r.has("gate_hi"), "{}: give both gate_lo and gate_hi, or neither",
                r.where(r.has("gate_lo") ? "gate_lo" : "gate_hi"));
  if (r.has("gate_lo")) {
    sc.gate = true;
    sc.gate_box = {r.vec<Dim>("gate_lo"), r.vec<Dim>("gate_hi")};
    for (int d = 0; d < Dim; ++d)
      LIQUID_VERIFY(sc.gate_box.lo[d] < sc.gate_box.hi[d], "{}: hi must exceed lo on every axis (axis {})",
                    r.where("gate_hi"), d);
    LIQUID_VERIFY(inside<Dim>(sc.gate_box, s.domain), "{}: the gate {} reaches outside the domain {}",
                  r.where("gate_lo"), format_box<Dim>(sc.gate_box), format_box<Dim>(s.domain));
    LIQUID_VERIFY(sc.settle > 0.0, "{}: a gate holds the liquid while it settles: give sph.settle > 0",
                  r.where("gate_lo"));
  }
  o.restitution = r.number("restitution", o.restitution);
  LIQUID_VERIFY(o.restitution >= 0.0 && o.restitution <= 1.0, "{}: {} is outside [0, 1]",
                r.where("restitution"), o.restitution);
  o.seed = static_cast<std::uint64_t>(r.integer_in("seed", 0, std::numeric_limits<long>::max(), 1));
  const double angle = r.number("turn_angle", 0.0);
  LIQUID_VERIFY(std::abs(angle) <= 3600.0, "{}: {} degrees is more than ten turns", r.where("turn_angle"),
                angle);
  o.rotation.angle = angle * std::numbers::pi / 180.0;
  if (!o.rotation.active())
    for (const char* key : {"turn_duration", "turn_pivot", "turn_axis"})
      LIQUID_VERIFY(!r.has(key), "{}: the container does not turn without sph.turn_angle", r.where(key));
  o.rotation.duration = r.positive("turn_duration", 1.0);
  o.rotation.pivot = r.vec<Dim>("turn_pivot", s.domain.centre());
  if (r.has("view_eye") || r.has("view_target") || r.has("view_angle")) {
    for (const char* key : {"view_eye", "view_target", "view_angle"})
      LIQUID_VERIFY(r.has(key), "{}: the view needs view_eye, view_target and view_angle; '{}' is missing",
                    r.where_table(), key);
    o.view.eye = r.vec<Dim>("view_eye");
    o.view.target = r.vec<Dim>("view_target");
    const double view_angle = r.number("view_angle");
    LIQUID_VERIFY(view_angle > 0.0 && view_angle < 90.0, "{}: the half-angle {} is outside (0, 90) degrees",
                  r.where("view_angle"), view_angle);
    LIQUID_VERIFY((o.view.target - o.view.eye).norm() > 0.0, "{}: the target is the eye",
                  r.where("view_target"));
    o.view.half_angle = view_angle * std::numbers::pi / 180.0;
  }
  if (r.has("turn_axis")) {
    LIQUID_VERIFY(Dim == 3, "{}: a 2D container turns about z; turn_axis is for 3D scenes",
                  r.where("turn_axis"));
    const Vec<Dim> axis = r.vec<Dim>("turn_axis");
    LIQUID_VERIFY(axis.norm() > 0.0, "{}: the axis must not be zero", r.where("turn_axis"));
    for (int d = 0; d < Dim; ++d) o.rotation.axis[d] = axis[d] / axis.norm();
  }
}

}  // namespace

std::string field_not_written(const std::vector<std::string>& fields, bool sph) {
  const std::vector<std::string> ok = sph ? SceneOutput::sph_fields() : SceneOutput::pic_fields();
  for (const std::string& f : fields)
    if (std::find(ok.begin(), ok.end(), f) == ok.end()) return f;
  return "";
}

template <int Dim>
double sph_sound_speed(const Scene<Dim>& scene) {
  if (scene.sph_scene.sound_speed > 0.0) return scene.sph_scene.sound_speed;
  // The fastest speed the scene can reach: its fastest initial or inflow speed, plus a fall from the
  // top of the liquid or of a source to the bottom of the domain (in a turning container, across its
  // diagonal).
  double start = scene.max_initial_speed;
  for (const SceneSource<Dim>& src : scene.sources) start = std::max(start, src.velocity.norm());
  const Vec<Dim>& g = scene.gravity;
  double fall = 0.0;
  if (scene.sph_scene.options.rotation.active()) {
    fall = scene.domain.size().norm();
  } else if (g.norm() > 0.0) {
    const Vec<Dim> up = -g / g.norm();
    const auto lowest = [&](const Box<Dim>& b) {
      return up.dot(b.centre()) - 0.5 * up.cwiseAbs().dot(b.size());
    };
    const auto highest = [&](const Box<Dim>& b) {
      return up.dot(b.centre()) + 0.5 * up.cwiseAbs().dot(b.size());
    };
    double top = highest(scene.liquid_bounds);
    for (const SceneSource<Dim>& src : scene.sources) top = std::max(top, highest(src.bounds));
    fall = std::max(0.0, top - lowest(scene.domain));
  }
  const double fastest = std::sqrt(start * start + 2.0 * g.norm() * fall);
  LIQUID_VERIFY(fastest > 0.0,
                "{}: nothing in the scene moves (no gravity, no initial velocity, no inflow): give "
                "sph.sound_speed",
                scene.path);
  return 10.0 * fastest;
}

template <int Dim>
sph::SphOptions<Dim> sph_options(const Scene<Dim>& scene) {
  sph::SphOptions<Dim> o = scene.sph_scene.options;
  o.container = scene.domain;
  o.obstacles.clear();
  if (scene.solid) o.obstacles.push_back(scene.solid);
  o.gravity = scene.gravity;
  o.adaptive = scene.adaptive;
  const double shortest = scene.domain.size().minCoeff();
  if (!scene.sph_scene.spacing_given) {
    LIQUID_VERIFY(scene.grid_given,
                  "{}: missing key 'sph.spacing': the SPH particles need a spacing (or a [grid] whose finest "
                  "cell, halved, sets it)",
                  scene.path);
    o.spacing = 0.5 * std::ldexp(shortest, -scene.pic.finest_level);  // [grid] finest, as a PIC run's
  }
  const std::string from = scene.sph_scene.spacing_where.empty()
                               ? fmt::format("{}: the spacing from [grid] finest", scene.path)
                               : scene.sph_scene.spacing_where;
  LIQUID_VERIFY(o.spacing < shortest,
                "{}: spacing {} is not below the domain's shortest side {}: no particle fits", from,
                o.spacing, shortest);
  const double particles = scene.liquid_bounds.volume() / std::pow(o.spacing, Dim);
  constexpr double budget = 5e7;
  LIQUID_VERIFY(particles <= budget,
                "{}: the liquid at spacing {} would take about {:.3g} particles, over the budget of "
                "{:.0g}: a larger spacing (or a coarser [grid] finest) runs",
                from, o.spacing, particles, budget);
  const double c = sph_sound_speed(scene);
  o.fluid.stiffness = o.fluid.rest_density * c * c;
  o.sources.clear();
  for (const SceneSource<Dim>& src : scene.sources)
    o.sources.push_back({src.region, src.bounds, src.velocity, src.start, src.stop});
  try {
    o.check();
  } catch (const Error& e) {
    throw Error(fmt::format("{}: [sph]: {}", scene.path, e.what()));
  }
  return o;
}

int scene_dimension(const std::string& path) {
  const toml::table doc = parse(path);
  const toml::table* domain = doc["domain"].as_table();
  LIQUID_VERIFY(domain != nullptr, "{}: missing table [domain]", path);
  const toml::array* lo = (*domain)["lo"].as_array();
  LIQUID_VERIFY(lo != nullptr, "{}:{}: missing key 'domain.lo' (an array of 2 or 3 numbers)", path,
                domain->source().begin.line);
  LIQUID_VERIFY(lo->size() == 2 || lo->size() == 3,
                "{}:{}: key 'domain.lo' has {} entries; a scene is 2D or 3D", path, lo->source().begin.line,
                lo->size());
  return static_cast<int>(lo->size());
}

namespace {

template <int Dim>
const toml::table& table_or_empty(const TableReader& top, const char* name) {
  static const toml::table empty;
  const toml::table* t = top.table(name);
  return t ? *t : empty;
}

template <int Dim>
void read_domain(const TableReader& top, Scene<Dim>& s) {
  const toml::table* domain = top.table("domain");
  LIQUID_VERIFY(domain != nullptr, "{}: missing table [domain] (lo and hi)", s.path);
  const TableReader r(*domain, s.path, "domain", {"lo", "hi"});
  LIQUID_VERIFY(r.has("lo"), "{}: missing key 'domain.lo'", r.where_table());
  const int found = static_cast<int>((*domain)["lo"].as_array() ? (*domain)["lo"].as_array()->size() : 0);
  LIQUID_VERIFY(found == Dim, "{}: a {}D scene was expected, domain.lo has {} entries", r.where("lo"), Dim,
                found);
  s.domain = {r.vec<Dim>("lo"), r.vec<Dim>("hi")};
  for (int d = 0; d < Dim; ++d)
    LIQUID_VERIFY(s.domain.lo[d] < s.domain.hi[d], "{}: hi must exceed lo on every axis (axis {})",
                  r.where("hi"), d);
}

const std::vector<std::string> solver_keys = {"method",
                                              "adaptive",
                                              "flip",
                                              "integrator",
                                              "reseed",
                                              "refill_emptied",
                                              "reseed_mode",
                                              "reseed_max",
                                              "gravity",
                                              "extrapolation",
                                              "advect_cfl",
                                              "surface",
                                              "surface_radius",
                                              "projection",
                                              "min_face_mass",
                                              "share_factors",
                                              "condition_estimate",
                                              "nullspace",
                                              "transfer_exponent",
                                              "transfer_degree",
                                              "ppe_degree",
                                              "ppe_rows",
                                              "ppe_gradient_cap",
                                              "patch_transfer",
                                              "level_change_p2g",
                                              "level_change_tent_share",
                                              "affine_outside_patches",
                                              "preset"};

/// The [solver] keys every method reads: the method, the adaptivity and gravity.
template <int Dim>
void read_method(const TableReader& r, Scene<Dim>& s) {
  const std::string method = r.choice("method", {"rbf", "pic", "flip", "apic", "sph"}, std::string("rbf"));
  s.sph = method == "sph";
  s.pic.transfer = pic::parse_pic_transfer(s.sph ? "rbf" : method);
  s.adaptive = r.boolean("adaptive", s.pic.transfer == pic::PicTransfer::rbf);
  LIQUID_VERIFY(
      s.sph || !s.adaptive || s.pic.transfer == pic::PicTransfer::rbf,
      "{}: method '{}' runs on a uniform grid: set solver.adaptive = false (adaptive trees use rbf)",
      r.where("adaptive"), to_string(s.pic.transfer));
  s.gravity = r.vec<Dim>("gravity", pic::PicOptions<Dim>::default_gravity());
}

/// The PIC solver's [solver] keys: transfers, reseeding, surface, projection, the closed box's PPE.
template <int Dim>
void read_pic_solver(const TableReader& r, Scene<Dim>& s) {
  pic::PicOptions<Dim>& o = s.pic;
  o.flip = r.number("flip", 0.95);
  LIQUID_VERIFY(o.flip >= 0.0 && o.flip <= 1.0, "{}: {} is outside [0, 1]", r.where("flip"), o.flip);
  o.integrator = r.choice("integrator", {"rk2", "rk3"}, std::string("rk2")) == "rk2"
                     ? particles::Integrator::rk2
                     : particles::Integrator::rk3;
  o.reseed = r.boolean("reseed", true);
  // The paper's preset first: the keys below override what it sets.
  s.paper_preset = r.choice("preset", {"default", "paper"}, std::string("default")) == "paper";
  if (s.paper_preset) o.apply_paper_preset();
  o.refill_emptied = r.boolean("refill_emptied", o.refill_emptied);
  if (r.has("reseed_mode")) {
    const std::string reseed_mode = r.choice("reseed_mode", {"replace", "keep", "holes", "top-up"});
    o.reseeding.keep = reseed_mode == "keep" || reseed_mode == "top-up";
    if (reseed_mode == "holes") {  // only cells the step left empty inside the liquid
      o.reseeding.lo = 1;
      o.reseeding.hi = std::numeric_limits<int>::max();
    } else if (reseed_mode == "top-up") {  // sparse cells get new particles; crowded ones are left
      o.reseeding.lo = Dim == 2 ? 3 : 5;
      o.reseeding.hi = std::numeric_limits<int>::max();
    } else {  // the paper's band: cells with too few or too many particles
      o.reseeding.lo = Dim == 2 ? 3 : 5;
      o.reseeding.hi = Dim == 2 ? 12 : 15;
    }
  }
  // The most particles a cell keeps before reseeding thins it (keep, top-up) or replaces them
  // (replace, holes); 0: never. Without reseed_mode, the method's own mode takes it: top-up with rbf.
  if (r.has("reseed_max")) {
    constexpr long per_cell = 1L << Dim;  // a reseeded cell holds 2^Dim particles
    const long most = r.integer("reseed_max");
    LIQUID_VERIFY(most == 0 || (most >= per_cell && most <= 1'000'000),
                  "{}: {} is neither 0 (never thin) nor in [{}, 1000000] (a reseeded cell holds {})",
                  r.where("reseed_max"), most, per_cell, per_cell);
    if (o.reseeding.lo == 0) {  // no reseed_mode, no preset: the method's default range
      o.reseeding.lo = Dim == 2 ? 3 : 5;
      o.reseeding.keep = o.transfer == pic::PicTransfer::rbf;
    }
    o.reseeding.hi = most == 0 ? std::numeric_limits<int>::max() : static_cast<int>(most);
  }
  o.rbf.exponent = static_cast<int>(r.integer_in("transfer_exponent", 1, 9, o.rbf.exponent));
  LIQUID_VERIFY(o.rbf.exponent % 2 == 1, "{}: the PHS exponent must be odd (1, 3, 5, 7 or 9), got {}",
                r.where("transfer_exponent"), o.rbf.exponent);
  o.rbf.degree = static_cast<int>(r.integer_in("transfer_degree", 0, 4, o.rbf.degree));
  // The RBF-FD rows' and face gradients' polynomial degree at T-junctions (the PPE and projection).
  // Degree 2 is the least that reproduces quadratics, which a consistent Laplacian row needs.
  if (r.has("ppe_degree"))
    o.poisson.rbf.degree = o.poisson.gradient_degree = static_cast<int>(r.integer_in("ppe_degree", 2, 4));
  // The rows at T-junctions: the paper's RBF-FD Laplacian, or the flux sum of the projection's own
  // face gradients (the PPE then is exactly D G).
  if (r.has("ppe_rows"))
    o.poisson.irregular = mac::parse_irregular_rows(r.choice("ppe_rows", {"laplacian", "flux"}));
  // The projection's RBF-FD face gradients keep at most this times their stencil size of the whole
  // rings (0: whole rings; the default caps 3D at 2, 2D not at all).
  if (r.has("ppe_gradient_cap")) {
    o.poisson.gradient_ring_cap = r.number("ppe_gradient_cap");
    LIQUID_VERIFY(o.poisson.gradient_ring_cap == 0.0 ||
                      (o.poisson.gradient_ring_cap >= 1.0 && o.poisson.gradient_ring_cap <= 8.0),
                  "{}: {} is neither 0 (whole rings) nor in [1, 8] (times the stencil size)",
                  r.where("ppe_gradient_cap"), o.poisson.gradient_ring_cap);
  }
  if (r.has("patch_transfer")) o.uniform_patches = r.choice("patch_transfer", {"apic", "rbf"}) == "apic";
  o.tent_at_level_changes = r.choice("level_change_p2g", {"rbf", "tent"}, std::string("rbf")) == "tent";
  LIQUID_VERIFY(!o.tent_at_level_changes || o.uniform_patches,
                "{}: the tent transfer at level changes goes with patch_transfer = \"apic\"",
                r.where("level_change_p2g"));
  if (o.tent_at_level_changes) o.rbf_gradient_affine = false;  // together they blow up a 2D pool
  if (r.has("level_change_tent_share")) {
    o.level_change_tent_share = r.number("level_change_tent_share");
    LIQUID_VERIFY(o.level_change_tent_share >= 0.0 && o.level_change_tent_share <= 1.0,
                  "{}: {} is outside [0, 1]", r.where("level_change_tent_share"), o.level_change_tent_share);
    LIQUID_VERIFY(o.uniform_patches && !o.tent_at_level_changes,
                  "{}: the tents' share blends into the RBF particle -> face at level changes, which needs "
                  "patch_transfer = \"apic\" and level_change_p2g = \"rbf\"",
                  r.where("level_change_tent_share"));
  }
  if (r.has("affine_outside_patches")) {
    o.rbf_gradient_affine = r.choice("affine_outside_patches", {"zero", "rbf-gradient"}) == "rbf-gradient";
    LIQUID_VERIFY(o.uniform_patches,
                  "{}: the particles' affine part outside the patches goes with patch_transfer = \"apic\"",
                  r.where("affine_outside_patches"));
    LIQUID_VERIFY(!(o.rbf_gradient_affine && o.tent_at_level_changes),
                  "{}: \"rbf-gradient\" with level_change_p2g = \"tent\" is unstable (a 2D still pool blew "
                  "up); use \"zero\" with the tents",
                  r.where("affine_outside_patches"));
  }
  o.rbf.share_factors = r.boolean("share_factors", true);
  o.rbf.condition_estimate =
      r.choice("condition_estimate", {"probes", "hager-higham"}, std::string("probes")) == "probes"
          ? rbf::ConditionEstimate::probes
          : rbf::ConditionEstimate::hager_higham;
  o.poisson.nullspace = r.choice("nullspace", {"zero-mean", "pin"}, std::string("zero-mean")) == "pin"
                            ? mac::Nullspace::pin
                            : mac::Nullspace::zero_mean;
  o.extrapolation_layers = static_cast<int>(r.integer_in("extrapolation", 1, 64, 4));
  o.advect_cfl = r.positive("advect_cfl", 1.0);
  o.surface = pic::parse_pic_surface(r.choice("surface", {"air", "levelset"}, std::string("air")));
  LIQUID_VERIFY(o.surface != pic::PicSurface::levelset || o.poisson.irregular != mac::IrregularRows::flux,
                "{}: flux rows go with surface = \"air\" (with the level-set surface their ghost-fluid faces "
                "at level changes cost 10-65x the accuracy; docs/findings/transfer-stability.md)",
                r.where("ppe_rows"));
  o.surface_radius = r.positive("surface_radius", o.surface_radius);
  LIQUID_VERIFY(o.surface_radius < 2.0, "{}: {} finest cells is too wide (below 2)",
                r.where("surface_radius"), o.surface_radius);
  o.projection =
      pic::parse_pic_projection(r.choice("projection", {"volume", "mass", "split"}, std::string("volume")));
  LIQUID_VERIFY(o.projection == pic::PicProjection::volume || s.sph || o.transfer != pic::PicTransfer::rbf,
                "{}: the {} projection needs method pic, flip or apic (a uniform grid)",
                r.where("projection"), to_string(o.projection));
  o.min_face_mass = r.positive("min_face_mass", o.min_face_mass);
  LIQUID_VERIFY(o.min_face_mass <= 1.0, "{}: {} is above 1 (a full cell's mass)", r.where("min_face_mass"),
                o.min_face_mass);
}

/// [grid]: the PIC tree's levels (an SPH scene may give one: its finest cell sets the spacing).
template <int Dim>
void read_grid(const TableReader& top, Scene<Dim>& s) {
  if (!top.has("grid") && s.sph) return;
  pic::PicOptions<Dim>& o = s.pic;
  const toml::table* t = top.table("grid");
  LIQUID_VERIFY(t != nullptr, "{}: missing table [grid] (at least 'finest')", s.path);
  s.grid_given = true;
  const TableReader r(*t, s.path, "grid", {"finest", "coarse", "max_jump", "band"});
  o.finest_level = static_cast<int>(r.integer_in("finest", 1, morton::max_level<Dim>));
  o.coarse_level =
      static_cast<int>(r.integer_in("coarse", 0, o.finest_level, std::max(0, o.finest_level - 3)));
  if (r.has("max_jump") && (*t)["max_jump"].is_string()) {
    r.choice("max_jump", {"unlimited"});
    o.max_jump = tree::unlimited_jump;
  } else {
    o.max_jump = static_cast<int>(r.integer_in("max_jump", 1, 4, 2));
  }
  o.band = static_cast<int>(r.integer_in("band", 0, 16, 2));
}

/// [time]: the end, the step's bounds.
template <int Dim>
void read_time(const TableReader& top, Scene<Dim>& s) {
  const std::string& path = s.path;
  const toml::table* t = top.table("time");
  LIQUID_VERIFY(t != nullptr, "{}: missing table [time] (end or steps)", path);
  const TableReader r(*t, path, "time", {"end", "steps", "cfl", "dt_min", "dt_max"});
  LIQUID_VERIFY(r.has("end") || r.has("steps"), "{}: give 'time.end' (seconds) or 'time.steps'",
                r.where_table());
  if (r.has("end")) s.time.end = r.positive("end");
  if (r.has("steps")) s.time.steps = r.integer_in("steps", 1, kMaxSteps);
  // SPH's step is bounded by the speed of sound (AdaptiveSph::stable_dt): a lower bound on dt would
  // override it, so its default is far below any stable step.
  s.time.cfl = r.positive("cfl", s.sph ? 0.25 : 1.0);
  s.time.dt_max = r.positive("dt_max", s.sph ? 1e-3 : 0.01);
  s.time.dt_min = r.positive("dt_min", std::min(s.sph ? 1e-9 : 1e-5, s.time.dt_max));
  LIQUID_VERIFY(s.time.dt_min <= s.time.dt_max, "{}: dt_min {} exceeds dt_max {}", r.where("dt_min"),
                s.time.dt_min, s.time.dt_max);
  if (r.has("end"))
    LIQUID_VERIFY(std::isfinite(s.time.end) && s.time.end / s.time.dt_max <= static_cast<double>(kMaxSteps),
                  "{}: {} s needs at least {:.3g} steps of dt_max = {} s, more than a run may take ({}); "
                  "shorten it or raise time.dt_max",
                  r.where("end"), s.time.end, s.time.end / s.time.dt_max, s.time.dt_max, kMaxSteps);
}

/// A scene's name is a file stem: it names the output files, inside the output folder.
bool is_file_stem(const std::string& name) {
  if (name.empty() || name.size() > 200 || name.front() == '.' || name.front() == '-') return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.' || c == '+';
  });
}

/// The default name: the scene file's stem, with every character a stem may not hold replaced by '_'.
std::string stem_of(const std::string& path) {
  std::string stem = std::filesystem::path(path).stem().string();
  for (char& c : stem)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.' || c == '+'))
      c = '_';
  while (!stem.empty() && (stem.front() == '.' || stem.front() == '-')) stem.erase(stem.begin());
  return stem.empty() ? std::string("scene") : stem;
}

/// [ppe]: the PIC solver's pressure solve.
template <int Dim>
void read_ppe(const TableReader& top, Scene<Dim>& s) {
  const std::string& path = s.path;
  static const toml::table empty;
  pic::PicOptions<Dim>& o = s.pic;
  const toml::table* t = top.table("ppe");
  const TableReader r(
      t ? *t : empty, path, "ppe",
      {"solver", "tolerance", "max_iterations", "continue_on_failure", "amg_reuse", "fallback"});
  const std::vector<std::string> names = linalg::solver_names();
  s.ppe_solver_given = r.has("solver");
  o.solver.kind = s.ppe_solver_given ? linalg::parse_solver(r.choice("solver", names))
                                     : default_ppe_solver(s.adaptive, Dim);
  o.solver.tolerance = r.positive("tolerance", o.solver.tolerance);
  LIQUID_VERIFY(o.solver.tolerance < 1.0, "{}: a relative tolerance must be below 1 (found {})",
                r.where("tolerance"), o.solver.tolerance);
  o.solver.max_iterations =
      static_cast<int>(r.integer_in("max_iterations", 1, 10000000, o.solver.max_iterations));
  o.continue_on_ppe_failure = r.boolean("continue_on_failure", false);
  o.ppe_fallback = r.boolean("fallback", o.ppe_fallback);
  o.solver.amg.reuse_factor = r.number("amg_reuse", o.solver.amg.reuse_factor);
  LIQUID_VERIFY(o.solver.amg.reuse_factor >= 0.0,
                "{}: must be 0 (a new AMG hierarchy every step) or positive (found {})", r.where("amg_reuse"),
                o.solver.amg.reuse_factor);
}

/// [output]: what the frames hold.
template <int Dim>
void read_output(const TableReader& top, Scene<Dim>& s) {
  const std::string& path = s.path;
  static const toml::table empty;
  const toml::table* t = top.table("output");
  const TableReader r(t ? *t : empty, path, "output", {"every", "cells", "particles", "surface", "fields"});
  s.output.every = r.has("every") ? r.positive("every") : 0.0;
  s.output.cells = r.boolean("cells", true);
  s.output.particles = r.boolean("particles", true);
  s.output.surface = r.boolean("surface", true);
  s.output.fields_given = r.has("fields");
  std::vector<std::string> all = SceneOutput::pic_fields();
  for (const std::string& f : SceneOutput::sph_fields())
    if (std::find(all.begin(), all.end(), f) == all.end()) all.push_back(f);
  s.output.fields = r.strings("fields", all, s.sph ? SceneOutput::sph_fields() : SceneOutput::pic_fields());
  if (s.output.fields_given) {
    const std::string wrong = field_not_written(s.output.fields, s.sph);
    LIQUID_VERIFY(wrong.empty(), "{}: '{}' is not a field of {} (its fields: {})", r.where("fields"), wrong,
                  s.sph ? "the SPH particles" : "the PIC cells and particles",
                  fmt::join(s.sph ? SceneOutput::sph_fields() : SceneOutput::pic_fields(), ", "));
  }
}

/// [[fluid]], [[solid]] and [[source]]: the liquid, the obstacles and the inflows.
/// A fluid's initial velocity given as Dim expressions in x, y (, z): the field, and its largest
/// speed over a 17^Dim lattice of the shape's bounding box (inside the shape), where every value
/// must be finite.
template <int Dim>
std::pair<std::function<Vec<Dim>(const Vec<Dim>&)>, double> velocity_expressions(const TableReader& r,
                                                                                 const toml::array& a,
                                                                                 const Shape<Dim>& shape) {
  LIQUID_VERIFY(static_cast<int>(a.size()) == Dim, "{}: expected {} expressions (the scene is {}D), found {}",
                r.where("velocity"), Dim, Dim, a.size());
  std::array<std::shared_ptr<const Expression<Dim>>, Dim> e;
  for (int d = 0; d < Dim; ++d) {
    LIQUID_VERIFY(a.get(d)->is_string(),
                  "{}: entry {} is not a string: give every component as a number or every one as an "
                  "expression in x, y{}",
                  r.where("velocity"), d + 1, Dim == 3 ? ", z" : "");
    e[d] = std::make_shared<const Expression<Dim>>(a.get(d)->as_string()->get(),
                                                   fmt::format("{}, entry {}", r.where("velocity"), d + 1));
  }
  const auto field = [e](const Vec<Dim>& x) {
    Vec<Dim> v;
    for (int d = 0; d < Dim; ++d) v[d] = (*e[d])(x);
    return v;
  };
  constexpr int n = 16;
  double speed = 0.0;
  const Vec<Dim> size = shape.bounds.size();
  const long points = static_cast<long>(std::pow(n + 1, Dim));
  for (long i = 0; i < points; ++i) {
    Vec<Dim> x;
    long rest = i;
    for (int d = 0; d < Dim; ++d, rest /= n + 1)
      x[d] = shape.bounds.lo[d] + size[d] * double(rest % (n + 1)) / n;
    if (shape.phi(x) > 0.0) continue;
    const Vec<Dim> v = field(x);
    LIQUID_VERIFY(v.allFinite(), "{}: the velocity at ({:.6g}) is not finite ({:.6g})", r.where("velocity"),
                  fmt::join(x.data(), x.data() + Dim, ", "), fmt::join(v.data(), v.data() + Dim, ", "));
    speed = std::max(speed, v.norm());
  }
  return {field, speed};
}

template <int Dim>
void read_shapes(const TableReader& top, Scene<Dim>& s) {
  const std::string& path = s.path;
  const auto fluids = top.tables("fluid");
  LIQUID_VERIFY(!fluids.empty(), "{}: missing table [[fluid]]: the scene holds no liquid", path);
  s.fluid_where = fmt::format("{}:{}: [[fluid]]", path, fluids.front()->source().begin.line);
  std::vector<std::pair<levelset::Function<Dim>, std::function<Vec<Dim>(const Vec<Dim>&)>>> moving;
  for (const toml::table* t : fluids) {
    std::vector<std::string> keys = shape_keys;
    keys.push_back("velocity");
    const TableReader r(*t, path, "fluid", keys);
    const Shape<Dim> shape = read_shape<Dim>(r, true);
    LIQUID_VERIFY(s.liquid || shape.op == "add", "{}: the first [[fluid]] shape must add liquid",
                  r.where("op"));
    if (shape.op == "add")
      LIQUID_VERIFY(inside<Dim>(shape.bounds, s.domain), "{}: the fluid {} reaches outside the domain {}",
                    r.where("shape"), format_box<Dim>(shape.bounds), format_box<Dim>(s.domain));
    if (shape.op == "add") {
      if (!s.liquid) s.liquid_bounds = shape.bounds;
      s.liquid_bounds.lo = s.liquid_bounds.lo.cwiseMin(shape.bounds.lo);
      s.liquid_bounds.hi = s.liquid_bounds.hi.cwiseMax(shape.bounds.hi);
    }
    if (r.has("velocity")) {
      const toml::array* a = t->get("velocity")->as_array();
      if (a != nullptr && !a->empty() && a->get(0)->is_string()) {
        auto [field, speed] = velocity_expressions<Dim>(r, *a, shape);
        moving.emplace_back(shape.phi, std::move(field));
        s.max_initial_speed = std::max(s.max_initial_speed, speed);
      } else {
        const Vec<Dim> u = r.vec<Dim>("velocity");
        moving.emplace_back(shape.phi, [u](const Vec<Dim>&) { return u; });
        s.max_initial_speed = std::max(s.max_initial_speed, u.norm());
      }
    }
    s.liquid = combine<Dim>(s.liquid, shape);
  }
  if (!moving.empty())
    s.velocity = [moving](const Vec<Dim>& x) {
      Vec<Dim> v = Vec<Dim>::Zero();
      for (const auto& [phi, u] : moving)
        if (phi(x) < 0.0) v = u(x);
      return v;
    };
  for (const toml::table* t : top.tables("solid")) {
    const TableReader r(*t, path, "solid", shape_keys);
    const Shape<Dim> shape = read_shape<Dim>(r, true);
    LIQUID_VERIFY(s.solid || shape.op == "add", "{}: the first [[solid]] shape must add solid",
                  r.where("op"));
    s.solid = combine<Dim>(s.solid, shape);
  }
  for (const toml::table* t : top.tables("source")) {
    std::vector<std::string> keys = shape_keys;
    keys.erase(std::find(keys.begin(), keys.end(), "op"));
    keys.insert(keys.end(), {"velocity", "start", "stop"});
    const TableReader r(*t, path, "source", keys);
    const Shape<Dim> shape = read_shape<Dim>(r, false);
    LIQUID_VERIFY(inside<Dim>(shape.bounds, s.domain), "{}: the source {} reaches outside the domain {}",
                  r.where("shape"), format_box<Dim>(shape.bounds), format_box<Dim>(s.domain));
    SceneSource<Dim> src;
    src.region = shape.phi;
    src.bounds = shape.bounds;
    src.velocity = r.vec<Dim>("velocity");
    src.start = r.number("start", 0.0);
    src.stop = r.number("stop", std::numeric_limits<double>::infinity());
    LIQUID_VERIFY(src.start >= 0.0 && src.stop > src.start, "{}: need 0 <= start < stop (found {} and {})",
                  r.where("stop"), src.start, src.stop);
    s.sources.push_back(src);
  }
}

/// The PIC solver's options: its own tables' values (s.pic) with the scene's domain, gravity,
/// adaptivity, solids and sources.
template <int Dim>
void assemble_pic(Scene<Dim>& s) {
  pic::PicOptions<Dim>& o = s.pic;
  o.domain = s.domain;
  o.gravity = s.gravity;
  o.adaptive = s.adaptive;
  o.solid = s.solid;
  o.sources.clear();
  for (const SceneSource<Dim>& src : s.sources)
    o.sources.push_back({src.region, src.velocity, src.start, src.stop});
  if (!s.ppe_solver_given) o.solver.kind = default_ppe_solver(o.adaptive, Dim);
}

}  // namespace

template <int Dim>
Scene<Dim> load_scene(const std::string& path) {
  const toml::table doc = parse(path);
  const TableReader top(doc, path, "",
                        {"name", "description", "figure", "domain", "grid", "solver", "sph", "time", "ppe",
                         "output", "fluid", "solid", "source"});
  Scene<Dim> s;
  s.path = path;
  s.name = top.string("name", stem_of(path));
  LIQUID_VERIFY(is_file_stem(s.name),
                "{}: '{}' is not a file stem: a scene's name names its output files, so it takes letters, "
                "digits, '-', '_', '.' and '+' only, and does not start with '.' or '-'",
                top.where("name"), s.name);
  s.description = top.string("description", std::string());
  s.figure = top.string("figure", std::string());
  read_domain<Dim>(top, s);
  {
    const TableReader solver(table_or_empty<Dim>(top, "solver"), path, "solver", solver_keys);
    read_method<Dim>(solver, s);
    read_pic_solver<Dim>(solver, s);
  }
  read_grid<Dim>(top, s);
  if (const toml::table* t = top.table("sph")) {
    const TableReader sph(*t, path, "sph", sph_keys);
    s.sph_table = sph.where_table();
    read_sph<Dim>(sph, s);
  }
  read_time<Dim>(top, s);
  read_ppe<Dim>(top, s);
  read_output<Dim>(top, s);
  read_shapes<Dim>(top, s);
  assemble_pic<Dim>(s);
  if (s.sph) sph_options<Dim>(s);  // refuses what the SPH solver cannot run, naming the key
  return s;
}

template <int Dim>
PicSize estimate_pic_size(const Scene<Dim>& s) {
  const pic::PicOptions<Dim>& o = s.pic;
  const Vec<Dim> size = s.domain.size();
  const double domain_volume = s.domain.volume();
  const double fine_cell = std::ldexp(domain_volume, -Dim * o.finest_level);
  // The liquid's volume, and on a tree the volume of the band around its surface, by sampling the
  // liquid's level set (less the solids) on a lattice of the domain.
  const int n = Dim == 2 ? 256 : 48;
  const double h = std::ldexp(size.maxCoeff(), -o.finest_level);
  const double width = (o.band + 1) * h;  // the band's half width around the surface
  // A band thinner than the lattice is measured at the lattice's spacing and scaled down (the
  // surface's area times the width), so that it never vanishes between the samples.
  const double spacing = size.maxCoeff() / n, reach = std::max(width, spacing);
  long total = 1;
  for (int k = 0; k < Dim; ++k) total *= n;
  long inside = 0, band = 0, band_inside = 0;
  if (s.liquid) {
    for (long i = 0; i < total; ++i) {
      Vec<Dim> x;
      for (long k = 0, r = i; k < Dim; ++k, r /= n)
        x[k] = s.domain.lo[k] + size[k] * (static_cast<double>(r % n) + 0.5) / n;
      if (s.solid && s.solid(x) < 0.0) continue;
      const double phi = s.liquid(x);
      inside += phi < 0.0;
      band += std::abs(phi) < reach;
      band_inside += phi < 0.0 && phi > -reach;
    }
  }
  const double liquid_volume = domain_volume * static_cast<double>(inside) / static_cast<double>(total);
  PicSize out;
  if (!s.adaptive) {
    out.cells = std::ldexp(1.0, Dim * o.finest_level);
    out.particles = (1 << Dim) * liquid_volume / fine_cell;
    out.bytes = 300.0 * (out.particles + out.cells);
    return out;
  }
  const double scale = domain_volume * width / reach / static_cast<double>(total);
  const double band_volume = scale * static_cast<double>(band);
  const double band_liquid = std::min(scale * static_cast<double>(band_inside), liquid_volume);
  const double coarse_cell = std::ldexp(domain_volume, -Dim * o.coarse_level);
  out.particles = (1 << Dim) * (band_liquid / fine_cell + (liquid_volume - band_liquid) / coarse_cell);
  out.cells = band_volume / fine_cell + domain_volume / coarse_cell;
  out.bytes = 600.0 * out.particles + 3000.0 * out.cells;
  return out;
}
template PicSize estimate_pic_size<2>(const Scene<2>&);
template PicSize estimate_pic_size<3>(const Scene<3>&);

template <int Dim>
void check_sph_table(const Scene<Dim>& s) {
  LIQUID_VERIFY(
      s.sph || s.sph_table.empty(),
      "{}: the [sph] table is read only by the SPH solver (solver.method = \"sph\" or --method sph); "
      "this run is '{}', which would ignore it",
      s.sph_table, to_string(s.pic.transfer));
}
template void check_sph_table<2>(const Scene<2>&);
template void check_sph_table<3>(const Scene<3>&);

linalg::SolverKind default_ppe_solver(bool adaptive, int dim) {
  if (!adaptive) return linalg::SolverKind::cg_jacobi;
  return dim == 3 ? linalg::SolverKind::bicgstab_jacobi : linalg::SolverKind::bicgstab_ilut;
}

std::string scenes_folder() {
  if (const char* env = std::getenv("LIQUID_SCENES"); env && *env) return env;
  return LIQUID_SCENES_DIR;
}

std::string find_scene(const std::string& name_or_path) {
  if (std::filesystem::is_regular_file(name_or_path)) return name_or_path;
  const std::filesystem::path builtin = std::filesystem::path(scenes_folder()) / (name_or_path + ".toml");
  if (std::filesystem::is_regular_file(builtin)) return builtin.string();
  std::vector<std::string> names;
  for (const auto& [name, description] : builtin_scenes()) names.push_back(name);
  throw Error(fmt::format("no scene file '{}' and no built-in scene of that name (built-in, in {}: {})",
                          name_or_path, scenes_folder(), fmt::join(names, ", ")));
}

std::vector<std::pair<std::string, std::string>> builtin_scenes() {
  std::vector<std::pair<std::string, std::string>> out;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(scenes_folder(), ec)) {
    if (entry.path().extension() != ".toml") continue;
    std::string description;
    try {
      const toml::table doc = parse(entry.path().string());
      description = doc["description"].value_or(std::string());
    } catch (const Error& e) {
      description = std::string("(cannot be read: ") + e.what() + ")";
    }
    out.emplace_back(entry.path().stem().string(), description);
  }
  std::sort(out.begin(), out.end());
  return out;
}

template sph::SphOptions<2> sph_options<2>(const Scene<2>&);
template sph::SphOptions<3> sph_options<3>(const Scene<3>&);
template double sph_sound_speed<2>(const Scene<2>&);
template double sph_sound_speed<3>(const Scene<3>&);
template Scene<2> load_scene<2>(const std::string&);
template Scene<3> load_scene<3>(const std::string&);

}  // namespace liquid::scene
