#include "gate.hpp"

#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <sstream>

#include <fmt/format.h>
#include <toml++/toml.h>

#include "liquid/core/error.hpp"
#include "record.hpp"

namespace liquid::verification {

const char* to_string(GateFigure::Kind kind) {
  switch (kind) {
    case GateFigure::Kind::error:
      return "error";
    case GateFigure::Kind::order:
      return "order";
    case GateFigure::Kind::iterations:
      return "iterations";
    case GateFigure::Kind::count:
      return "count";
  }
  return "unknown";
}

namespace {

GateFigure::Kind parse_kind(const std::string& text, const std::string& where) {
  for (auto k : {GateFigure::Kind::error, GateFigure::Kind::order, GateFigure::Kind::iterations,
                 GateFigure::Kind::count})
    if (text == to_string(k)) return k;
  throw Error(fmt::format("{}: unknown figure kind '{}' (error, order, iterations or count)", where, text));
}

std::string reference_path(const std::string& dir, const std::string& case_name) {
  return (std::filesystem::path(dir) / (case_name + ".toml")).string();
}

std::string where(const std::string& path, const toml::source_region& r) {
  return fmt::format("{}:{}", path, r.begin.line);
}

/// Refuses, naming file:line and key, a key of `table` that is not one of `known`: a misspelt
/// tolerance or a figure's own tolerance would otherwise be read as nothing and loosen nothing.
void only_known_keys(const toml::table& table, const std::string& path, const std::string& prefix,
                     std::initializer_list<const char*> known) {
  for (const auto& [key, node] : table) {
    bool ok = false;
    for (const char* k : known) ok = ok || key.str() == k;
    std::string names;
    for (const char* k : known) names += (names.empty() ? "" : ", ") + std::string(k);
    LIQUID_VERIFY(ok, "{}: unknown key '{}{}' (known: {})", where(path, node.source()), prefix, key.str(),
                  names);
  }
}

GateTolerance read_tolerance(const toml::table& doc, const std::string& path) {
  GateTolerance t;
  if (const auto* node = doc.get("tolerance"))
    LIQUID_VERIFY(node->is_table(),
                  "{}: 'tolerance' must be a table [tolerance] of error_rel, error_floor, "
                  "order_drop and iterations_rel",
                  where(path, node->source()));
  if (const auto* tol = doc["tolerance"].as_table()) {
    only_known_keys(*tol, path, "tolerance.", {"error_rel", "error_floor", "order_drop", "iterations_rel"});
    auto get = [&](const char* key, double& out) {
      if (const auto* node = tol->get(key)) {
        const auto v = node->value<double>();
        LIQUID_VERIFY(v && std::isfinite(*v) && *v >= 0.0,
                      "{}: tolerance.{} must be a finite non-negative number", where(path, node->source()),
                      key);
        out = *v;
      }
    };
    get("error_rel", t.error_rel);
    get("error_floor", t.error_floor);
    get("order_drop", t.order_drop);
    get("iterations_rel", t.iterations_rel);
  }
  return t;
}

toml::table parse_file(const std::string& path) {
  try {
    return toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    throw Error(
        fmt::format("{}:{}:{}: {}", path, e.source().begin.line, e.source().begin.column, e.description()));
  }
}

}  // namespace

std::vector<AcceptedFigure> read_reference(const std::string& path, GateTolerance& tol) {
  const toml::table doc = parse_file(path);
  only_known_keys(doc, path, "", {"case", "tolerance", "figure"});
  tol = read_tolerance(doc, path);
  const auto* list = doc["figure"].as_array();
  LIQUID_VERIFY(list != nullptr, "{}: no [[figure]] entries", path);
  std::vector<AcceptedFigure> out;
  for (const auto& node : *list) {
    const auto* t = node.as_table();
    LIQUID_VERIFY(t != nullptr, "{}: [[figure]] must be a table", where(path, node.source()));
    only_known_keys(*t, path, "figure.", {"name", "kind", "value"});
    const auto name = (*t)["name"].value<std::string>();
    const auto kind = (*t)["kind"].value<std::string>();
    const auto value = (*t)["value"].value<double>();
    const std::string at = where(path, t->source());
    LIQUID_VERIFY(name && kind && value, "{}: a figure needs name, kind and value", at);
    LIQUID_VERIFY(std::isfinite(*value), "{}: figure '{}' has the value {}, not a finite number", at, *name,
                  *value);
    for (const auto& seen : out)
      LIQUID_VERIFY(seen.name != *name, "{}: figure '{}' is accepted twice (first at {})", at, *name,
                    seen.where);
    out.push_back({*name, *kind, parse_kind(*kind, at), *value, at});
  }
  return out;
}

void validate_reference(const std::string& case_name, const std::string& reference_dir) {
  const std::string path = reference_path(reference_dir, case_name);
  if (!std::filesystem::exists(path)) return;  // reported as a missing reference after the run
  GateTolerance tol;
  (void)read_reference(path, tol);
}

bool GateOutcome::passed() const {
  if (!problems.empty()) return false;
  for (const auto& l : lines)
    if (l.regression) return false;
  return true;
}

GateOutcome compare_with_reference(const std::string& case_name, const std::vector<GateFigure>& figures,
                                   const std::string& reference_dir) {
  GateOutcome out;
  const std::string path = reference_path(reference_dir, case_name);
  if (!std::filesystem::exists(path)) {
    out.problems.push_back(
        fmt::format("no accepted figures: {} is missing (run the gate with --bless)", path));
    return out;
  }
  GateTolerance tol;
  const std::vector<AcceptedFigure> accepted = read_reference(path, tol);
  for (const AcceptedFigure& a : accepted) {
    const std::string* name = &a.name;
    const std::string* kind = &a.kind;
    GateLine line;
    line.figure = a.name;
    line.kind = a.kind;
    line.accepted = a.value;
    const GateFigure::Kind k = a.parsed;
    const GateFigure* now = nullptr;
    for (const auto& f : figures)
      if (f.name == *name) now = &f;
    if (now == nullptr) {
      out.problems.push_back(fmt::format("{}: accepted figure '{}' is no longer produced", case_name, *name));
      continue;
    }
    // A relabelled kind would switch its check off (an order read as an error passes when it rises).
    LIQUID_VERIFY(k == now->kind,
                  "{}: figure '{}' is accepted as kind '{}', but the case produces it as '{}'", a.where,
                  *name, *kind, to_string(now->kind));
    line.now = now->value;
    switch (k) {
      case GateFigure::Kind::error:
        line.allowed = line.accepted * (1.0 + tol.error_rel) + tol.error_floor;
        line.regression = !(line.now <= line.allowed);
        break;
      case GateFigure::Kind::order:
        line.allowed = line.accepted - tol.order_drop;
        line.regression = !(line.now >= line.allowed);
        break;
      case GateFigure::Kind::iterations:
        line.allowed = std::floor(line.accepted * (1.0 + tol.iterations_rel)) + 2.0;
        line.regression = !(line.now <= line.allowed);
        break;
      case GateFigure::Kind::count:
        line.allowed = line.accepted;
        line.regression = !(line.now <= line.allowed);
        break;
    }
    line.moved = line.now != line.accepted &&
                 std::abs(line.now - line.accepted) > 1e-6 * std::max(std::abs(line.accepted), 1e-300);
    out.lines.push_back(line);
  }
  for (const auto& f : figures) {
    bool known = false;
    for (const auto& l : out.lines) known = known || l.figure == f.name;
    for (const auto& p : out.problems) known = known || p.find("'" + f.name + "'") != std::string::npos;
    if (!known)
      out.problems.push_back(
          fmt::format("{}: new figure '{}' = {:.6g} has no accepted value (bless to accept it)", case_name,
                      f.name, f.value));
  }
  return out;
}

void bless_reference(const std::string& case_name, const std::vector<GateFigure>& figures,
                     const std::string& reference_dir) {
  const std::string path = reference_path(reference_dir, case_name);
  GateTolerance tol;
  if (std::filesystem::exists(path)) tol = read_tolerance(parse_file(path), path);
  std::string text = fmt::format(
      "# Accepted figures of the verification case {}, checked by `liquid-verify gate`.\n"
      "# Written by `liquid-verify gate --bless`; a commit that moves them says why.\n"
      "case = \"{}\"\n\n[tolerance]\nerror_rel = {}\nerror_floor = {}\norder_drop = {}\niterations_rel = "
      "{}\n",
      case_name, case_name, tol.error_rel, tol.error_floor, tol.order_drop, tol.iterations_rel);
  for (const auto& f : figures)
    text += fmt::format("\n[[figure]]\nname = \"{}\"\nkind = \"{}\"\nvalue = {:.10g}\n", f.name,
                        to_string(f.kind), f.value);
  write_file(path, text);
}

Table gate_table(const std::string& case_name, const GateOutcome& outcome, bool all) {
  Table t(fmt::format("gate {}: figures that moved", case_name),
          {"figure", "kind", "accepted", "now", "allowed", "status"});
  for (const auto& l : outcome.lines) {
    if (!all && !l.moved && !l.regression) continue;
    t.add_row(
        {l.figure, l.kind, l.accepted, l.now, l.allowed, std::string(l.regression ? "REGRESSION" : "ok")});
  }
  return t;
}

}  // namespace liquid::verification
