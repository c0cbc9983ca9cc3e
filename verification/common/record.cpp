#include "record.hpp"

#include <filesystem>
#include <fstream>

#include <fmt/format.h>

#include "liquid/core/error.hpp"
#include "liquid/io/files.hpp"

namespace liquid::verification {

std::string status_word(const CaseResult& result) {
  if (!result.passed) return "FAILED";
  if (!result.asserted) return "ran, nothing asserted (--expect-order P[,G] or --expect-error E would check)";
  return "passed";
}

Json result_json(const std::string& name, const CaseResult& result, double seconds) {
  Json j = Json::object();
  j.set("case", name);
  j.set("passed", result.passed);
  j.set("asserted", result.asserted);
  j.set("seconds", seconds);
  j.set("rows", result.tables.empty() ? Json::array() : result.tables.front().to_json());
  Json tables = Json::array();
  for (const auto& t : result.tables) {
    Json tj = Json::object();
    tj.set("title", t.title());
    tj.set("rows", t.to_json());
    tables.push(std::move(tj));
  }
  j.set("tables", std::move(tables));
  Json failures = Json::array();
  for (const auto& f : result.failures) failures.push(f);
  j.set("failures", std::move(failures));
  Json notes = Json::array();
  for (const auto& n : result.notes) notes.push(n);
  j.set("notes", std::move(notes));
  Json warnings = Json::array();
  for (const auto& w : result.warnings) warnings.push(w);
  j.set("warnings", std::move(warnings));
  // Case-specific top-level fields last (order, order_grad, ...).
  if (const auto* fields = result.fields.items())
    for (const auto& [key, value] : *fields) j.set(key, value);
  return j;
}

std::string result_text(const std::string& name, const CaseResult& result, double seconds) {
  std::string out = fmt::format("== {} ==\n", name);
  for (const auto& t : result.tables) out += t.to_text() + "\n";
  for (const auto& n : result.notes) out += "note: " + n + "\n";
  for (const auto& w : result.warnings) out += "WARNING: " + w + "\n";
  for (const auto& f : result.failures) out += "FAILED: " + f + "\n";
  out += fmt::format("{}: {} in {:.2f} s\n", name, status_word(result), seconds);
  return out;
}

std::string result_markdown(const std::string& name, const std::string& summary, const CaseResult& result,
                            double seconds) {
  std::string out = fmt::format("## `{}` — {}\n\n{}\n\n", name, status_word(result), summary);
  for (const auto& t : result.tables) out += t.to_markdown() + "\n";
  for (const auto& n : result.notes) out += "- " + n + "\n";
  for (const auto& w : result.warnings) out += "- **warning:** " + w + "\n";
  for (const auto& f : result.failures) out += "- **failed:** " + f + "\n";
  out += fmt::format("\nRun time: {:.2f} s.\n", seconds);
  return out;
}

void check_output_path(const std::string& flag, const std::string& path) {
  io::check_output_file(flag, path);
}

void write_file(const std::string& path, const std::string& text) {
  io::write_text_file(path, text);
}

}  // namespace liquid::verification
