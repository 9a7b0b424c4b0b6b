#include "core/signal/zero_phase_filter.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

#include "tests/support/allocation_counter.hpp"

namespace millwatch::signal {
namespace {

/// Runs `x` (one channel) through the streaming stage; returns the output in input order.
std::vector<double> stream(const ButterworthDesign& d, const std::vector<double>& x,
                           std::size_t chunk = 0) {
  ZeroPhaseFilter z(d, 1, chunk);
  std::vector<double> out;
  auto take = [&](std::size_t ready) {
    for (std::size_t i = 0; i < ready; ++i) {
      out.push_back(z.output(0, i));
    }
  };
  for (const double v : x) {
    take(z.push({&v, 1}));
  }
  take(z.flush());
  return out;
}

/// A milling-like force: tooth-passing harmonics, a DC level and white noise.
std::vector<double> force_like(double fs_hz, std::size_t n) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.05);
  std::vector<double> x(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) / fs_hz;
    const double phase = 2.0 * std::numbers::pi * 841.7 * t;
    x[i] = 0.6 + std::max(0.0, std::sin(phase)) + 0.2 * std::sin(3.0 * phase + 0.4) + noise(rng);
  }
  return x;
}

TEST(ZeroPhaseFilter, EqualsWholeRecordFiltfiltEndsIncluded) {
  for (const double fs_hz : {50000.0, 333300.0}) {
    const auto d = ButterworthDesign::lowpass(fs_hz, 3300.0, 4);
    const std::vector<double> x = force_like(fs_hz, 100000);
    std::vector<double> reference(x.size());
    filtfilt(d, x, reference);
    const std::vector<double> z = stream(d, x);
    ASSERT_EQ(z.size(), x.size());
    double worst = 0.0;
    for (std::size_t i = 0; i < x.size(); ++i) {
      worst = std::max(worst, std::abs(z[i] - reference[i]));
    }
    EXPECT_LT(worst, 1e-9) << fs_hz;
  }
}

TEST(ZeroPhaseFilter, AStretchShorterThanThePaddingIsFilteredAsFiltfiltDoes) {
  const auto d = ButterworthDesign::lowpass(333300.0, 3300.0, 4);
  const std::vector<double> x = force_like(333300.0, 40);  // filtfilt pads with 39 samples
  std::vector<double> reference(x.size());
  filtfilt(d, x, reference);
  const std::vector<double> z = stream(d, x);
  ASSERT_EQ(z.size(), x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    EXPECT_NEAR(z[i], reference[i], 1e-9) << i;
  }
}

TEST(ZeroPhaseFilter, OutputDoesNotDependOnTheChunkSize) {
  const auto d = ButterworthDesign::lowpass(50000.0, 3300.0, 4);
  const std::vector<double> x = force_like(50000.0, 30000);
  const std::vector<double> a = stream(d, x, 500);
  const std::vector<double> b = stream(d, x, 7777);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_NEAR(a[i], b[i], 1e-10) << i;
  }
}

TEST(ZeroPhaseFilter, KeepsASymmetricPulseCentredWhereTheCausalFilterDelaysIt) {
  const double fs_hz = 50000.0;
  const auto d = ButterworthDesign::lowpass(fs_hz, 3300.0, 4);
  std::vector<double> x(4000, 0.0);
  const double centre = 2000.3;  // between samples
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double u = (static_cast<double>(i) - centre) / 12.0;
    x[i] = std::exp(-0.5 * u * u);
  }
  auto peak = [](const std::vector<double>& y) {
    const auto k = static_cast<std::size_t>(std::max_element(y.begin(), y.end()) - y.begin());
    // Parabola through the three samples around the maximum.
    const double den = y[k - 1] - 2.0 * y[k] + y[k + 1];
    return static_cast<double>(k) + 0.5 * (y[k - 1] - y[k + 1]) / den;
  };
  const std::vector<double> z = stream(d, x);
  EXPECT_NEAR(peak(z), centre, 0.02);
  std::vector<double> causal(x.size());
  LowPassFilter f(d);
  f.process(x, causal);
  EXPECT_GT(peak(causal) - centre, 0.5 * d.group_delay_samples(0.0));
}

TEST(ZeroPhaseFilter, StretchesAreIndependentAndChannelsShareTheTiming) {
  const auto d = ButterworthDesign::lowpass(50000.0, 3300.0, 4);
  const std::vector<double> a = force_like(50000.0, 9000);
  std::vector<double> b(a.size());
  std::transform(a.begin(), a.end(), b.begin(), [](double v) { return -2.0 * v + 5.0; });
  ZeroPhaseFilter z(d, 2, 1000);
  std::vector<double> first, second;
  auto run = [&](std::vector<double>& out) {
    auto take = [&](std::size_t ready) {
      for (std::size_t i = 0; i < ready; ++i) {
        out.push_back(z.output(0, i));
        EXPECT_NEAR(z.output(1, i), -2.0 * z.output(0, i) + 5.0, 1e-9);
      }
    };
    for (std::size_t i = 0; i < a.size(); ++i) {
      const std::array<double, 2> s = {a[i], b[i]};
      take(z.push(s));
    }
    take(z.flush());
  };
  run(first);
  run(second);  // after flush, a new stretch: the same input gives the same output
  ASSERT_EQ(first.size(), a.size());
  ASSERT_EQ(second.size(), a.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_NEAR(first[i], second[i], 1e-12);
  }
}

TEST(ZeroPhaseFilter, PushAllocatesNothingAfterSetup) {
  const auto d = ButterworthDesign::lowpass(333300.0, 3300.0, 4);
  ZeroPhaseFilter z(d, 3);
  const std::vector<double> x = force_like(333300.0, 3 * z.chunk_samples());
  std::vector<double> out0(x.size()), out2(x.size());
  std::size_t emitted = 0;
  auto take = [&](std::size_t ready) {
    for (std::size_t i = 0; i < ready; ++i, ++emitted) {
      out0[emitted] = z.output(0, i);
      out2[emitted] = z.output(2, i);
    }
  };
  test::AllocationCounter counter;
  for (const double v : x) {
    const std::array<double, 3> s = {v, -v, 0.5 * v};
    take(z.push(s));
  }
  take(z.flush());
  EXPECT_EQ(counter.allocations(), 0);
  ASSERT_EQ(emitted, x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    ASSERT_NEAR(out2[i], 0.5 * out0[i], 1e-12);  // linear, channels independent
  }
}

TEST(ZeroPhaseFilter, RejectsAWrongNumberOfChannels) {
  const auto d = ButterworthDesign::lowpass(50000.0, 3300.0, 4);
  EXPECT_THROW(ZeroPhaseFilter(d, 0), std::invalid_argument);
  ZeroPhaseFilter z(d, 3);
  const std::array<double, 2> two = {1.0, 2.0};
  EXPECT_THROW(z.push(two), std::invalid_argument);
  ZeroPhaseFilter none;
  EXPECT_THROW(none.push(two), std::invalid_argument);
}

}  // namespace
}  // namespace millwatch::signal
