#include "options.hpp"

#include <unistd.h>

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <initializer_list>
#include <limits>
#include <map>
#include <regex>
#include <sstream>

#include <fmt/format.h>

#include "liquid/core/error.hpp"

namespace liquid::verification {

namespace {

// The names come from the library's own to_string, so the command line and the library agree.
template <class E>
std::map<std::string, E> names_of(std::initializer_list<E> values) {
  std::map<std::string, E> out;
  for (E v : values) out.emplace(to_string(v), v);
  return out;
}
const std::map<std::string, linalg::SolverKind> solver_names = [] {
  std::map<std::string, linalg::SolverKind> out;
  for (const std::string& name : linalg::solver_names()) out.emplace(name, linalg::parse_solver(name));
  return out;
}();
const std::map<std::string, mac::StencilRule> stencil_names =
    names_of({mac::StencilRule::nearest, mac::StencilRule::face_grown, mac::StencilRule::ring});
const std::map<std::string, RowProtocol> row_names = names_of({RowProtocol::refine, RowProtocol::rebuild});
const std::map<std::string, NullspaceChoice> nullspace_names =
    names_of({NullspaceChoice::pin, NullspaceChoice::pin_point, NullspaceChoice::zero_mean});
const std::map<std::string, AlgebraicControl> algebraic_names =
    names_of({AlgebraicControl::tighten, AlgebraicControl::check, AlgebraicControl::off});
const std::map<std::string, Perturbation> perturb_names{{"first-order", Perturbation::first_order}};

// CLI::Range lets NaN through (every comparison with it is false), so the real-valued flags are
// checked finite first; text that is no number is left to the conversion's own message.
const CLI::Validator finite_number(
    [](std::string& text) {
      char* end = nullptr;
      const double v = std::strtod(text.c_str(), &end);
      if (end == text.c_str() || std::isfinite(v)) return std::string();
      return "a finite number is needed, got " + text;
    },
    "FINITE");

template <class E>
std::string name_of(const std::map<std::string, E>& names, E value) {
  for (const auto& [k, v] : names)
    if (v == value) return k;
  return "?";
}

const char* const kNullspaceHelp =
    "pure Neumann Poisson studies: pin (default: one unknown near the centre pinned to the exact value, "
    "the discrete incompatibility then spread as a uniform source), pin-point (the paper's: left at the "
    "pinned cell, a point source) or zero-mean (a bordered system)";
const char* const kAlgebraicHelp =
    "Poisson studies: keep the solver's error out of the errors reported. tighten (default): continue "
    "each solve to 100x tighter tolerances until the solution moves by under 1% of the row's error; "
    "check: continue once and report that share only; off: no second solve";

}  // namespace

LevelRange parse_level_range(const std::string& text, const std::string& flag) {
  static const std::regex pattern(R"(^\s*(\d+)\s*:\s*(\d+)\s*$)");
  std::smatch m;
  LIQUID_VERIFY(std::regex_match(text, m, pattern), "{} expects A:B with integers A <= B, got '{}'", flag,
                text);
  LevelRange r;
  for (auto [part, out] : {std::pair{m.str(1), &r.first}, std::pair{m.str(2), &r.last}}) {
    const auto [end, ec] = std::from_chars(part.data(), part.data() + part.size(), *out);
    LIQUID_VERIFY(
        ec == std::errc() && end == part.data() + part.size() && *out <= 64,
        "{} {}: the level {} is out of range (0 to 64; a tree has at most 30 levels in 2D, 20 in 3D)", flag,
        text, part);
  }
  LIQUID_VERIFY(r.first <= r.last, "{} {}: the first level exceeds the last", flag, text);
  return r;
}

SizeList parse_size_list(const std::string& text, const std::string& flag) {
  static const std::regex pattern(R"(^\s*([23])\s*:\s*(\d+(\s*,\s*\d+)*)\s*$)");
  std::smatch m;
  LIQUID_VERIFY(std::regex_match(text, m, pattern),
                "{} expects D:N[,N...] with D = 2 or 3 and whole divisions N (e.g. 3:48,64), got '{}'", flag,
                text);
  SizeList sizes;
  sizes.dim = m.str(1) == "2" ? 2 : 3;
  std::stringstream list(m.str(2));
  for (std::string part; std::getline(list, part, ',');) {
    part.erase(0, part.find_first_not_of(' '));
    part.erase(part.find_last_not_of(' ') + 1);
    int n = 0;
    const auto [end, ec] = std::from_chars(part.data(), part.data() + part.size(), n);
    LIQUID_VERIFY(ec == std::errc() && end == part.data() + part.size() && n >= 4 && n <= 1000,
                  "{} {}: the division {} is out of range (4 to 1000: spacings a/4 to a/1000)", flag, text,
                  part);
    LIQUID_VERIFY(sizes.divisions.empty() || n > sizes.divisions.back(),
                  "{} {}: the divisions must increase (finer sizes last)", flag, text);
    sizes.divisions.push_back(n);
  }
  return sizes;
}

long default_max_cells() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page <= 0) return 4'000'000;
  return static_cast<long>(0.5 * double(pages) * double(page) / kCellBytes);
}

