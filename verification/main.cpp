// liquid-verify: runs the verification cases and suites.
//
//   liquid-verify list
//   liquid-verify run CASE [--json FILE] [--md FILE] [--levels A:B] [--max-jump K] [--solver NAME] [--full]
//   liquid-verify suite quick|full [--out DIR]
//   liquid-verify poisson --dim 2|3 --exact EXPR [--levelset EXPR] --domain x0,x1,y0,y1[,z0,z1]
//                         --bc neumann|dirichlet --tree uniform|band|random:SEED --max-jump K --levels A:B
//                         [--solver NAME] [--json FILE] [--md FILE]
//   liquid-verify gate [--suite quick|full] [--reference DIR] [--case NAME]... [--bless] [--perturb KIND]
//
// Exit codes: 0 every case met its expectations; 1 a case missed one; 2 bad input (the message
// names it); 3 an unexpected internal error.

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <regex>

#include "common/case.hpp"
#include "common/gate.hpp"
#include "common/record.hpp"
#include "liquid/core/error.hpp"
#include "liquid/core/timer.hpp"
#include "user_poisson.hpp"

namespace lv = liquid::verification;

namespace {

struct RunOutcome {
  bool passed = false;
  lv::Json json;
  std::vector<lv::GateFigure> gate;
};

RunOutcome run_case(const lv::CaseInfo& info, const lv::CaseOptions& options, const std::string& json_path,
                    const std::string& md_path) {
  fmt::print("running {}: {}\n", info.name, info.summary);
  std::fflush(stdout);
  liquid::Stopwatch watch;
  lv::CaseResult result = info.run(options);
  const double seconds = watch.seconds();
  fmt::print("{}\n", lv::result_text(info.name, result, seconds));
  std::fflush(stdout);
  RunOutcome outcome{result.passed, lv::result_json(info.name, result, seconds), result.gate};
  if (!json_path.empty()) lv::write_file(json_path, outcome.json.dump() + "\n");
  if (!md_path.empty())
    lv::write_file(md_path, lv::result_markdown(info.name, info.summary, result, seconds));
  return outcome;
}

void parse_levels(const std::string& text, lv::CaseOptions& options) {
  std::smatch m;
  static const std::regex pattern(R"(^\s*(\d+)\s*:\s*(\d+)\s*$)");
  LIQUID_VERIFY(std::regex_match(text, m, pattern), "--levels expects A:B with integers A <= B, got '{}'",
                text);
  options.level_min = std::stoi(m[1]);
  options.level_max = std::stoi(m[2]);
  LIQUID_VERIFY(*options.level_min <= *options.level_max, "--levels {}: the first level exceeds the last",
                text);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"liquid-verify: verification cases of the liquid solvers"};
  app.require_subcommand(1);

  auto* list = app.add_subcommand("list", "list the verification cases");

  std::string case_name, json_path, md_path, levels, solver, stencil, rows, trees_dir, nullspace;
  double tolerance = -1.0;
  int max_jump = -1, rbf_exponent = -1, rbf_degree = -1, gradient_degree = -1;
  double stencil_growth = -1.0;
  bool full = false;
  auto* run = app.add_subcommand("run", "run one case and print its tables");
  run->add_option("case", case_name, "case name (see list)")->required();
  run->add_option("--json", json_path, "write the result as JSON to FILE");
  run->add_option("--md", md_path, "write the result as Markdown to FILE");
  run->add_option("--levels", levels, "refinement levels A:B of a convergence study");
  run->add_option("--max-jump", max_jump, "largest level jump between neighbouring cells");
  run->add_option("--solver", solver, "linear solver name");
  run->add_option("--stencil", stencil, "RBF-FD stencil rule: nearest, face-grown or ring");
  run->add_option("--rbf-exponent", rbf_exponent, "PHS exponent s (odd, 1-9) of the RBF-FD Laplacian rows");
  run->add_option("--rbf-degree", rbf_degree, "polynomial degree (0-4) of the RBF-FD Laplacian rows");
  run->add_option("--gradient-degree", gradient_degree, "polynomial degree (0-4) of RBF-FD face gradients");
  run->add_option("--stencil-growth", stencil_growth,
                  "irregular RBF-FD stencils grow to G x (polynomial terms) + 1 nodes (default 2, 1-8)");
  run->add_option("--rows", rows,
                  "Poisson studies: refine the first row's tree uniformly (the paper's recursive "
                  "subdivision, the default), or rebuild each row's tree by its rule")
      ->check(CLI::IsMember({"rebuild", "refine"}));
  run->add_option("--nullspace", nullspace,
                  "pure Neumann Poisson studies: pin one unknown near the centre to the exact value (the "
                  "paper's way, the default) or constrain the mean to zero")
      ->check(CLI::IsMember({"pin", "zero-mean"}));
  run->add_option("--tolerance", tolerance, "relative residual the linear solver must reach (default 1e-10)")
      ->check(CLI::Range(1e-16, 0.5));
  run->add_option("--trees", trees_dir,
                  "write the trees the case checks to DIR as HDF5 + XDMF (ParaView); cellgraph-invariants");
  run->add_flag("--full", full, "use the full suite's extent");

