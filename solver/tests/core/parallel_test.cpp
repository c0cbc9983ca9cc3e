// The parallel loop helper: every index once, per-thread state merged, and the first failure
// rethrown with its type after the threads join.
#include <gtest/gtest.h>
#include <omp.h>

#include <new>
#include <stdexcept>
#include <vector>

#include "liquid/core/error.hpp"
#include "liquid/core/parallel.hpp"

namespace liquid {
namespace {

TEST(ParallelFor, VisitsEveryIndexOnceAndMergesState) {
  const long n = 10000;
  std::vector<int> seen(n, 0);
  long total = 0;
  parallel_for(
      n, [] { return 0L; },
      [&](long& sum, long i) {
        ++seen[i];
        sum += i;
      },
      [&](long& sum) { total += sum; }, 16);
  for (long i = 0; i < n; ++i) EXPECT_EQ(seen[i], 1) << i;
  EXPECT_EQ(total, n * (n - 1) / 2);
}

TEST(ParallelFor, RethrowsTheLibraryErrorAsItWas) {
  EXPECT_THROW(parallel_for(1000L,
                            [](long i) {
                              if (i == 517) throw Error("cell 517: bad");
                            }),
               Error);
}

TEST(ParallelFor, KeepsBadAllocAnInternalError) {
  // An out-of-memory failure must not turn into a liquid::Error ("bad input" to the programs).
  bool was_error = false, was_bad_alloc = false;
  try {
    parallel_for(1000L, [](long i) {
      if (i == 3) throw std::bad_alloc();
    });
  } catch (const Error&) {
    was_error = true;
  } catch (const std::bad_alloc&) {
    was_bad_alloc = true;
  }
  EXPECT_FALSE(was_error);
  EXPECT_TRUE(was_bad_alloc);
}

}  // namespace
}  // namespace liquid

/// SerialScope(true) runs the parallel regions its thread starts on one thread and gives the thread
/// count back when it ends, also when it ends by an exception; SerialScope(false) changes nothing.
TEST(SerialScope, RunsOnOneThreadWhileItLivesAndRestoresTheCount) {
  const int before = omp_get_max_threads();
  omp_set_num_threads(2);
  const auto threads_in_a_region = [] {
    int n = 0;
#pragma omp parallel
    {
#pragma omp single
      n = omp_get_num_threads();
    }
    return n;
  };
  ASSERT_EQ(threads_in_a_region(), 2) << "the test needs two threads outside the scope";
  {
    const liquid::SerialScope scope(true);
    EXPECT_EQ(threads_in_a_region(), 1);
  }
  EXPECT_EQ(threads_in_a_region(), 2);
  {
    const liquid::SerialScope scope(false);
    EXPECT_EQ(threads_in_a_region(), 2);
  }
  try {
    const liquid::SerialScope scope(true);
    throw std::runtime_error("leaves the scope");
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(omp_get_max_threads(), 2);
  omp_set_num_threads(before);
}