bool StudyFlags::given(Option option) const {
  return app->count(flag_of(option)) > 0;
}

void add_study_flags(CLI::App& app, StudyFlags& f) {
  f.app = &app;
  f.max_cells = default_max_cells();
  app.add_option("--levels", f.levels, "refinement levels A:B of a convergence study");
  app.add_option("--max-jump", f.max_jump, "largest level jump between neighbouring cells (1-30)")
      ->check(CLI::Range(1, 30));
  app.add_option("--solver", f.solver, "linear solver")->transform(CLI::CheckedTransformer(solver_names));
  app.add_option("--stencil", f.stencil, "RBF-FD stencil rule")
      ->transform(CLI::CheckedTransformer(stencil_names));
  app.add_option("--rbf-exponent", f.rbf_exponent, "PHS exponent s of the RBF-FD Laplacian rows")
      ->check(CLI::IsMember({1, 3, 5, 7, 9}));
  app.add_option("--rbf-degree", f.rbf_degree, "polynomial degree of the RBF-FD Laplacian rows")
      ->check(CLI::Range(0, 4));
  app.add_option("--gradient-degree", f.gradient_degree, "polynomial degree of RBF-FD face gradients")
      ->check(CLI::Range(0, 4));
  app.add_option("--stencil-growth", f.stencil_growth,
                 "irregular RBF-FD stencils grow to G x (polynomial terms) + 1 nodes")
      ->check(finite_number)
      ->check(CLI::Range(1.0, 8.0));
  app.add_option("--ring-cap", f.ring_cap,
                 "ring stencils keep at most C x (their target size) nodes, the nearest; 0: whole rings")
      ->check(finite_number)
      ->check(CLI::Range(0.0, 8.0));
  app.add_option("--gradient-cap", f.gradient_cap,
                 "as --ring-cap, for the RBF-FD face gradients only (the PIC step's 3D default is 2); 0: "
                 "--ring-cap applies")
      ->check(finite_number)
      ->check(CLI::Range(0.0, 8.0));
  app.add_option("--rows", f.rows,
                 "Poisson studies: refine the first row's tree uniformly (the paper's recursive subdivision) "
                 "or rebuild each row's tree by its rule")
      ->transform(CLI::CheckedTransformer(row_names));
  app.add_option("--nullspace", f.nullspace, kNullspaceHelp)
      ->transform(CLI::CheckedTransformer(nullspace_names));
  app.add_option("--tolerance", f.tolerance, "relative residual the linear solver must reach")
      ->check(finite_number)
      ->check(CLI::Range(1e-16, 0.5));
  app.add_option("--algebraic", f.algebraic, kAlgebraicHelp)
      ->transform(CLI::CheckedTransformer(algebraic_names));
  app.add_option("--perturb", f.perturb, "run a deliberately degraded scheme (first-order)")
      ->transform(CLI::CheckedTransformer(perturb_names));
  app.add_option("--trees", f.trees_dir, "write the trees the case checks to DIR as HDF5 + XDMF (ParaView)")
      ->check(CLI::ExistingDirectory);
  app.add_option("--methods", f.methods, "flow studies: run only these methods (comma-separated row names)")
      ->delimiter(',');
  app.add_option(
      "--reference-method", f.reference,
      "dam-break-convergence: the method of the reference run, one level finer than the finest row "
      "(default: regular-apic; adaptive-rbf in 3D past level 7)");
  app.add_option("--band", f.band,
                 "flow studies: the adaptive rows keep cells within K face hops of a surface cell at the "
                 "finest level (0 to 16, as the scene key [grid] band; default 2, the paper's)")
      ->check(CLI::Range(0, 16));
  app.add_option("--seed", f.seed,
                 "sampled problems (the SPH resampling and surface cases): the random draws");
  app.add_option("--particles", f.particles,
                 "sampled problems: how many particles are drawn (100 to 2000000)")
      ->check(CLI::Range(100L, 2'000'000L));
  app.add_option("--radius", f.radius,
                 "sph-sphere-surface: the sphere's radius, in the unit box (0.05 to 0.35)")
      ->check(finite_number)
      ->check(CLI::Range(0.05, 0.35));
  app.add_option("--aspect", f.aspect, "sph-flat-surface: the box's width over its height (0.25 to 4)")
      ->check(finite_number)
      ->check(CLI::Range(0.25, 4.0));
  app.add_option(
         "--merge-wait", f.merge_wait,
         "sph-adaptivity-gain: a split's children are not merged for this many resampling passes (0 to "
         "1000; 0, the default, is the paper's)")
      ->check(CLI::Range(0, 1000));
  app.add_option("--duration", f.duration,
                 "pool-stability: simulated seconds of every row (0.1 to 3600; default 6, full tier 30)")
      ->check(finite_number)
      ->check(CLI::Range(0.1, 3600.0));
  app.add_option(
      "--sizes", f.sizes,
      "sph-gain-scaling: one dimension and its spacings a/N, as D:N[,N...] (e.g. 3:48; N from 4 to "
      "1000, increasing)");
  app.add_option(
         "--resample-travel", f.resample_travel,
         "sph-adaptivity-gain, sph-gain-scaling: resample once the fastest particle may have travelled this "
         "many level-0 spacings (0 to 100; 0: every 5th step, the paper's)")
      ->check(finite_number)
      ->check(CLI::Range(0.0, 100.0));
  app.add_option("--max-cells", f.max_cells, kMaxCellsHelp)->check(CLI::Range(1L, 1'000'000'000'000L));
  app.add_flag("--full", f.full, "use the full suite's extent");
}

