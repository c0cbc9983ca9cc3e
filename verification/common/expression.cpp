#include "expression.hpp"

#include <cmath>

#include <fmt/format.h>
#include <gsl/gsl_deriv.h>
#include <muParser.h>
#include <omp.h>

#include "liquid/core/error.hpp"

namespace liquid::verification {

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
      inst->parser.DefineConst("pi", 3.14159265358979323846);
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

namespace {
template <class F>
double central(F& f, double at, double step, double* abserr) {
  gsl_function g;
  g.function = [](double t, void* p) { return (*static_cast<F*>(p))(t); };
  g.params = &f;
  double result = 0.0, err = 0.0;
  gsl_deriv_central(&g, at, step, &result, &err);
  if (abserr) *abserr = err;
  return result;
}
}  // namespace

template <int Dim>
double Expression<Dim>::derivative(const Vec<Dim>& x, int k, double* abserr) const {
  auto along = [&](double t) {
    Vec<Dim> y = x;
    y[k] = t;
    return (*this)(y);
  };
  return central(along, x[k], 1e-3 * std::max(1.0, std::abs(x[k])), abserr);
}

template <int Dim>
double Expression<Dim>::laplacian(const Vec<Dim>& x, double* abserr) const {
  // GSL has first derivatives only, and nesting them loses 5-6 digits; instead, second central
  // differences at h, h/2, h/4, h/8 with Richardson extrapolation of their h^2, h^4, h^6 terms
  // (exact for polynomials up to degree 9). The error estimate is the last correction.
  double sum = 0.0, err_sum = 0.0;
  for (int k = 0; k < Dim; ++k) {
    const double h0 = 0.05 * std::max(1.0, std::abs(x[k]));
    const double f0 = (*this)(x);
    double table[4][4];
    for (int i = 0; i < 4; ++i) {
      const double h = h0 / (1 << i);
      Vec<Dim> xp = x, xm = x;
      xp[k] += h;
      xm[k] -= h;
      table[i][0] = ((*this)(xp)-2.0 * f0 + (*this)(xm)) / (h * h);
      for (int j = 1; j <= i; ++j) {
        const double factor = std::pow(4.0, j);
        table[i][j] = (factor * table[i][j - 1] - table[i - 1][j - 1]) / (factor - 1.0);
      }
    }
    sum += table[3][3];
    err_sum += std::abs(table[3][3] - table[3][2]) + 1e-14 * std::abs(f0) / (h0 * h0 / 64);
  }
  if (abserr) *abserr = err_sum;
  return sum;
}

template class Expression<2>;
template class Expression<3>;

}  // namespace liquid::verification
