#pragma once
// Errors: the library throws liquid::Error with a message naming what went wrong; programs catch
// it in main and print it. Two levels of checks, as in the house style:
//   LIQUID_VERIFY(cond, msg)  always on, for user input and run-time failures;
//   LIQUID_ASSERT(cond, msg)  debug builds only, for internal invariants.

#include <fmt/format.h>

#include <stdexcept>
#include <string>

namespace liquid {

/// The one exception type of the library. what() is a complete sentence for the user.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
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
}  // namespace detail

}  // namespace liquid

#define LIQUID_VERIFY(cond, ...)                                                       \
  do {                                                                                 \
    if (!(cond)) ::liquid::detail::fail(__FILE__, __LINE__, fmt::format(__VA_ARGS__)); \
  } while (false)

#ifdef NDEBUG
#define LIQUID_ASSERT(cond, ...) \
  do {                           \
  } while (false)
#else
#define LIQUID_ASSERT(cond, ...) LIQUID_VERIFY(cond, __VA_ARGS__)
#endif