CaseOptions case_options(const StudyFlags& f, const CaseInfo& info) {
  std::vector<std::string> refused;
  for (Option o : {Option::levels,          Option::max_jump,       Option::solver,
                   Option::stencil,         Option::rbf_exponent,   Option::rbf_degree,
                   Option::gradient_degree, Option::stencil_growth, Option::ring_cap,
                   Option::gradient_cap,    Option::rows,           Option::nullspace,
                   Option::tolerance,       Option::algebraic,      Option::perturb,
                   Option::trees,           Option::methods,        Option::seed,
                   Option::particles,       Option::radius,         Option::aspect,
                   Option::merge_wait,      Option::duration,       Option::sizes,
                   Option::resample_travel, Option::reference,      Option::band})
    if (f.given(o) && !info.accepts_option(o)) refused.push_back(flag_of(o));
  if (!refused.empty()) {
    std::vector<std::string> accepted;
    for (Option o : info.accepts) accepted.push_back(flag_of(o));
    throw Error(fmt::format("case '{}' does not take {}: it {}", info.name, fmt::join(refused, ", "),
                            accepted.empty()
                                ? "fixes its own problem, trees and scheme (it takes only --full)"
                                : fmt::format("takes {} (and --full)", fmt::join(accepted, ", "))));
  }
  CaseOptions o;
  if (f.given(Option::levels)) o.levels = parse_level_range(f.levels, "--levels");
  if (f.given(Option::max_jump)) o.max_jump = f.max_jump;
  if (f.given(Option::solver)) o.solver = f.solver;
  if (f.given(Option::stencil)) o.stencil = f.stencil;
  if (f.given(Option::rbf_exponent)) o.rbf_exponent = f.rbf_exponent;
  if (f.given(Option::rbf_degree)) o.rbf_degree = f.rbf_degree;
  if (f.given(Option::gradient_degree)) o.gradient_degree = f.gradient_degree;
  if (f.given(Option::stencil_growth)) o.stencil_growth = f.stencil_growth;
  // A ring cap: 0 (whole rings; for --gradient-cap, --ring-cap's) or at least 1, and the ring rule's.
  const auto cap = [&](Option option, double value, const char* zero) {
    if (!(value == 0.0 || value >= 1.0))
      throw Error(fmt::format("{} {} must be 0 ({}) or at least 1 (a stencil keeps at least its target size)",
                              flag_of(option), value, zero));
    if (value != 0.0 && f.given(Option::stencil) && f.stencil != mac::StencilRule::ring)
      throw Error(fmt::format("{} limits the ring rule's stencils; --stencil {} takes none", flag_of(option),
                              mac::to_string(f.stencil)));
    return value;
  };
  if (f.given(Option::ring_cap)) o.ring_cap = cap(Option::ring_cap, f.ring_cap, "whole rings");
  if (f.given(Option::gradient_cap))
    o.gradient_cap = cap(Option::gradient_cap, f.gradient_cap, "as --ring-cap");
  if (f.given(Option::rows)) o.rows = f.rows;
  if (f.given(Option::nullspace)) o.nullspace = f.nullspace;
  if (f.given(Option::tolerance)) o.tolerance = f.tolerance;
  if (f.given(Option::algebraic)) o.algebraic = f.algebraic;
  if (f.given(Option::perturb)) o.perturb = f.perturb;
  if (f.given(Option::trees)) o.trees_dir = f.trees_dir;
  if (f.given(Option::methods)) {
    if (f.methods.empty()) throw Error("--methods: give at least one method");
    o.methods = f.methods;
  }
  if (f.given(Option::reference)) o.reference = f.reference;
  if (f.given(Option::band)) o.band = f.band;
  if (f.given(Option::seed)) {
    // Digits only, within 64 bits (a parser for unsigned integers would wrap -3 or saturate 1e23).
    std::uint64_t seed = 0;
    const char* end = f.seed.data() + f.seed.size();
    const auto [at, ec] = std::from_chars(f.seed.data(), end, seed);
    LIQUID_VERIFY(!f.seed.empty() && ec == std::errc() && at == end,
                  "--seed '{}': expected a whole number from 0 to {}", f.seed,
                  std::numeric_limits<std::uint64_t>::max());
    o.seed = seed;
  }
  if (f.given(Option::particles)) o.particles = f.particles;
  if (f.given(Option::radius)) o.radius = f.radius;
  if (f.given(Option::aspect)) o.aspect = f.aspect;
  if (f.given(Option::merge_wait)) o.merge_wait = f.merge_wait;
  if (f.given(Option::duration)) o.duration = f.duration;
  if (f.given(Option::sizes)) o.sizes = parse_size_list(f.sizes, "--sizes");
  if (f.given(Option::resample_travel)) o.resample_travel = f.resample_travel;
  o.max_cells = f.max_cells;
  o.full = f.full;
  return o;
}

