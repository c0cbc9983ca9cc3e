// liquid-verify: runs the verification cases and suites.
//
//   liquid-verify list
//   liquid-verify run CASE [--json FILE] [--md FILE] [--levels A:B] [--max-jump K] [--solver NAME] [--full]
//   liquid-verify suite quick|full [--out DIR]
//
// Exit codes: 0 every case met its expectations; 1 a case missed one; 2 bad input (the message
// names it); 3 an unexpected internal error.

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include <cstdio>
#include <iostream>
#include <regex>

#include "common/case.hpp"
#include "common/record.hpp"
#include "liquid/core/error.hpp"
#include "liquid/core/timer.hpp"

namespace lv = liquid::verification;

namespace {

struct RunOutcome {
  bool passed = false;
  lv::Json json;
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
  RunOutcome outcome{result.passed, lv::result_json(info.name, result, seconds)};
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

  std::string case_name, json_path, md_path, levels, solver, stencil;
  int max_jump = -1;
  bool full = false;
  auto* run = app.add_subcommand("run", "run one case and print its tables");
  run->add_option("case", case_name, "case name (see list)")->required();
  run->add_option("--json", json_path, "write the result as JSON to FILE");
  run->add_option("--md", md_path, "write the result as Markdown to FILE");
  run->add_option("--levels", levels, "refinement levels A:B of a convergence study");
  run->add_option("--max-jump", max_jump, "largest level jump between neighbouring cells");
  run->add_option("--solver", solver, "linear solver name");
  run->add_option("--stencil", stencil, "RBF-FD stencil rule: nearest, face-grown or ring");
  run->add_flag("--full", full, "use the full suite's extent");

  std::string suite_name = "quick", out_dir = "reports/latest";
  auto* suite = app.add_subcommand("suite", "run a suite, writing DIR/<case>.json and DIR/<case>.md");
  suite->add_option("name", suite_name, "quick or full")->check(CLI::IsMember({"quick", "full"}));
  suite->add_option("--out", out_dir, "output folder");

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
      options.full = full;
      fmt::print("liquid-verify run {} levels={} max-jump={} solver={} tier={}\n", case_name,
                 levels.empty() ? "default" : levels, max_jump >= 0 ? std::to_string(max_jump) : "default",
                 solver.empty() ? "default" : solver, full ? "full" : "quick");
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
  } catch (const liquid::Error& e) {
    fmt::print(stderr, "liquid-verify: error: {}\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    fmt::print(stderr, "liquid-verify: internal error: {}\n", e.what());
    return 3;
  }
  return 0;
}
