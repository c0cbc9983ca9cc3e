#pragma once
// Errors: the library throws liquid::Error with a message naming what went wrong; programs catch
// it in main and print it. Two levels of checks, as in the house style:
//   LIQUID_VERIFY(cond, msg)  always on, for user input and run-time failures;
//   LIQUID_ASSERT(cond, msg)  debug builds only, for internal invariants.

#include <fmt/format.h>

#include <stdexcept>
#include <string>

namespace liquid {

/// The library's exception type. what() is a complete sentence for the user.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

/// An Error that is the input's although work had begun to find it (a scene whose liquid holds no
/// sample point once the tree is built): the programs report it as bad input (exit 2), not as a
/// failed run.
class InputError : public Error {
 public:
  using Error::Error;
};

namespace detail {
/// The source path from the repository's top folder on ("solver/liquid/mac/poisson.cpp"), not the
/// build machine's absolute path.
inline std::string source_path(const char* file) {
  const std::string path(file);
  for (const char* top : {"/solver/", "/verification/", "/benchmarks/"}) {
    const auto at = path.rfind(top);
    if (at != std::string::npos) return path.substr(at + 1);
  }
  return path;
}

[[noreturn]] inline void fail(const char* file, int line, const std::string& message) {
  throw Error(fmt::format("{} ({}:{})", message, source_path(file), line));
}
[[noreturn]] inline void fail_input(const char* file, int line, const std::string& message) {
  throw InputError(fmt::format("{} ({}:{})", message, source_path(file), line));
}
}  // namespace detail

}  // namespace liquid

#define LIQUID_VERIFY(cond, ...)                                                       \
  do {                                                                                 \
    if (!(cond)) ::liquid::detail::fail(__FILE__, __LINE__, fmt::format(__VA_ARGS__)); \
  } while (false)

/// LIQUID_VERIFY for a condition on the input that only work can reveal: throws InputError.
#define LIQUID_VERIFY_INPUT(cond, ...)                                                       \
  do {                                                                                       \
    if (!(cond)) ::liquid::detail::fail_input(__FILE__, __LINE__, fmt::format(__VA_ARGS__)); \
  } while (false)

#ifdef NDEBUG
#define LIQUID_ASSERT(cond, ...) \
  do {                           \
  } while (false)
#else
#define LIQUID_ASSERT(cond, ...) LIQUID_VERIFY(cond, __VA_ARGS__)
#endif
