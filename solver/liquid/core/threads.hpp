#pragma once
// How the programs run their OpenMP threads. Idle threads sleep (passive waiting) unless the user
// set OMP_WAIT_POLICY: spinning threads on a machine with other load made 2-thread runs several
// times slower than 1-thread ones. Why: docs/findings/threads.md.

#include <unistd.h>

#include <cstdlib>
#include <string>

#include <omp.h>

namespace liquid {

/// Call first in main(). When OMP_WAIT_POLICY is not set, sets it to "passive" and runs the program
/// again with the same arguments (the OpenMP runtime reads the variable once, before main); returns
/// when it is set already, or when the program cannot be run again (then threads wait actively).
inline void use_passive_waiting(char** argv) {
  if (std::getenv("OMP_WAIT_POLICY") != nullptr) return;
  if (setenv("OMP_WAIT_POLICY", "passive", 1) != 0) return;
  execv("/proc/self/exe", argv);  // returns only on failure
}

/// "N threads, OMP_WAIT_POLICY=..." for the programs' echo.
inline std::string thread_summary() {
  const char* policy = std::getenv("OMP_WAIT_POLICY");
  return std::to_string(omp_get_max_threads()) + " threads, OMP_WAIT_POLICY=" +
         (policy ? std::string(policy) : std::string("unset (active waiting)"));
}

}  // namespace liquid
