// When the alerts stop waiting for identified estimates: three windows without an accepted one
// when no budget applies; with a CPU budget, windows skipped on purpose between fits do not make
// them fall back while the last estimate is younger than three budget periods plus three windows
// — and they do fall back once it is older (fits rejected, or none coming).

#include "core/identify/estimate_watch.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

namespace millwatch::identify {
namespace {

constexpr double kWindow_s = 30.0 * 60.0 / 25252.0;  // 30 revolutions at 25,252 rpm

std::int64_t end_of_window_us(int k) {
  return static_cast<std::int64_t>(std::llround(1e6 * kWindow_s * k));
}

TEST(EstimateWatch, WithoutABudgetThreeWindowsWithoutAnEstimate) {
  EstimateWatch w;
  EXPECT_FALSE(w.window_submitted(end_of_window_us(1), kWindow_s, 0.0));
  EXPECT_FALSE(w.window_submitted(end_of_window_us(2), kWindow_s, 0.0));
  w.estimate_accepted(end_of_window_us(1));
  EXPECT_FALSE(w.window_submitted(end_of_window_us(3), kWindow_s, 0.0));
  EXPECT_FALSE(w.window_submitted(end_of_window_us(4), kWindow_s, 0.0));
  EXPECT_TRUE(w.window_submitted(end_of_window_us(5), kWindow_s, 0.0));  // the third
  EXPECT_EQ(w.windows_without_estimate(), 3);
}

// A live run with a budget of 0.02 and fits of 0.4 s of CPU: one window in ~20 s is fitted, the
// ~280 windows in between are skipped on purpose; each accepted estimate arrives about a fit
// after its window. From the first estimate on the alerts keep the estimates; when the fits stop
// being accepted they fall back after three budget periods and three windows, not before.
TEST(EstimateWatch, WindowsSkippedForTheBudgetKeepARecentEstimate) {
  const double fit_cpu_s = 0.4;
  const double budget = 0.02;
  const double period_s = fit_cpu_s / budget;  // the identifier's budget_period_s()
  const int windows_per_period = static_cast<int>(std::ceil(period_s / kWindow_s));
  EstimateWatch w;
  int fallbacks = 0;
  int k = 1;
  int accepted_window = 0;
  for (int fit = 0; fit < 5; ++fit) {
    const int fitted = k;  // the first window after the rest
    for (int i = 0; i < windows_per_period; ++i, ++k) {
      const bool fall_back = w.window_submitted(end_of_window_us(k), kWindow_s, period_s);
      // Before the first estimate the count decides (the last test): from it on, never.
      fallbacks += fall_back && accepted_window > 0 ? 1 : 0;
      // The result comes ~0.4 s (6 windows) after the fitted window ends.
      if (k == fitted + 6) {
        w.estimate_accepted(end_of_window_us(fitted));
        accepted_window = fitted;
      }
    }
  }
  EXPECT_EQ(fallbacks, 0);
  EXPECT_GT(w.windows_without_estimate(), EstimateWatch::kChances);  // windows alone would flip

  // From now on every fit is rejected: the last estimate ages.
  const double limit_s = EstimateWatch::kChances * (period_s + kWindow_s);
  int first_fallback = 0;
  for (; k < 100000 && first_fallback == 0; ++k) {
    if (w.window_submitted(end_of_window_us(k), kWindow_s, period_s)) {
      first_fallback = k;
    }
  }
  ASSERT_GT(first_fallback, 0);
  const double age_s = 1e-6 * static_cast<double>(end_of_window_us(first_fallback) -
                                                  end_of_window_us(accepted_window));
  EXPECT_GT(age_s, limit_s);
  EXPECT_LE(age_s, limit_s + kWindow_s);  // the first window past the limit
}

TEST(EstimateWatch, WithABudgetButNoEstimateYetTheCountDecides) {
  EstimateWatch w;
  EXPECT_FALSE(w.window_submitted(end_of_window_us(1), kWindow_s, 20.0));
  EXPECT_FALSE(w.window_submitted(end_of_window_us(2), kWindow_s, 20.0));
  EXPECT_TRUE(w.window_submitted(end_of_window_us(3), kWindow_s, 20.0));
}

}  // namespace
}  // namespace millwatch::identify
