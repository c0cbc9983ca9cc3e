#pragma once
// A user's expression in x, y (, z) (muparser), evaluated safely from many OpenMP threads, with
// numerical first derivatives and Laplacian (GSL's adaptive central differences).

#include <memory>
#include <string>
#include <vector>

#include "liquid/core/types.hpp"

namespace liquid::verification {

template <int Dim>
class Expression {
 public:
  /// Parses `text`; `what` names the argument in errors (e.g. "--exact"). Throws liquid::Error with
  /// muparser's message and the position of the error.
  Expression(std::string text, std::string what);
  ~Expression();
  Expression(const Expression&) = delete;
  Expression& operator=(const Expression&) = delete;

  const std::string& text() const { return text_; }
  double operator()(const Vec<Dim>& x) const;
  /// d/dx_k at x; `abserr` (optional, out) receives GSL's error estimate.
  double derivative(const Vec<Dim>& x, int k, double* abserr = nullptr) const;
  /// Sum of second derivatives (each the derivative of a numerical derivative).
  double laplacian(const Vec<Dim>& x, double* abserr = nullptr) const;

 private:
  struct Instance;
  Instance& instance() const;
  std::string text_, what_;
  std::vector<std::unique_ptr<Instance>> instances_;  // one per OpenMP thread
};

}  // namespace liquid::verification