std::string echo(const std::string& case_name, const StudyFlags& f) {
  const auto show = [&](Option o, const std::string& value) {
    return fmt::format(" {} {}", flag_of(o), f.given(o) ? value : "default");
  };
  std::string s = "liquid-verify run " + case_name;
  s += show(Option::levels, f.levels);
  s += show(Option::max_jump, std::to_string(f.max_jump));
  s += show(Option::solver, name_of(solver_names, f.solver));
  s += show(Option::stencil, name_of(stencil_names, f.stencil));
  s += show(Option::rbf_exponent, std::to_string(f.rbf_exponent));
  s += show(Option::rbf_degree, std::to_string(f.rbf_degree));
  s += show(Option::gradient_degree, std::to_string(f.gradient_degree));
  s += show(Option::stencil_growth, fmt::format("{:g}", f.stencil_growth));
  s += show(Option::ring_cap, fmt::format("{:g}", f.ring_cap));
  s += show(Option::gradient_cap, fmt::format("{:g}", f.gradient_cap));
  s += show(Option::rows, name_of(row_names, f.rows));
  s += show(Option::nullspace, name_of(nullspace_names, f.nullspace));
  s += show(Option::tolerance, fmt::format("{:g}", f.tolerance));
  s += show(Option::algebraic, to_string(f.algebraic));
  s += show(Option::perturb, name_of(perturb_names, f.perturb));
  s += show(Option::trees, f.trees_dir);
  s += show(Option::methods, fmt::format("{}", fmt::join(f.methods, ",")));
  s += show(Option::reference, f.reference);
  s += show(Option::band, std::to_string(f.band));
  s += show(Option::seed, f.seed);
  s += show(Option::particles, std::to_string(f.particles));
  s += show(Option::radius, fmt::format("{:g}", f.radius));
  s += show(Option::aspect, fmt::format("{:g}", f.aspect));
  s += show(Option::merge_wait, std::to_string(f.merge_wait));
  s += show(Option::duration, fmt::format("{:g}", f.duration));
  s += show(Option::sizes, f.sizes);
  s += show(Option::resample_travel, fmt::format("{:g}", f.resample_travel));
  s += fmt::format(" --max-cells {} --tier {}", f.max_cells, f.full ? "full" : "quick");
  return s;
}