  std::string suite_name = "quick", out_dir = "reports/latest";
  auto* suite = app.add_subcommand("suite", "run a suite, writing DIR/<case>.json and DIR/<case>.md");
  suite->add_option("name", suite_name, "quick or full")->check(CLI::IsMember({"quick", "full"}));
  suite->add_option("--out", out_dir, "output folder");

  std::string gate_suite = "quick", reference_dir = "reference", perturb;
  std::vector<std::string> gate_cases;
  bool bless = false;
  auto* gate =
      app.add_subcommand("gate", "run a suite and compare its figures with the accepted ones in reference/");
  gate->add_option("--suite", gate_suite, "quick or full")->check(CLI::IsMember({"quick", "full"}));
  gate->add_option("--reference", reference_dir, "folder of the accepted <case>.toml files");
  gate->add_option("--case", gate_cases, "gate only these cases (repeatable)");
  gate->add_flag("--bless", bless, "write the current figures as the accepted ones");
  gate->add_option("--perturb", perturb,
                   "run a deliberately degraded scheme (first-order) to see the gate fail");
  run->add_option("--perturb", perturb, "run a deliberately degraded scheme (first-order)");

  lv::UserPoissonArgs user;
  std::string user_json, user_md;
  auto* poisson = app.add_subcommand("poisson", "your own manufactured-solution convergence study");
  poisson->add_option("--dim", user.dim, "2 or 3")->required();
  poisson->add_option("--exact", user.exact, "exact p as an expression in x, y (, z), e.g. 'sin(x)*cos(2*y)'")
      ->required();
  poisson->add_option("--levelset", user.levelset,
                      "unknowns where this expression is negative; p = exact on its zero set");
  poisson->add_option("--domain", user.domain, "x0,x1,y0,y1[,z0,z1]")->required();
  poisson->add_option("--bc", user.bc, "walls: neumann or dirichlet (the exact p)");
  poisson->add_option("--tree", user.tree, "uniform, band, or random:SEED");
  poisson->add_option("--max-jump", user.max_jump, "largest level jump between neighbouring cells");
  poisson->add_option("--levels", user.levels, "base levels A:B of the rows");
  poisson->add_option("--solver", user.solver, "linear solver name");
  poisson
      ->add_option("--nullspace", user.nullspace,
                   "Neumann walls without a level set: pin (default) or zero-mean")
      ->check(CLI::IsMember({"pin", "zero-mean"}));
  poisson
      ->add_option("--tolerance", user.tolerance,
                   "relative residual the linear solver must reach (default 1e-10)")
      ->check(CLI::Range(1e-16, 0.5));
  poisson->add_option("--json", user_json, "write the result as JSON to FILE");
  poisson->add_option("--md", user_md, "write the result as Markdown to FILE");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }

  try {
    if (*list) {
      for (const auto& c : lv::case_registry())
        fmt::print("{:<36} {:<6} {}\n", c.name, c.quick ? "quick" : "full", c.summary);
      return 0;
    }
    if (*run) {
      const lv::CaseInfo* info = lv::find_case(case_name);
      LIQUID_VERIFY(info != nullptr, "no verification case named '{}' (liquid-verify list shows them)",
                    case_name);
      lv::CaseOptions options;
      if (!levels.empty()) parse_levels(levels, options);
      if (max_jump >= 0) options.max_jump = max_jump;
      if (!solver.empty()) options.solver = solver;
      if (!stencil.empty()) options.stencil = stencil;
      if (!rows.empty()) options.rows = rows;
      if (!nullspace.empty()) options.nullspace = nullspace;
      if (tolerance > 0.0) options.tolerance = tolerance;
      if (!perturb.empty()) options.perturb = perturb;
      if (rbf_exponent >= 0) options.rbf_exponent = rbf_exponent;
      if (rbf_degree >= 0) options.rbf_degree = rbf_degree;
      if (gradient_degree >= 0) options.gradient_degree = gradient_degree;
      if (stencil_growth != -1.0) options.stencil_growth = stencil_growth;
      if (!trees_dir.empty()) {
        LIQUID_VERIFY(info->writes_trees, "--trees: case '{}' writes no trees (cellgraph-invariants does)",
                      case_name);
        LIQUID_VERIFY(std::filesystem::is_directory(trees_dir), "--trees: '{}' is not a folder", trees_dir);
        options.trees_dir = trees_dir;
      }
      options.full = full;
      fmt::print("liquid-verify run {} levels={} max-jump={} solver={} rows={} tier={}\n", case_name,
                 levels.empty() ? "default" : levels, max_jump >= 0 ? std::to_string(max_jump) : "default",
                 solver.empty() ? "default" : solver, rows.empty() ? "default" : rows,
                 full ? "full" : "quick");
      return run_case(*info, options, json_path, md_path).passed ? 0 : 1;
    }
    if (*suite) {
      const bool is_full = suite_name == "full";
      fmt::print("liquid-verify suite {} --out {}\n", suite_name, out_dir);
      lv::Json summary = lv::Json::object();
      summary.set("suite", suite_name);
      lv::Json cases = lv::Json::array();
      int n_failed = 0, n_run = 0;
      for (const auto& c : lv::case_registry()) {
        if (!is_full && !c.quick) continue;
        lv::CaseOptions options;
        options.full = is_full;
        const auto outcome =
            run_case(c, options, out_dir + "/" + c.name + ".json", out_dir + "/" + c.name + ".md");
        ++n_run;
        n_failed += outcome.passed ? 0 : 1;
        lv::Json entry = lv::Json::object();
        entry.set("case", c.name);
        entry.set("passed", outcome.passed);
        cases.push(std::move(entry));
      }
      summary.set("cases", std::move(cases));
      summary.set("passed", n_failed == 0);
      lv::write_file(out_dir + "/summary.json", summary.dump() + "\n");
      fmt::print("{} passed, {} failed\n", n_run - n_failed, n_failed);
      return n_failed == 0 ? 0 : 1;
    }
    if (*poisson) {
      const std::string command = lv::describe(user);
      fmt::print("{}\n", command);
      const lv::CaseInfo info{"poisson-user", command, false,
                              [&](const lv::CaseOptions&) { return lv::run_user_poisson(user); }};
      return run_case(info, lv::CaseOptions{}, user_json, user_md).passed ? 0 : 1;
    }
    if (*gate) {
      const bool is_full = gate_suite == "full";
      for (const auto& name : gate_cases)
        LIQUID_VERIFY(lv::find_case(name) != nullptr, "--case: no verification case named '{}'", name);
      LIQUID_VERIFY(perturb.empty() || !gate_cases.empty(),
                    "--perturb needs --case NAME: it degrades the Poisson studies' scheme, which not every "
                    "case has");
      fmt::print("liquid-verify gate --suite {} --reference {}{}{}\n", gate_suite, reference_dir,
                 bless ? " --bless" : "", perturb.empty() ? "" : " --perturb " + perturb);
      int n_failed = 0, n_run = 0;
      for (const auto& c : lv::case_registry()) {
        const bool chosen = gate_cases.empty()
                                ? (is_full || c.quick)
                                : std::find(gate_cases.begin(), gate_cases.end(), c.name) != gate_cases.end();
        if (!chosen) continue;
        lv::CaseOptions options;
        options.full = is_full;
        if (!perturb.empty()) options.perturb = perturb;
        const auto outcome = run_case(c, options, "", "");
        ++n_run;
        if (bless) {
          LIQUID_VERIFY(outcome.passed, "{} misses its own expectations; refusing to bless it", c.name);
          lv::bless_reference(c.name, outcome.gate, reference_dir);
          fmt::print("gate {}: blessed {} figures into {}/{}.toml\n\n", c.name, outcome.gate.size(),
                     reference_dir, c.name);
          continue;
        }
        const lv::GateOutcome g = lv::compare_with_reference(c.name, outcome.gate, reference_dir);
        const lv::Table moved = lv::gate_table(c.name, g, false);
        if (!moved.rows().empty()) fmt::print("{}\n", moved.to_text());
        for (const auto& p : g.problems) fmt::print("gate {}: {}\n", c.name, p);
        const bool ok = g.passed() && outcome.passed;
        fmt::print("gate {}: {} ({} figures, {} moved)\n\n", c.name, ok ? "passed" : "FAILED", g.lines.size(),
                   moved.rows().size());
        n_failed += ok ? 0 : 1;
      }
      fmt::print("gate: {} passed, {} failed\n", n_run - n_failed, n_failed);
      return n_failed == 0 ? 0 : 1;
    }
  } catch (const liquid::Error& e) {
    fmt::print(stderr, "liquid-verify: error: {}\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    fmt::print(stderr, "liquid-verify: internal error: {}\n", e.what());
    return 3;
  }
  return 0;
}
