// The usual peak force that tells a revolution that did not cut: against known sequences of
// revolutions' peaks (a steady cut, a spike, a real stop, a heavier cut, a lock).

#include "core/monitor/revolution_stats.hpp"

#include <gtest/gtest.h>

namespace millwatch::monitor {
namespace {

/// A two-flute revolution whose larger flute peak is `peak_N`.
RevolutionMeasurement revolution(double peak_N) {
  RevolutionMeasurement m;
  m.flutes = 2;
  m.peak_resultant_N = {peak_N, 0.8 * peak_N};
  return m;
}

// One revolution with a spike a hundred times the cut's peak (a knock, a chip striking the
// dynamometer, a sample at the amplifier's range) cuts, and every revolution of the cut after
// it still does: the usual peak rises 5 % at most.
TEST(RevolutionStats, ASpikeDoesNotMakeTheCutAfterItIdle) {
  RevolutionStats stats(30);
  for (int i = 0; i < 20; ++i) {
    ASSERT_TRUE(stats.cutting(revolution(2.0)));
  }
  EXPECT_DOUBLE_EQ(stats.typical_peak_N(), 2.0);
  EXPECT_TRUE(stats.cutting(revolution(200.0)));
  EXPECT_NEAR(stats.typical_peak_N(), 2.1, 1e-12);
  for (int i = 0; i < 50; ++i) {
    ASSERT_TRUE(stats.cutting(revolution(2.0))) << i;
  }
  EXPECT_NEAR(stats.typical_peak_N(), 2.0, 0.01);
}

// A spike in the first revolutions after a lock (the entry revolution the tooth events walked
// back to, struck by a chip) does not set the usual peak: it starts at the first three's
// median, and none of the cut after them is idle.
TEST(RevolutionStats, ASpikeAmongTheFirstRevolutionsDoesNotSetTheUsualPeak) {
  for (int at = 0; at < RevolutionStats::kSeedRevolutions; ++at) {
    RevolutionStats stats(30);
    for (int i = 0; i < RevolutionStats::kSeedRevolutions; ++i) {
      EXPECT_TRUE(stats.cutting(revolution(i == at ? 200.0 : 2.0 + 0.1 * i)));
    }
    EXPECT_LE(stats.typical_peak_N(), 2.2);
    for (int i = 0; i < 30; ++i) {
      ASSERT_TRUE(stats.cutting(revolution(2.0))) << at << " " << i;
    }
    EXPECT_NEAR(stats.typical_peak_N(), 2.0, 0.2) << at;
  }
}

// Revolutions below a fifth of the usual peak did not cut (the tool left the work), and do not
// move it; a cut three times heavier is followed within a few dozen revolutions.
TEST(RevolutionStats, AStopIsIdleAndAHeavierCutIsFollowed) {
  RevolutionStats stats(30);
  for (int i = 0; i < 20; ++i) {
    ASSERT_TRUE(stats.cutting(revolution(2.0)));
  }
  for (int i = 0; i < 10; ++i) {
    EXPECT_FALSE(stats.cutting(revolution(0.3)));
  }
  EXPECT_DOUBLE_EQ(stats.typical_peak_N(), 2.0);
  for (int i = 0; i < 60; ++i) {
    ASSERT_TRUE(stats.cutting(revolution(6.0)));
  }
  EXPECT_NEAR(stats.typical_peak_N(), 6.0, 0.5);
  // Back to the lighter cut: still cutting (above a fifth).
  EXPECT_TRUE(stats.cutting(revolution(2.0)));
}

// A lock starts the usual peak again: after a heavy cut, a light one (below a fifth of it) is
// taken as cutting from its lock on; a stop after it is idle again. A usual peak of zero (two
// of the first three revolutions at 0 N) is no usual peak: the next revolution gives it.
TEST(RevolutionStats, ALockLearnsTheUsualPeakAgain) {
  RevolutionStats stats(30);
  for (int i = 0; i < 20; ++i) {
    ASSERT_TRUE(stats.cutting(revolution(10.0)));
  }
  EXPECT_FALSE(stats.cutting(revolution(1.0)));
  stats.restart();
  EXPECT_EQ(stats.typical_peak_N(), 0.0);
  for (int i = 0; i < 10; ++i) {
    EXPECT_TRUE(stats.cutting(revolution(1.0)));
  }
  EXPECT_DOUBLE_EQ(stats.typical_peak_N(), 1.0);
  // And a stop after it is idle again.
  EXPECT_FALSE(stats.cutting(revolution(0.1)));
  stats.restart();
  for (const double peak : {0.0, 0.0, 1.0}) {
    EXPECT_TRUE(stats.cutting(revolution(peak)));
  }
  EXPECT_EQ(stats.typical_peak_N(), 0.0);
  EXPECT_TRUE(stats.cutting(revolution(2.0)));
  EXPECT_EQ(stats.typical_peak_N(), 2.0);
  EXPECT_FALSE(stats.cutting(revolution(0.1)));
}

}  // namespace
}  // namespace millwatch::monitor
