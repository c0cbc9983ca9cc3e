// liquid-verify: runs the verification cases and suites.
//
//   liquid-verify list
//   liquid-verify run CASE [--json FILE] [--md FILE] [--levels A:B] [--max-jump K] [--solver NAME] ...
//   [--full]
//                         (a case refuses the study options it does not read)
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
#include "liquid/core/threads.hpp"
#include "liquid/core/timer.hpp"
#include "liquid/io/files.hpp"
#include "options.hpp"
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

}  // namespace

int main(int argc, char** argv) {
  liquid::use_passive_waiting(argv);
  CLI::App app{"liquid-verify: verification cases of the liquid solvers"};
  app.require_subcommand(1);

  auto* list = app.add_subcommand("list", "list the verification cases");
  bool quick_names = false;
  list->add_flag("--quick-names", quick_names,
                 "print only the names of the quick cases, one a line (for ctest)");
  bool list_markdown = false;
  list->add_flag("--markdown", list_markdown, "print the cases as a Markdown table (the README's)");

  std::string case_name, json_path, md_path;
  lv::StudyFlags flags;
  auto* run = app.add_subcommand("run", "run one case and print its tables");
  run->add_option("case", case_name, "case name (see list)")->required();
  run->add_option("--json", json_path, "write the result as JSON to FILE");
  run->add_option("--md", md_path, "write the result as Markdown to FILE");
  lv::add_study_flags(*run, flags);

  std::string suite_name = "quick", out_dir = "reports/latest";
  auto* suite = app.add_subcommand("suite", "run a suite, writing DIR/<case>.json and DIR/<case>.md");
  suite->add_option("name", suite_name, "quick or full")->check(CLI::IsMember({"quick", "full"}));
  suite->add_option("--out", out_dir, "output folder");

  std::string gate_suite = "quick", reference_dir = std::string(LIQUID_SOURCE_DIR) + "/reference", perturb;
  std::vector<std::string> gate_cases;
  bool bless = false;
  auto* gate =
      app.add_subcommand("gate", "run a suite and compare its figures with the accepted ones in reference/");
  gate->add_option("--suite", gate_suite, "quick or full")->check(CLI::IsMember({"quick", "full"}));
  gate->add_option("--reference", reference_dir,
                   "folder of the accepted <case>.toml files (default: the "
                   "source tree's reference/)")
      ->check(CLI::ExistingDirectory);
  gate->add_option("--case", gate_cases, "gate only these cases (repeatable)");
  gate->add_flag("--bless", bless, "write the current figures as the accepted ones");
  gate->add_option("--perturb", perturb,
                   "run a deliberately degraded scheme (first-order) to see the gate fail")
      ->check(CLI::IsMember({"first-order"}));

  lv::UserPoissonArgs user;
  std::string user_json, user_md;
  auto* poisson = app.add_subcommand("poisson", "your own manufactured-solution convergence study");
  lv::add_user_poisson_flags(*poisson, user);
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
      if (quick_names) {
        for (const auto& c : lv::case_registry())
          if (c.quick) fmt::print("{}\n", c.name);
        return 0;
      }
      if (list_markdown) {
        // Grouped by family (the folder under verification/cases/), then by name.
        std::vector<const lv::CaseInfo*> cases;
        for (const auto& c : lv::case_registry()) cases.push_back(&c);
        std::stable_sort(cases.begin(), cases.end(), [](const lv::CaseInfo* a, const lv::CaseInfo* b) {
          return lv::case_family(a->name) < lv::case_family(b->name);
        });
        fmt::print("| case | family | tier | what it checks |\n| --- | --- | --- | --- |\n");
        for (const lv::CaseInfo* c : cases)
          fmt::print("| `{}` | {} | {} | {} |\n", c->name, lv::case_family(c->name),
                     c->quick ? "quick" : "full", c->summary);
        return 0;
      }
      for (const auto& c : lv::case_registry())
        fmt::print("{:<36} {:<6} {}\n", c.name, c.quick ? "quick" : "full", c.summary);
      return 0;
    }
    if (*run) {
      const lv::CaseInfo* info = lv::find_case(case_name);
      LIQUID_VERIFY(info != nullptr, "no verification case named '{}' (liquid-verify list shows them)",
                    case_name);
      if (run->count("--json")) lv::check_output_path("--json", json_path);
      if (run->count("--md")) lv::check_output_path("--md", md_path);
      liquid::io::check_distinct_outputs({{"--json", json_path}, {"--md", md_path}});
      const lv::CaseOptions options = lv::case_options(flags, *info);
      fmt::print("{}\n", lv::echo(case_name, flags));
      fmt::print("  threads: {}\n", liquid::thread_summary());
      return run_case(*info, options, json_path, md_path).passed ? 0 : 1;
    }
    if (*suite) {
      const bool is_full = suite_name == "full";
      LIQUID_VERIFY(!out_dir.empty(), "--out: the folder name is empty");
      lv::check_output_path("--out", (std::filesystem::path(out_dir) / "summary.json").string());
      fmt::print("liquid-verify suite {} --out {}\n", suite_name, out_dir);
      fmt::print("  threads: {}\n", liquid::thread_summary());
      lv::Json summary = lv::Json::object();
      summary.set("suite", suite_name);
      lv::Json cases = lv::Json::array();
      int n_failed = 0, n_run = 0;
      for (const auto& c : lv::case_registry()) {
        if (!is_full && !c.quick) continue;
        lv::CaseOptions options;
        options.full = is_full;
        options.max_cells = lv::default_max_cells();
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
      user.nullspace_given = poisson->count("--nullspace") > 0;
      if (poisson->count("--json")) lv::check_output_path("--json", user_json);
      if (poisson->count("--md")) lv::check_output_path("--md", user_md);
      liquid::io::check_distinct_outputs({{"--json", user_json}, {"--md", user_md}});
      const std::string command = lv::describe(user);
      fmt::print("{}\n", command);
      fmt::print("  threads: {}\n", liquid::thread_summary());
      const lv::CaseInfo info{"poisson-user", command, false,
                              [&](const lv::CaseOptions&) { return lv::run_user_poisson(user); },
                              lv::no_options};
      return run_case(info, lv::CaseOptions{}, user_json, user_md).passed ? 0 : 1;
    }
    if (*gate) {
      const bool is_full = gate_suite == "full";
      for (const auto& name : gate_cases)
        LIQUID_VERIFY(lv::find_case(name) != nullptr, "--case: no verification case named '{}'", name);
      LIQUID_VERIFY(perturb.empty() || !gate_cases.empty(),
                    "--perturb needs --case NAME: it degrades the Poisson studies' scheme, which not every "
                    "case has");
      for (const auto& name : gate_cases)
        LIQUID_VERIFY(perturb.empty() || lv::find_case(name)->perturbable(),
                      "--perturb: case '{}' has no perturbation (it fixes its own scheme)", name);
      fmt::print("liquid-verify gate --suite {} --reference {}{}{}\n", gate_suite, reference_dir,
                 bless ? " --bless" : "", perturb.empty() ? "" : " --perturb " + perturb);
      fmt::print("  threads: {}\n", liquid::thread_summary());
      int n_failed = 0, n_run = 0;
      for (const auto& c : lv::case_registry()) {
        const bool chosen = gate_cases.empty()
                                ? (is_full || c.quick)
                                : std::find(gate_cases.begin(), gate_cases.end(), c.name) != gate_cases.end();
        if (!chosen) continue;
        lv::validate_reference(c.name, reference_dir);  // a broken file is refused before the run
        lv::CaseOptions options;
        options.full = is_full;
        options.max_cells = lv::default_max_cells();
        if (!perturb.empty()) options.perturb = lv::Perturbation::first_order;
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
  } catch (const std::bad_alloc&) {
    fmt::print(stderr,
               "liquid-verify: internal error: out of memory (a smaller --levels or --max-cells "
               "refuses such a study before it starts)\n");
    return 3;
  } catch (const std::exception& e) {
    fmt::print(stderr, "liquid-verify: internal error: {}\n", e.what());
    return 3;
  }
  return 0;
}
