// Phase timers and the always-on checks.
#include <gtest/gtest.h>

#include "liquid/core/error.hpp"
#include "liquid/core/timer.hpp"

namespace liquid {
namespace {

TEST(PhaseTimer, AccumulatesPerName) {
  PhaseTimer timer;
  for (int i = 0; i < 3; ++i) {
    auto scope = timer.scope("ppe");
  }
  timer.add("grid", 0.5);
  EXPECT_EQ(timer.entries().at("ppe").calls, 3);
  EXPECT_GE(timer.seconds("ppe"), 0.0);
  EXPECT_DOUBLE_EQ(timer.seconds("grid"), 0.5);
  EXPECT_DOUBLE_EQ(timer.seconds("missing"), 0.0);
}

TEST(Verify, ThrowsWithMessageAndLocation) {
  try {
    LIQUID_VERIFY(1 + 1 == 3, "cell {} has residual {}", 42, 1e-3);
    FAIL() << "no throw";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("cell 42 has residual 0.001"), std::string::npos);
    EXPECT_NE(what.find("timer_test.cpp"), std::string::npos);
  }
}

}  // namespace
}  // namespace liquid
