#include "case.hpp"

#include <algorithm>

#include "liquid/core/error.hpp"

namespace liquid::verification {

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
