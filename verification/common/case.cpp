#include "case.hpp"

#include <algorithm>
#include <utility>

#include "liquid/core/error.hpp"

namespace liquid::verification {

void refuse_study_options(const CaseOptions& options, const std::string& case_name, const std::string& why,
                          bool levels_too) {
  for (const auto& [given, flag] :
       {std::pair{options.perturb.has_value(), "--perturb"},
        std::pair{options.solver.has_value(), "--solver"},
        std::pair{options.max_jump.has_value(), "--max-jump"},
        std::pair{options.stencil.has_value(), "--stencil"}, std::pair{options.rows.has_value(), "--rows"},
        std::pair{options.rbf_exponent.has_value(), "--rbf-exponent"},
        std::pair{options.rbf_degree.has_value(), "--rbf-degree"},
        std::pair{options.gradient_degree.has_value(), "--gradient-degree"},
        std::pair{options.stencil_growth.has_value(), "--stencil-growth"},
        std::pair{options.nullspace.has_value(), "--nullspace"},
        std::pair{options.tolerance.has_value(), "--tolerance"},
        std::pair{levels_too && options.level_min.has_value(), "--levels"}})
    LIQUID_VERIFY(!given, "{} does not take {}: {}", case_name, flag, why);
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

CaseRegistrar::CaseRegistrar(CaseInfo info) {
  LIQUID_VERIFY(find_case(info.name) == nullptr, "verification case '{}' registered twice", info.name);
  auto& cases = case_registry();
  cases.push_back(std::move(info));
  std::sort(cases.begin(), cases.end(), [](const CaseInfo& a, const CaseInfo& b) { return a.name < b.name; });
}

}  // namespace liquid::verification
