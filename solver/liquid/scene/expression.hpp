#pragma once
// An expression in x, y (, z) written in a scene file or on a command line (muparser syntax, the
// constant pi), evaluated from many OpenMP threads at once: one parser per thread.

#include <memory>
#include <string>
#include <vector>

#include "liquid/core/types.hpp"

namespace liquid::scene {

template <int Dim>
class Expression {
 public:
  /// Parses `text`; `what` starts every error message (e.g. "FILE:LINE: key 'fluid.velocity'" or
  /// "--exact"). Throws liquid::Error with muparser's message and the position of the error.
  Expression(std::string text, std::string what);
  ~Expression();
  Expression(const Expression&) = delete;
  Expression& operator=(const Expression&) = delete;

  const std::string& text() const { return text_; }
  const std::string& what() const { return what_; }
  /// The value at x (from any thread of the OpenMP team this object was made for).
  double operator()(const Vec<Dim>& x) const;

 private:
  struct Instance;
  Instance& instance() const;
  std::string text_, what_;
  std::vector<std::unique_ptr<Instance>> instances_;  // one per OpenMP thread
};

}  // namespace liquid::scene
