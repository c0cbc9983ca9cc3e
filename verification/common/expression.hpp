#pragma once
// A user's expression in x, y (, z) (liquid::scene::Expression: muparser, one parser per OpenMP
// thread), with numerical first derivatives and Laplacian (GSL's adaptive central differences).

#include <string>

#include "liquid/core/types.hpp"
#include "liquid/scene/expression.hpp"

namespace liquid::verification {

template <int Dim>
class Expression {
 public:
  /// Parses `text`; `what` names the argument in errors (e.g. "--exact"). Throws liquid::Error with
  /// muparser's message and the position of the error.
  Expression(std::string text, std::string what) : value_(std::move(text), std::move(what)) {}

  const std::string& text() const { return value_.text(); }
  double operator()(const Vec<Dim>& x) const { return value_(x); }
  /// d/dx_k at x; `abserr` (optional, out) receives GSL's error estimate.
  double derivative(const Vec<Dim>& x, int k, double* abserr = nullptr) const;
  /// Sum of second derivatives (each the derivative of a numerical derivative).
  double laplacian(const Vec<Dim>& x, double* abserr = nullptr) const;

 private:
  scene::Expression<Dim> value_;
};

}  // namespace liquid::verification
