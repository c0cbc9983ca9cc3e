#include "user_poisson.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <regex>
#include <sstream>

#include <fmt/format.h>

#include "common/expression.hpp"
#include "liquid/core/error.hpp"
#include "liquid/levelset/levelset.hpp"
#include "liquid/tree/builders.hpp"
#include "options.hpp"
#include "studies/poisson_study.hpp"

namespace liquid::verification {

namespace {

// What a user study accepts: domain sides whose squares and inverse squares stay far inside
// double's range, finest cells wider than 1e-11 of the coordinates (so that a cell's centre and
// its faces differ in many digits), and solution values whose squares cannot overflow.
constexpr double kMinDomainWidth = 1e-50;
constexpr double kMaxDomainWidth = 1e50;
constexpr double kMinRelativeCell = 1e-11;
constexpr double kMaxSolution = 1e100;

std::vector<double> parse_numbers(const std::string& text, const std::string& what) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    std::size_t used = 0;
    double v = 0.0;
    try {
      v = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    LIQUID_VERIFY(used > 0 && item.find_first_not_of(" \t", used) == std::string::npos,
                  "{}: '{}' is not a number (in '{}')", what, item, text);
    out.push_back(v);
  }
  return out;
}

template <int Dim>
CaseResult run(const UserPoissonArgs& args) {
  const auto box = parse_numbers(args.domain, "--domain");
  LIQUID_VERIFY(static_cast<int>(box.size()) == 2 * Dim,
                "--domain: {}D needs {} numbers x0,x1,y0,y1{}, got {}", Dim, 2 * Dim,
                Dim == 3 ? ",z0,z1" : "", box.size());
  Box<Dim> domain;
  for (int k = 0; k < Dim; ++k) {
    domain.lo[k] = box[2 * k];
    domain.hi[k] = box[2 * k + 1];
    LIQUID_VERIFY(std::isfinite(box[2 * k]) && std::isfinite(box[2 * k + 1]) && box[2 * k] < box[2 * k + 1],
                  "--domain: axis {} is empty or inverted ({} .. {})", k, box[2 * k], box[2 * k + 1]);
    // The study forms squares and inverse squares of lengths: keep them far inside double's range.
    const double width = box[2 * k + 1] - box[2 * k];
    LIQUID_VERIFY(width >= kMinDomainWidth && width <= kMaxDomainWidth,
                  "--domain: axis {} spans {:.3g} ({} .. {}), outside [{:g}, {:g}]", k, width, box[2 * k],
                  box[2 * k + 1], kMinDomainWidth, kMaxDomainWidth);
  }
  LIQUID_VERIFY(args.bc == "neumann" || args.bc == "dirichlet", "--bc must be neumann or dirichlet, got '{}'",
                args.bc);
  LIQUID_VERIFY(args.max_jump >= 1, "--max-jump must be at least 1, got {}", args.max_jump);

  auto exact = std::make_shared<Expression<Dim>>(args.exact, "--exact");
  // A value that is not finite names --exact and the point, wherever the study meets it.
  const auto finite = [exact](double v, const Vec<Dim>& x, const char* what) {
    if (!std::isfinite(v))
      throw Error(fmt::format("--exact '{}': {} is {} at ({:.6g})", exact->text(), what, v,
                              fmt::join(x.data(), x.data() + Dim, ", ")));
    return v;
  };
  std::shared_ptr<Expression<Dim>> phi;
  if (!args.levelset.empty()) phi = std::make_shared<Expression<Dim>>(args.levelset, "--levelset");

  PoissonStudy<Dim> s;
  s.domain = domain;
  s.exact = [exact, finite](const Vec<Dim>& x) { return finite((*exact)(x), x, "p"); };
  s.gradient = [exact, finite](const Vec<Dim>& x) {
    Vec<Dim> g;
    for (int k = 0; k < Dim; ++k) g[k] = finite(exact->derivative(x, k), x, "a derivative of p");
    return g;
  };
  s.laplacian = [exact, finite](const Vec<Dim>& x) { return finite(exact->laplacian(x), x, "f = Lap p"); };
  if (phi) s.levelset = [phi](const Vec<Dim>& x) { return (*phi)(x); };
  s.dirichlet_walls = args.bc == "dirichlet";
  s.max_jump = args.max_jump;
  s.solver.kind = args.solver;
  s.rows = args.rows;
  // A study asserts only what the user expects of it.
  s.order_floor = s.order_grad_floor = -std::numeric_limits<double>::infinity();
  s.asserted = !args.expect_order.empty() || args.expect_error > 0.0;
  if (!args.expect_order.empty()) {
    const auto floors = parse_numbers(args.expect_order, "--expect-order");
    LIQUID_VERIFY(floors.size() == 1 || floors.size() == 2, "--expect-order expects P or P,G, got '{}'",
                  args.expect_order);
    for (double v : floors)
      LIQUID_VERIFY(std::isfinite(v) && v > 0.0 && v < 10.0, "--expect-order: {} is not an order in (0, 10)",
                    v);
    s.order_floor = floors[0];
    if (floors.size() == 2) s.order_grad_floor = floors[1];
  }
  if (args.expect_error > 0.0) s.error_ceiling = args.expect_error;

  const LevelRange levels = parse_level_range(args.levels, "--levels");
  s.level_min = levels.first;
  s.level_max = levels.last;
  std::smatch m;

  // The refined region: the level set when given, else a circle/sphere at the centre.
  levelset::Function<Dim> band_phi = s.levelset;
  if (!band_phi) band_phi = levelset::sphere<Dim>(domain.centre(), 0.25 * domain.size().minCoeff());
  static const std::regex random(R"(^random:(\d+)$)");
  if (args.tree == "uniform") {
    s.finest_offset = 0;
    s.make_tree = [domain](int level, const tree::CellGraphOptions<Dim>& o) {
      return tree::uniform<Dim>(domain, level, o);
    };
  } else if (args.tree == "band") {
    s.make_tree = [domain, band_phi](int level, const tree::CellGraphOptions<Dim>& o) {
      return tree::banded<Dim>(domain, band_phi, level, 3.0, o);
    };
  } else if (std::regex_match(args.tree, m, random)) {
    std::uint64_t seed = 0;
    const std::string digits = m.str(1);
    const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), seed);
    LIQUID_VERIFY(ec == std::errc() && end == digits.data() + digits.size(),
                  "--tree {}: the seed is out of range (at most {})", args.tree,
                  std::numeric_limits<std::uint64_t>::max());
    s.make_tree = [domain, seed](int level, const tree::CellGraphOptions<Dim>& o) {
      return tree::random<Dim>(domain, seed, level, level + 2, 0.3, o);
    };
  } else {
    throw Error(fmt::format("--tree must be uniform, band or random:SEED, got '{}'", args.tree));
  }
  LIQUID_VERIFY(s.level_max + s.finest_offset <= morton::max_level<Dim>,
                "--levels {}: the finest level {} exceeds {} in {}D", args.levels,
                s.level_max + s.finest_offset, morton::max_level<Dim>, Dim);
  // The finest cells must be far wider than the spacing of doubles at the domain's coordinates.
  for (int k = 0; k < Dim; ++k) {
    const double h = domain.size()[k] / std::ldexp(1.0, s.level_max + s.finest_offset);
    const double at = std::max(std::abs(domain.lo[k]), std::abs(domain.hi[k]));
    LIQUID_VERIFY(
        h >= kMinRelativeCell * at,
        "--domain: axis {} ({} .. {}): cells of the finest level {} are {:.3g} wide, below {:g} times "
        "the coordinates' size: move the domain towards the origin or use fewer levels",
        k, domain.lo[k], domain.hi[k], s.level_max + s.finest_offset, h, kMinRelativeCell);
  }

  // How far below the measured errors are the numerical f and grad p? GSL's estimates at sample points.
  double f_err = 0.0, g_err = 0.0;
  for (int i = 0; i < 64; ++i) {
    Vec<Dim> x;
    for (int k = 0; k < Dim; ++k)
      x[k] = domain.lo[k] + domain.size()[k] * ((i * (k + 3) * 37 % 64) + 0.5) / 64;
    // Values past kMaxSolution overflow the squared norms of the errors and residuals: refuse them
    // here, by name, rather than print NaN orders.
    const auto bounded = [&](double v, const char* what) {
      LIQUID_VERIFY(std::abs(v) <= kMaxSolution,
                    "--exact '{}': |{}| is {:.3g} at ({:.6g}), above {:g}: the study's norms would overflow; "
                    "scale the solution",
                    args.exact, what, std::abs(v), fmt::join(x.data(), x.data() + Dim, ", "), kMaxSolution);
    };
    bounded(finite((*exact)(x), x, "p"), "p");
    double e = 0.0;
    bounded(finite(exact->laplacian(x, &e), x, "f = Lap p"), "f = Lap p");
    f_err = std::max(f_err, e);
    for (int k = 0; k < Dim; ++k) {
      bounded(finite(exact->derivative(x, k, &e), x, "a derivative of p"), "a derivative of p");
      g_err = std::max(g_err, e);
    }
  }

  if (phi) {
    // Later rows only refine the region, so a level set negative at no centre of the first row's
    // tree leaves no unknowns: say so by the argument's name before any solve.
    tree::CellGraphOptions<Dim> o;
    o.max_jump = s.max_jump;
    const tree::CellGraph<Dim> first = s.make_tree(s.level_min, o);
    bool inside = false;
    first.for_each_cell([&](tree::CellId c) { inside = inside || (*phi)(first.centre(c)) < 0.0; });
    LIQUID_VERIFY(
        inside, "--levelset '{}' is negative at no cell centre of the level {} tree ({} cells): no unknowns",
        args.levelset, s.level_min, first.n_cells());
  }

  CaseOptions options;
  if (args.nullspace_given) options.nullspace = args.nullspace;
  if (args.tolerance != 0.0) options.tolerance = args.tolerance;
  options.algebraic = args.algebraic;
  options.max_cells = args.max_cells;
  CaseResult result = run_poisson_study<Dim>(s, options);
  // The smallest errors measured must sit well above what the numerical derivatives could add:
  // an error e in f moves p by about e L^2 (L the domain's size); grad p is compared directly.
  const double size = domain.size().maxCoeff();
  double min_p = std::numeric_limits<double>::infinity(), min_g = min_p;
  for (const GateFigure& g : result.gate) {
    if (g.kind != GateFigure::Kind::error) continue;
    if (g.name.ends_with("err p")) min_p = std::min(min_p, g.value);
    if (g.name.ends_with("err dp/dn")) min_g = std::min(min_g, g.value);
  }
  const double p_from_f = f_err * size * size;
  const bool roundoff = min_p < exact_error_level && min_g < exact_error_level;
  if (!roundoff) {
    result.expect(p_from_f <= 0.1 * min_p,
                  fmt::format("the numerical f (estimated error {:.1e}, about {:.1e} in p) is not 10 times "
                              "below the smallest error of p measured ({:.1e}): the table may show the "
                              "derivatives' error; use a smoother p or a coarser finest level",
                              f_err, p_from_f, min_p));
    result.expect(g_err <= 0.1 * min_g,
                  fmt::format("the numerical grad p (estimated error {:.1e}) is not 10 times below the "
                              "smallest error of dp/dn measured ({:.1e})",
                              g_err, min_g));
  }
  result.notes.push_back(
      fmt::format("grad p from GSL central differences and f = Lap p from Richardson-extrapolated second "
                  "differences of '{}'; largest estimated error of f at 64 sample points: "
                  "{:.1e} (an error in f of e moves p by about e times the domain size squared: {:.1e}); "
                  "of grad p: {:.1e}",
                  args.exact, f_err, p_from_f, g_err));
  result.fields.set("grad_error_estimate", g_err);
  result.fields.set("f_error_estimate", f_err);
  result.fields.set("command", describe(args));
  return result;
}

}  // namespace

