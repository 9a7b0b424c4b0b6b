// The revolution-synchronous average against analytic signals: a known function of the angle,
// sampled at angles that do not fall on the grid, averaged over windows of revolutions that
// follow one another.

#include "core/monitor/sync_average.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include "core/signal/cpu_features.hpp"
#include "tests/support/allocation_counter.hpp"

namespace millwatch::monitor {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
// Four channels: the pipeline's three and one more (any channel count averages alike).
using Average = SyncAverageOf<4>;

double shape(double angle, double scale) {
  return scale * (1.0 + 0.5 * std::cos(angle) + 0.3 * std::sin(3.0 * angle + 0.4));
}

/// Feeds `revolutions` revolutions of `samples_per_rev` samples (not a multiple of the bins,
/// so the samples land between bins) with amplitude `scale`.
void feed(Average& avg, int revolutions, double samples_per_rev, double scale, double& phase) {
  for (int r = 0; r < revolutions; ++r) {
    while (phase < kTwoPi) {
      avg.add(phase, {shape(phase, scale), -shape(phase, scale), 0.5 * scale, scale});
      phase += kTwoPi / samples_per_rev;
    }
    phase -= kTwoPi;
    avg.end_revolution();
  }
}

// The average equals the function at the bins within the linear-interpolation error, for every
// channel; once a window is full, the next revolution starts a new one, and the average is then
// that window's alone, however far it has filled.
TEST(SyncAverage, RecoversAKnownRevolutionAndStartsAWindowOnceFull) {
  const int bins = 128;
  Average avg(bins, 10);
  double phase = 0.123;
  feed(avg, 10, 517.3, 1.0, phase);
  EXPECT_EQ(avg.revolutions(), 10);
  double worst = 0.0;
  for (int k = 0; k < bins; ++k) {
    const double a = kTwoPi * k / bins;
    worst = std::max(worst, std::fabs(avg.average(0, k) - shape(a, 1.0)));
    EXPECT_NEAR(avg.average(1, k), -avg.average(0, k), 1e-12);
    EXPECT_NEAR(avg.average(2, k), 0.5, 1e-12);
  }
  // Samples share their weight between the two nearest bins: the error is of the order of the
  // curvature times (bin width)² — here about 5e-4 of the signal.
  EXPECT_LT(worst, 2e-3);
  // Five revolutions at twice the level: a new window of five, none of the first ten in it.
  feed(avg, 5, 517.3, 2.0, phase);
  EXPECT_EQ(avg.revolutions(), 5);
  EXPECT_NEAR(avg.average(3, 17), 2.0, 1e-12);
  // Five more fill it; three at three times the level start the next.
  feed(avg, 5, 517.3, 2.0, phase);
  EXPECT_EQ(avg.revolutions(), 10);
  EXPECT_NEAR(avg.average(3, 17), 2.0, 1e-12);
  std::vector<double> out;
  avg.average(0, out);
  ASSERT_EQ(out.size(), static_cast<std::size_t>(bins));
  EXPECT_NEAR(out[40], shape(kTwoPi * 40 / bins, 2.0), 4e-3);
  feed(avg, 3, 517.3, 3.0, phase);
  EXPECT_EQ(avg.revolutions(), 3);
  EXPECT_NEAR(avg.average(3, 17), 3.0, 1e-12);
  // A revolution without samples after a full window starts one too: an empty window of one.
  feed(avg, 7, 517.3, 3.0, phase);
  avg.end_revolution();
  EXPECT_EQ(avg.revolutions(), 1);
  EXPECT_EQ(avg.average(3, 17), 0.0);
  avg.clear();
  EXPECT_EQ(avg.revolutions(), 0);
  EXPECT_EQ(avg.average(0, 5), 0.0);
}

// A grid finer than one revolution's samples: the bins no sample reached in a revolution fill
// in over several; bins none reached take their neighbours' mean.
TEST(SyncAverage, FillsAFineGridOverSeveralRevolutions) {
  Average avg(256, 30);
  std::vector<double> out;
  double phase = 0.0;
  for (int r = 0; r < 30; ++r) {
    // 97 samples per revolution, phase advancing by an irrational fraction each turn.
    for (int n = 0; n < 97; ++n) {
      const double a = std::fmod(phase + kTwoPi * n / 97.0, kTwoPi);
      avg.add(a, {std::sin(a), 0.0, 0.0, 1.0});
    }
    avg.end_revolution();
    phase = std::fmod(phase + kTwoPi * 0.618034 / 97.0, kTwoPi);
  }
  avg.average(0, out);
  double worst = 0.0;
  for (int k = 0; k < 256; ++k) {
    worst =
        std::max(worst, std::fabs(out[static_cast<std::size_t>(k)] - std::sin(kTwoPi * k / 256)));
  }
  EXPECT_LT(worst, 0.02);
}

// A line of samples (add_line) gives the sums that adding them one by one at their wrapped
// angles gives: samples sparser than the bins (2.15 bins apart, the pipeline's 50 kHz case) and
// denser (0.97 apart, its 333.3 kHz case; 0.31: runs of three or four in two bins), a line
// starting below zero and crossing 2π; and lines no spindle makes (backwards, over a turn a step).
TEST(SyncAverage, ALineOfSamplesGivesTheSumsOfAddingThemOneByOne) {
  for (const double bins_per_sample : {2.15, 0.97, 1.0, 0.31, -0.8, 300.5}) {
    Average line(256, 4);
    Average one_by_one(256, 4);
    const double first_bin = -3.7123;  // no sample on a bin (a weight of 1e-14 there)
    const auto count = std::max<std::size_t>(
        40, static_cast<std::size_t>(std::ceil(260.0 / std::fabs(bins_per_sample))));
    const auto values = [](std::size_t i) {
      const double x = 0.01 * static_cast<double>(i);
      return std::array<double, Average::kChannels>{std::sin(x), std::cos(x), x, 1.0 + x};
    };
    line.add_line(count, first_bin, bins_per_sample, values);
    for (std::size_t i = 0; i < count; ++i) {
      const double bin = first_bin + bins_per_sample * static_cast<double>(i);
      const double wrapped = bin - 256.0 * std::floor(bin / 256.0);
      one_by_one.add(kTwoPi * wrapped / 256.0, values(i));
    }
    line.end_revolution();
    one_by_one.end_revolution();
    for (int c = 0; c < Average::kChannels; ++c) {
      for (int k = 0; k < 256; ++k) {
        ASSERT_NEAR(line.average(c, k), one_by_one.average(c, k), 1e-9)
            << bins_per_sample << " channel " << c << " bin " << k;
      }
    }
  }
}

// The pipeline's three channels read from rows of four (the ring's: fx, fy, fz, fx² + fy²):
// add_line_rows() gives exactly add_line()'s sums and weights, bit for bit, with its AVX kernel
// and without, on sparse lines (2.15, 1.0 bins a sample: the AVX kernel's sparse loop), dense
// ones (0.97, 0.31, 0: its runs), lines crossing 2π and lines no spindle makes, revolution after
// revolution of a window. Skipped where the CPU has no AVX, once the fallback is compared.
TEST(SyncAverage, RowsOfFourGiveTheSumsOfAddLineBitForBit) {
  using Three = SyncAverageOf<3>;
  const auto bits = [](double x) { return std::bit_cast<std::uint64_t>(x); };
  for (const double bins_per_sample : {2.15, 0.97, 1.0, 0.31, 0.0, -0.8, 300.5}) {
    for (const bool avx : {true, false}) {
      Three from_rows(256, 3);
      Three from_values(256, 3);
      from_rows.set_avx(avx);
      from_values.set_avx(false);
      ASSERT_EQ(from_rows.avx(), avx && signal::cpu_has_avx());
      std::vector<double> ring;  // rows of four; the fourth must not reach the sums
      for (int r = 0; r < 5; ++r) {
        const double first_bin = -3.7123 + 251.3 * r;
        const auto count = std::max<std::size_t>(
            40, static_cast<std::size_t>(std::ceil(260.0 / std::fabs(bins_per_sample + 1e-3))));
        ring.assign(4 * count, 0.0);
        for (std::size_t i = 0; i < count; ++i) {
          const double x = 0.01 * static_cast<double>(i) + r;
          ring[4 * i] = std::sin(x);
          ring[4 * i + 1] = -std::cos(3.0 * x);
          ring[4 * i + 2] = 1e-3 * x - 0.5;
          ring[4 * i + 3] = 1e6 + x;
        }
        from_rows.add_line_rows(count, first_bin, bins_per_sample,
                                [&](std::size_t i) { return &ring[4 * i]; });
        from_values.add_line(count, first_bin, bins_per_sample, [&](std::size_t i) {
          return Three::Values{ring[4 * i], ring[4 * i + 1], ring[4 * i + 2]};
        });
        from_rows.end_revolution();
        from_values.end_revolution();
        for (int k = 0; k < 256; ++k) {
          const auto got = from_rows.window_sums(k);
          const auto want = from_values.window_sums(k);
          for (std::size_t c = 0; c < got.size(); ++c) {
            ASSERT_EQ(bits(got[c]), bits(want[c]))
                << bins_per_sample << (from_rows.avx() ? " AVX" : " fallback") << " revolution "
                << r << " bin " << k << " sum " << c << ": " << got[c] << " against " << want[c];
          }
        }
      }
    }
  }
  if (!signal::cpu_has_avx()) {
    GTEST_SKIP() << "this CPU has no AVX: only add_line_rows()'s fallback was compared";
  }
}

TEST(SyncAverage, AddingAndClosingAllocateNothing) {
  Average avg(256, 30);
  double phase = 0.0;
  feed(avg, 3, 300.0, 1.0, phase);
  test::AllocationCounter counter;
  feed(avg, 40, 300.0, 1.0, phase);
  EXPECT_EQ(counter.allocations(), 0);
}

}  // namespace
}  // namespace millwatch::monitor
