// The live identifier's CPU budget as pure bookkeeping on injected times: the rest after a fit
// is t·(1/b − 1), and a worker that follows it (a simulated one, with fits of varying cost and
// windows every 71 ms, as at 25,252 rpm with 30-revolution windows) uses at most the fraction b
// of a core over a long run — and most of it, since it fits the first window after each rest.

#include "core/identify/cpu_budget.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

namespace millwatch::identify {
namespace {

TEST(CpuBudget, AfterAFitOfTItRestsTTimesOneOverBMinusOne) {
  CpuBudget b(0.25);
  EXPECT_TRUE(b.limits());
  EXPECT_TRUE(b.allows(0.0));  // no fit yet: no rest
  EXPECT_EQ(b.period_s(), 0.0);
  b.fit_done(0.1, 10.0);  // 0.1 s of CPU, ended at 10 s
  EXPECT_DOUBLE_EQ(b.rest_until_s(), 10.0 + 0.1 * (1.0 / 0.25 - 1.0));
  EXPECT_FALSE(b.allows(10.0));
  EXPECT_FALSE(b.allows(10.299));
  EXPECT_TRUE(b.allows(10.3));
  EXPECT_DOUBLE_EQ(b.period_s(), 0.4);  // fit and rest: t/b

  CpuBudget none(1.0);  // no budget: never a rest
  EXPECT_FALSE(none.limits());
  none.fit_done(5.0, 1.0);
  EXPECT_TRUE(none.allows(1.0));
}

TEST(CpuBudget, RefusesAFractionOutsideZeroToOne) {
  for (const double bad : {0.0, -0.02, 1.01, std::numeric_limits<double>::quiet_NaN()}) {
    EXPECT_THROW(CpuBudget{bad}, std::invalid_argument) << bad;
  }
}

TEST(CpuBudget, AWorkerThatFollowsItUsesAtMostItsFractionOfACore) {
  for (const double fraction : {0.02, 0.1, 0.5}) {
    CpuBudget b(fraction);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> cost_s(0.05, 0.6);  // a fit's CPU time
    const double window_s = 30.0 * 60.0 / 25252.0;
    double cpu_s = 0.0, busy_until_s = -1.0, now_s = 0.0;
    int fitted = 0, skipped = 0;
    for (int k = 1; k <= 40000; ++k) {  // ~47 min of windows
      now_s = k * window_s;
      if (now_s < busy_until_s || !b.allows(now_s)) {
        ++skipped;
        continue;
      }
      // The fit has the core to itself: wall time = CPU time.
      const double t = cost_s(rng);
      cpu_s += t;
      busy_until_s = now_s + t;
      b.fit_done(t, busy_until_s);
      ++fitted;
    }
    const double used = cpu_s / now_s;
    std::printf("budget %.2f: used %.4f of a core, %d fitted, %d skipped\n", fraction, used, fitted,
                skipped);
    EXPECT_LE(used, fraction * 1.01);
    // At most a window's wait after each rest is lost.
    EXPECT_GE(used, fraction * 0.8);
    EXPECT_GT(skipped, fitted);
  }
}

}  // namespace
}  // namespace millwatch::identify
