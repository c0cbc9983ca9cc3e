#include "common/case.hpp"

#include <algorithm>
#include <filesystem>
#include <map>
#include <utility>

#include "liquid/core/error.hpp"

namespace liquid::verification {

const char* flag_of(Option option) {
  switch (option) {
    case Option::levels:
      return "--levels";
    case Option::max_jump:
      return "--max-jump";
    case Option::solver:
      return "--solver";
    case Option::stencil:
      return "--stencil";
    case Option::rbf_exponent:
      return "--rbf-exponent";
    case Option::rbf_degree:
      return "--rbf-degree";
    case Option::gradient_degree:
      return "--gradient-degree";
    case Option::stencil_growth:
      return "--stencil-growth";
    case Option::ring_cap:
      return "--ring-cap";
    case Option::gradient_cap:
      return "--gradient-cap";
    case Option::rows:
      return "--rows";
    case Option::nullspace:
      return "--nullspace";
    case Option::tolerance:
      return "--tolerance";
    case Option::algebraic:
      return "--algebraic";
    case Option::perturb:
      return "--perturb";
    case Option::trees:
      return "--trees";
    case Option::methods:
      return "--methods";
    case Option::seed:
      return "--seed";
    case Option::particles:
      return "--particles";
    case Option::radius:
      return "--radius";
    case Option::aspect:
      return "--aspect";
    case Option::merge_wait:
      return "--merge-wait";
    case Option::duration:
      return "--duration";
    case Option::sizes:
      return "--sizes";
    case Option::reference:
      return "--reference-method";
    case Option::band:
      return "--band";
    case Option::resample_travel:
      return "--resample-travel";
  }
  return "?";
}

const char* to_string(RowProtocol rows) {
  return rows == RowProtocol::refine ? "refine" : "rebuild";
}

const char* to_string(NullspaceChoice choice) {
  switch (choice) {
    case NullspaceChoice::pin:
      return "pin";
    case NullspaceChoice::pin_point:
      return "pin-point";
    case NullspaceChoice::zero_mean:
      return "zero-mean";
  }
  return "?";
}

const char* to_string(AlgebraicControl control) {
  switch (control) {
    case AlgebraicControl::tighten:
      return "tighten";
    case AlgebraicControl::check:
      return "check";
    case AlgebraicControl::off:
      return "off";
  }
  return "?";
}

bool CaseInfo::accepts_option(Option o) const {
  return std::find(accepts.begin(), accepts.end(), o) != accepts.end();
}
bool CaseInfo::perturbable() const {
  return accepts_option(Option::perturb);
}

std::vector<CaseInfo>& case_registry() {
  static std::vector<CaseInfo> cases;
  return cases;
}

const CaseInfo* find_case(const std::string& name) {
  for (const auto& c : case_registry())
    if (c.name == name) return &c;
  return nullptr;
}

namespace {
std::map<std::string, std::string>& families() {
  static std::map<std::string, std::string> by_name;
  return by_name;
}
}  // namespace

const std::string& case_family(const std::string& name) {
  static const std::string none;
  const auto it = families().find(name);
  return it == families().end() ? none : it->second;
}

CaseRegistrar::CaseRegistrar(const char* file, CaseInfo info) {
  families()[info.name] = std::filesystem::path(file).parent_path().filename().string();
  LIQUID_VERIFY(find_case(info.name) == nullptr, "verification case '{}' registered twice", info.name);
  auto& cases = case_registry();
  cases.push_back(std::move(info));
  std::sort(cases.begin(), cases.end(), [](const CaseInfo& a, const CaseInfo& b) { return a.name < b.name; });
}

Json series_entry(const std::string& group, const std::string& label, const std::vector<double>& x,
                  const std::vector<double>& y, const std::string& x_label, const std::string& y_label) {
  Json j = Json::object();
  j.set("group", group);
  j.set("label", label);
  Json xs = Json::array(), ys = Json::array();
  for (std::size_t i = 0; i < x.size() && i < y.size(); ++i) xs.push(x[i]), ys.push(y[i]);
  j.set("h", std::move(xs));
  j.set("error", std::move(ys));
  if (!x_label.empty()) j.set("x_label", x_label);
  if (!y_label.empty()) j.set("y_label", y_label);
  return j;
}

}  // namespace liquid::verification