std::string describe(const UserPoissonArgs& a) {
  return fmt::format(
      "liquid-verify poisson --dim {} --exact '{}'{} --domain {} --bc {} --tree {} --max-jump {} "
      "--levels {} --rows {} --solver {} --nullspace {} --tolerance {:g} --algebraic {} --expect-order {} "
      "--expect-error {} "
      "--max-cells {}",
      a.dim, a.exact, a.levelset.empty() ? "" : " --levelset '" + a.levelset + "'", a.domain, a.bc, a.tree,
      a.max_jump, a.levels, to_string(a.rows), linalg::to_string(a.solver),
      a.nullspace_given ? to_string(a.nullspace) : "default", a.tolerance != 0.0 ? a.tolerance : 1e-10,
      to_string(a.algebraic), a.expect_order.empty() ? "none" : a.expect_order,
      a.expect_error > 0.0 ? fmt::format("{:g}", a.expect_error) : "none", a.max_cells);
}

CaseResult run_user_poisson(const UserPoissonArgs& args) {
  LIQUID_VERIFY(args.dim == 2 || args.dim == 3, "--dim must be 2 or 3, got {}", args.dim);
  LIQUID_VERIFY(!args.exact.empty(), "--exact is required");
  return args.dim == 2 ? run<2>(args) : run<3>(args);
}

}  // namespace liquid::verification
