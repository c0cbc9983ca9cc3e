// Speed at equal error (studies/flow_measures): what a method needs at an error, read between its
// runs or bounded outside them, and the speed-up against the fastest of several methods.

#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "studies/flow_measures.hpp"

namespace liquid::verification {
namespace {

// Runs on a power law t = c e^-p are read back exactly between them.
TEST(EqualErrorTest, ReadsAPowerLawBetweenRuns) {
  const ErrorCurve c{"m", {0.04, 0.02, 0.01}, {1.0, 8.0, 64.0}};  // t = (0.04 / e)^3
  for (double e : {0.04, 0.03, 0.02, 0.013, 0.01}) {
    const SecondsAt s = seconds_at(c, e);
    EXPECT_EQ(s.how, Reach::interpolated) << e;
    EXPECT_NEAR(s.seconds, std::pow(0.04 / e, 3.0), 1e-12 * std::pow(0.04 / e, 3.0)) << e;
  }
}

// Outside the runs' range nothing is extrapolated: below, at least the most accurate run's seconds;
// above, at most the cheapest run's.
TEST(EqualErrorTest, BoundsOutsideTheRuns) {
  const ErrorCurve c{"m", {0.04, 0.01, 0.02}, {3.0, 64.0, 8.0}};  // rows in any order
  const SecondsAt fine = seconds_at(c, 0.005);
  EXPECT_EQ(fine.how, Reach::at_least);
  EXPECT_DOUBLE_EQ(fine.seconds, 64.0);
  const SecondsAt coarse = seconds_at(c, 0.1);
  EXPECT_EQ(coarse.how, Reach::at_most);
  EXPECT_DOUBLE_EQ(coarse.seconds, 3.0);
}

// The speed-up at every run's error inside the method's range, against the fastest other method
// there; exact where the others' runs bracket the error, one-sided where one of them is only bounded.
TEST(EqualErrorTest, SpeedUpAgainstTheFastestOther) {
  // The method: t = (0.02 / e)^2 between 0.02 and 0.005 (1 to 16 s).
  const ErrorCurve method{"adaptive", {0.02, 0.005}, {1.0, 16.0}};
  // A: t = 4 (0.02 / e)^2 over [0.01, 0.04]; B: t = 2 (0.02 / e)^3 over [0.008, 0.02].
  const std::vector<ErrorCurve> others{{"a", {0.04, 0.01}, {1.0, 16.0}},
                                       {"b", {0.02, 0.008}, {2.0, 2.0 * std::pow(2.5, 3.0)}}};
  const std::vector<EqualErrorRow> rows = speed_at_equal_error(method, others);
  // Errors 0.02, 0.01, 0.008 and 0.005 (0.04 lies outside the method's range), largest first.
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[0].error, 0.02);
  EXPECT_EQ(rows[3].error, 0.005);
  // At 0.02: A 4 s, B 2 s: B is the fastest, 2x.
  EXPECT_EQ(rows[0].fastest, "b");
  EXPECT_NEAR(rows[0].low, 2.0, 1e-12);
  EXPECT_EQ(rows[0].low, rows[0].high);
  EXPECT_EQ(speedup_text(rows[0]), "2x");
  // At 0.01: A 16 s, B 16 s, the method 4 s: 4x either way.
  EXPECT_NEAR(rows[1].seconds, 4.0, 1e-12);
  EXPECT_NEAR(rows[1].low, 4.0, 1e-12);
  EXPECT_NEAR(rows[1].high, 4.0, 1e-12);
  // At 0.008, beyond A's most accurate run (at least 16 s), B 31.25 s: the fastest takes
  // at least 16 s, at most 31.25 s; B sets the upper bound and is named.
  EXPECT_EQ(rows[2].fastest, "b");
  EXPECT_EQ(rows[2].other.how, Reach::interpolated);
  EXPECT_NEAR(rows[2].low * rows[2].seconds, 16.0, 1e-9);
  EXPECT_NEAR(rows[2].high * rows[2].seconds, 31.25, 1e-9);
  // At 0.005 neither brackets it: at least min(16, 31.25) = 16 s against the method's 16 s, no upper bound.
  EXPECT_NEAR(rows[3].low, 1.0, 1e-12);
  EXPECT_TRUE(std::isinf(rows[3].high));
  EXPECT_EQ(rows[3].other.how, Reach::at_least);
  EXPECT_EQ(speedup_text(rows[3]), ">= 1x");
}

// A slower method's speed-up is below one, and an other whose runs are all more accurate only caps it.
TEST(EqualErrorTest, SlowerMethodAndUpperBounds) {
  const ErrorCurve method{"adaptive", {0.04, 0.02}, {10.0, 40.0}};
  const std::vector<ErrorCurve> others{{"c", {0.01, 0.005}, {5.0, 20.0}}};
  const std::vector<EqualErrorRow> rows = speed_at_equal_error(method, others);
  ASSERT_EQ(rows.size(), 2u);
  // C's cheapest run (5 s) is already more accurate than 0.04 and 0.02: at most 5 s, so at most 0.5x
  // and 0.125x.
  EXPECT_EQ(rows[0].low, 0.0);
  EXPECT_NEAR(rows[0].high, 0.5, 1e-12);
  EXPECT_NEAR(rows[1].high, 0.125, 1e-12);
  EXPECT_EQ(speedup_text(rows[0]), "<= 0.5x");
}

// With fewer than two usable runs there is no range to read over.
TEST(EqualErrorTest, NoRangeNoRows) {
  const std::vector<ErrorCurve> others{{"a", {0.04, 0.01}, {1.0, 16.0}}};
  EXPECT_TRUE(speed_at_equal_error({"m", {0.02}, {1.0}}, others).empty());
  EXPECT_TRUE(speed_at_equal_error({"m", {0.02, 0.0}, {1.0, 2.0}}, others).empty());
  EXPECT_TRUE(speed_at_equal_error({"m", {0.02, 0.01}, {1.0, 2.0}}, {}).empty());
}

}  // namespace
}  // namespace liquid::verification