void add_user_poisson_flags(CLI::App& app, UserPoissonArgs& a) {
  a.max_cells = default_max_cells();
  app.add_option("--dim", a.dim, "2 or 3")->required()->check(CLI::IsMember({2, 3}));
  app.add_option("--exact", a.exact, "exact p as an expression in x, y (, z), e.g. 'sin(x)*cos(2*y)'")
      ->required();
  app.add_option("--levelset", a.levelset,
                 "unknowns where this expression is negative; p = exact on its zero set");
  app.add_option("--domain", a.domain, "x0,x1,y0,y1[,z0,z1]")->required();
  app.add_option("--bc", a.bc, "walls: neumann (dp/dn of the exact p) or dirichlet (the exact p)")
      ->check(CLI::IsMember({"neumann", "dirichlet"}));
  app.add_option("--tree", a.tree, "uniform, band, or random:SEED");
  app.add_option("--max-jump", a.max_jump, "largest level jump between neighbouring cells (1-30)")
      ->check(CLI::Range(1, 30));
  app.add_option("--levels", a.levels, "base levels A:B of the rows (A < B)");
  app.add_option("--rows", a.rows, "refine the first row's tree (default) or rebuild each row's")
      ->transform(CLI::CheckedTransformer(row_names));
  app.add_option("--solver", a.solver, "linear solver")->transform(CLI::CheckedTransformer(solver_names));
  app.add_option("--nullspace", a.nullspace, kNullspaceHelp)
      ->transform(CLI::CheckedTransformer(nullspace_names));
  app.add_option("--tolerance", a.tolerance, "relative residual the linear solver must reach (default 1e-10)")
      ->check(finite_number)
      ->check(CLI::Range(1e-16, 0.5));
  app.add_option("--algebraic", a.algebraic, kAlgebraicHelp)
      ->transform(CLI::CheckedTransformer(algebraic_names));
  app.add_option("--expect-order", a.expect_order,
                 "P[,G]: exit 1 when the fitted order of p (and of dp/dn) falls below");
  app.add_option("--expect-error", a.expect_error, "exit 1 when the finest row's L-inf error of p exceeds E")
      ->check(finite_number)
      ->check(CLI::PositiveNumber);
  app.add_option("--max-cells", a.max_cells, kMaxCellsHelp)->check(CLI::Range(1L, 1'000'000'000'000L));
}

}  // namespace liquid::verification
