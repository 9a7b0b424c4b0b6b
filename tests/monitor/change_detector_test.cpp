#include "core/monitor/change_detector.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace millwatch::monitor {
namespace {

/// Mean run length of a one-sided CUSUM on N(shift, 1) input, by simulation.
double simulated_run_length(double k, double h, double shift, int runs, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> z(shift, 1.0);
  double total = 0.0;
  for (int r = 0; r < runs; ++r) {
    Cusum c(k, h);
    int n = 1;
    while (!c.update(z(rng))) {
      ++n;
    }
    total += n;
  }
  return total / runs;
}

// Siegmund's approximation against published exact values and against simulation.
TEST(Cusum, SiegmundRunLengthMatchesSimulation) {
  // k = 0.5, h = 4 and 5: in control, one-sided (Montgomery's table of the two-sided ARL gives
  // 168 and 465, i.e. 336 and 930 one-sided).
  EXPECT_NEAR(cusum_average_run_length(0.5, 4.0), 336.0, 0.03 * 336.0);
  EXPECT_NEAR(cusum_average_run_length(0.5, 5.0), 930.0, 0.03 * 930.0);
  const double in_control = simulated_run_length(0.5, 4.0, 0.0, 3000, 1);
  EXPECT_NEAR(in_control, cusum_average_run_length(0.5, 4.0), 0.08 * in_control);
  // Out of control: a shift of 1σ is found after ≈ 8.4 steps with h = 4.
  const double delay = simulated_run_length(0.5, 4.0, 1.0, 20000, 2);
  EXPECT_NEAR(delay, cusum_average_run_length(0.5, 4.0, 1.0), 0.1 * delay);
  // A large allowance: Siegmund underestimates the ARL, so designs with it are safe.
  EXPECT_LT(cusum_average_run_length(3.0, 0.0), 1.0 / (0.5 * std::erfc(3.0 / std::sqrt(2.0))));
}

TEST(Cusum, ThresholdForAnArlInvertsSiegmund) {
  for (const double k : {0.25, 0.5, 1.0, 2.0}) {
    for (const double arl : {100.0, 1e4, 4e5, 1e8}) {
      const double h = cusum_threshold_for(k, arl);
      if (h > 0.0) {
        EXPECT_NEAR(cusum_average_run_length(k, h), arl, 1e-6 * arl) << k << " " << arl;
      } else {
        EXPECT_GE(cusum_average_run_length(k, 0.0), arl);
      }
    }
  }
  EXPECT_NEAR(cusum_threshold_for(0.5, 4e5), 11.04, 0.01);  // the wear detector's default design
  EXPECT_EQ(cusum_threshold_for(10.0, 1e6), 0.0);
}

TEST(Cusum, RunCountsStepsSinceTheStatisticLeftZero) {
  Cusum c(0.5, 2.5);
  EXPECT_FALSE(c.update(-2.0));
  EXPECT_EQ(c.run(), 0);
  EXPECT_FALSE(c.update(1.5));
  EXPECT_FALSE(c.update(1.5));
  EXPECT_EQ(c.run(), 2);
  EXPECT_DOUBLE_EQ(c.statistic(), 2.0);
  EXPECT_TRUE(c.update(1.5));
  EXPECT_EQ(c.run(), 3);
  c.reset();
  EXPECT_EQ(c.statistic(), 0.0);
}

TEST(ChangeDetector, NormalQuantile) {
  EXPECT_NEAR(normal_upper_quantile(0.025), 1.959964, 1e-6);
  EXPECT_NEAR(normal_upper_quantile(0.5), 0.0, 1e-9);
  EXPECT_NEAR(normal_upper_quantile(1e-7), 5.199338, 1e-5);
}

TEST(ChangeDetector, RobustSummaryOfIidAndAr1SeriesWithOutliers) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> z(0.0, 1.0);
  const std::size_t n = 20000;
  std::vector<double> x(n), scratch(n);
  for (double& v : x) {
    v = 2.0 + 0.1 * z(rng);
  }
  for (std::size_t i = 0; i < n; i += 100) {
    x[i] = 50.0;  // 1 % wild values
  }
  RobustSummary s = robust_summary(x, scratch);
  EXPECT_NEAR(s.median, 2.0, 0.005);
  EXPECT_NEAR(s.sigma, 0.1, 0.005);
  EXPECT_NEAR(s.rho1, 0.0, 0.03);

  double e = 0.0;
  for (double& v : x) {
    e = 0.8 * e + std::sqrt(1.0 - 0.64) * z(rng);  // stationary σ = 1
    v = e;
  }
  s = robust_summary(x, scratch);
  EXPECT_NEAR(s.sigma, 1.0, 0.05);
  EXPECT_NEAR(s.rho1, 0.8, 0.02);
}

// The AR(1) figure for a block median's σ covers the simulated spread without being far above
// it. It is meant to be conservative: its long-run factor (1 + ρ)/(1 − ρ) exceeds the
// finite-block one (for ρ = 0.8 and 25 revolutions 9 against 7.4), which is what a CUSUM summing
// many correlated blocks sees.
TEST(ChangeDetector, BlockMedianSigmaOfAr1Noise) {
  std::mt19937_64 rng(4);
  std::normal_distribution<double> z(0.0, 1.0);
  const int block = 25;
  for (const double rho : {0.0, 0.5, 0.8}) {
    const int blocks = 4000;
    std::vector<double> x(static_cast<std::size_t>(block));
    std::vector<double> medians;
    double e = z(rng);
    for (int b = 0; b < blocks; ++b) {
      for (double& v : x) {
        e = rho * e + std::sqrt(1.0 - rho * rho) * z(rng);
        v = e;
      }
      medians.push_back(median_in_place(x));
    }
    double sum = 0.0, sum_sq = 0.0;
    for (const double m : medians) {
      sum += m;
      sum_sq += m * m;
    }
    const double simulated = std::sqrt(sum_sq / blocks - (sum / blocks) * (sum / blocks));
    const double predicted = ar1_block_median_sigma(1.0, rho, block);
    EXPECT_GE(predicted, 0.95 * simulated) << rho;
    EXPECT_LE(predicted, 1.4 * simulated) << rho;
  }
}

TEST(ChangeDetector, MedianInPlace) {
  std::vector<double> odd = {5.0, 1.0, 3.0};
  EXPECT_EQ(median_in_place(odd), 3.0);
  std::vector<double> even = {4.0, 1.0, 3.0, 2.0};
  EXPECT_EQ(median_in_place(even), 2.5);
  std::vector<double> none;
  EXPECT_EQ(median_in_place(none), 0.0);
}

// A step of the level (a runout that changed mid-cut) is one large difference among many: the
// scatter of 400 noisy values (σ 0.1; the MAD's sampling error ~8 %) is the noise's σ, with the
// step within 10 % of without it; three values give none.
TEST(ChangeDetector, SuccessiveScatterIsBlindToAStep) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 0.1);
  std::vector<double> steady, stepped;
  std::vector<double> scratch(400);
  for (int i = 0; i < 400; ++i) {
    const double e = noise(rng);
    steady.push_back(1.0 + e);
    stepped.push_back((i < 200 ? 1.0 : 5.0) + e);
  }
  const double without = successive_scatter(steady, scratch);
  EXPECT_NEAR(without, 0.1, 0.02);
  EXPECT_NEAR(successive_scatter(stepped, scratch), without, 0.1 * without);
  const std::vector<double> three{1.0, 2.0, 3.0};
  EXPECT_EQ(successive_scatter(three, scratch), 0.0);
}

}  // namespace
}  // namespace millwatch::monitor
