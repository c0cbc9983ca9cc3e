#include "liquid/scene/expression.hpp"

#include <fmt/format.h>
#include <muParser.h>
#include <omp.h>

#include <algorithm>
#include <numbers>

#include "liquid/core/error.hpp"

namespace liquid::scene {

template <int Dim>
struct Expression<Dim>::Instance {
  mu::Parser parser;
  double vars[3] = {0.0, 0.0, 0.0};
};

template <int Dim>
Expression<Dim>::Expression(std::string text, std::string what)
    : text_(std::move(text)), what_(std::move(what)) {
  const int n = std::max(1, omp_get_max_threads());
  const char* names[3] = {"x", "y", "z"};
  for (int t = 0; t < n; ++t) {
    auto inst = std::make_unique<Instance>();
    try {
      for (int k = 0; k < Dim; ++k) inst->parser.DefineVar(names[k], &inst->vars[k]);
      inst->parser.DefineConst("pi", std::numbers::pi);
      inst->parser.SetExpr(text_);
      inst->parser.Eval();  // parses now, so errors surface here
    } catch (const mu::Parser::exception_type& e) {
      // muparser's message names the position itself for most errors; add it only where it does not.
      std::string message = e.GetMsg();
      if (message.find("position") == std::string::npos)
        message += fmt::format(" at position {}", e.GetPos());
      throw Error(fmt::format("{}: {} of '{}' (variables: {})", what_, message, text_,
                              Dim == 2 ? "x, y" : "x, y, z"));
    }
    instances_.push_back(std::move(inst));
  }
}

template <int Dim>
Expression<Dim>::~Expression() = default;

template <int Dim>
typename Expression<Dim>::Instance& Expression<Dim>::instance() const {
  const int t = omp_get_thread_num();
  LIQUID_ASSERT(t < static_cast<int>(instances_.size()), "expression used from thread {} of {}", t,
                instances_.size());
  return *instances_[t];
}

template <int Dim>
double Expression<Dim>::operator()(const Vec<Dim>& x) const {
  Instance& inst = instance();
  for (int k = 0; k < Dim; ++k) inst.vars[k] = x[k];
  try {
    return inst.parser.Eval();
  } catch (const mu::Parser::exception_type& e) {
    throw Error(fmt::format("{}: cannot evaluate '{}': {}", what_, text_, e.GetMsg()));
  }
}

template class Expression<2>;
template class Expression<3>;

}  // namespace liquid::scene
