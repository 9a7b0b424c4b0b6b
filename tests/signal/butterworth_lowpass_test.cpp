#include "core/signal/butterworth_lowpass.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "tests/support/allocation_counter.hpp"

namespace millwatch::signal {
namespace {

constexpr double kPi = std::numbers::pi;

// |H|² = 1/(1 + (tan(ω/2)/tan(ω_c/2))^{2n}): the bilinear Butterworth, exactly.
TEST(ButterworthLowPass, MagnitudeMatchesTheAnalyticResponse) {
  for (double fs : {20000.0, 50000.0, 333300.0}) {
    for (int order = 1; order <= 8; ++order) {
      const auto d = ButterworthDesign::lowpass(fs, 3300.0, order);
      const double tc = std::tan(kPi * 3300.0 / fs);
      for (double f = 10.0; f < 0.49 * fs; f *= 1.37) {
        const double ratio = std::tan(kPi * f / fs) / tc;
        const double expected = 1.0 / std::sqrt(1.0 + std::pow(ratio, 2.0 * order));
        EXPECT_NEAR(std::abs(d.response(f)), expected, 1e-9 + 1e-9 * expected)
            << "fs " << fs << " order " << order << " f " << f;
      }
      EXPECT_NEAR(20.0 * std::log10(std::abs(d.response(3300.0))), -3.0103, 1e-3);
      EXPECT_NEAR(std::abs(d.response(0.0)), 1.0, 1e-12);
    }
  }
}

std::vector<double> tone(double f, double fs, std::size_t n, double phase = 0.0) {
  std::vector<double> x(n);
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = std::sin(2 * kPi * f * static_cast<double>(i) / fs + phase);
  }
  return x;
}

// A steady tone comes out scaled by |H| and lagging by the phase delay.
TEST(ButterworthLowPass, SteadySineHasTheResponsesAmplitudeAndPhase) {
  const double fs = 50000.0;
  const auto d = ButterworthDesign::lowpass(fs, 3300.0, 4);
  for (double f : {420.0, 842.0, 2500.0, 5000.0}) {
    const auto x = tone(f, fs, 50000);
    std::vector<double> y(x.size());
    LowPassFilter lp(d);
    lp.process(x, y);
    // Fit y over the last half to a·sin + b·cos.
    double ss = 0, cc = 0, sc = 0, ys = 0, yc = 0;
    for (std::size_t i = x.size() / 2; i < x.size(); ++i) {
      const double t = 2 * kPi * f * static_cast<double>(i) / fs;
      ss += std::sin(t) * std::sin(t);
      cc += std::cos(t) * std::cos(t);
      sc += std::sin(t) * std::cos(t);
      ys += y[i] * std::sin(t);
      yc += y[i] * std::cos(t);
    }
    const double det = ss * cc - sc * sc;
    const double a = (ys * cc - yc * sc) / det;
    const double b = (yc * ss - ys * sc) / det;
    EXPECT_NEAR(std::hypot(a, b), std::abs(d.response(f)), 1e-6) << f;
    EXPECT_NEAR(std::atan2(b, a), std::arg(d.response(f)), 1e-6) << f;
    // The phase delay is that lag in time.
    const double lag_s = -std::remainder(std::atan2(b, a), 2 * kPi) / (2 * kPi * f);
    EXPECT_NEAR(std::remainder(lag_s - d.phase_delay_s(f), 1.0 / f), 0.0, 1e-9) << f;
  }
}

// The group delay from the coefficients agrees with the derivative of the phase and with the
// delay of a narrow-band pulse's envelope.
TEST(ButterworthLowPass, GroupDelayMatchesPhaseSlopeAndPulseEnvelope) {
  const double fs = 50000.0;
  const auto d = ButterworthDesign::lowpass(fs, 3300.0, 4);
  for (double f : {100.0, 842.0, 2000.0, 3000.0}) {
    const double df = 0.01;
    const double slope =
        std::arg(d.response(f + df) / d.response(f - df)) / (2 * 2 * kPi * df / fs);
    EXPECT_NEAR(d.group_delay_samples(f), -slope, 1e-5 * std::fabs(slope)) << f;
  }
  // Gaussian-modulated 842 Hz tone: the envelope peak moves by the group delay there.
  const double f0 = 842.0;
  const double t0 = 0.05;
  const double width = 0.004;  // narrow band: ±~100 Hz
  std::vector<double> x(10000), y(10000);
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double t = static_cast<double>(i) / fs;
    x[i] = std::exp(-0.5 * std::pow((t - t0) / width, 2)) * std::cos(2 * kPi * f0 * t);
  }
  LowPassFilter lp(d);
  lp.process(x, y);
  // Envelope by demodulation and a centroid of |y|² around the peak.
  double num = 0.0, den = 0.0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    const double t = static_cast<double>(i) / fs;
    const double e2 = y[i] * y[i];
    num += t * e2;
    den += e2;
  }
  EXPECT_NEAR(num / den - t0, d.group_delay_s(f0), 2e-6);
}

TEST(ButterworthLowPass, BlockSizeDoesNotChangeTheOutput) {
  const auto d = ButterworthDesign::lowpass(333300.0, 3300.0, 4);
  std::vector<double> x(20000);
  for (std::size_t i = 0; i < x.size(); ++i) {
    x[i] = std::sin(0.01 * static_cast<double>(i)) + 0.3 * std::sin(0.7 * static_cast<double>(i));
  }
  std::vector<double> whole(x.size());
  LowPassFilter one(d);
  one.process(x, whole);
  for (std::size_t block : {1u, 7u, 1000u}) {
    LowPassFilter f(d);
    std::vector<double> y(x.size());
    for (std::size_t i = 0; i < x.size(); i += block) {
      const std::size_t n = std::min(block, x.size() - i);
      f.process(std::span(x).subspan(i, n), std::span(y).subspan(i, n));
    }
    EXPECT_EQ(y, whole) << block;
  }
}

TEST(ButterworthLowPass, SettleRemovesTheStartUpTransient) {
  const auto d = ButterworthDesign::lowpass(50000.0, 3300.0, 5);
  LowPassFilter f(d);
  f.settle(2.5);
  for (int i = 0; i < 100; ++i) {
    EXPECT_NEAR(f.step(2.5), 2.5, 1e-12);
  }
}

// Zero phase: a symmetric pulse stays symmetric about the same centre, a slow tone is not
// shifted, the ends of a constant stay flat.
TEST(ButterworthLowPass, FiltfiltHasZeroPhase) {
  const double fs = 50000.0;
  const auto d = ButterworthDesign::lowpass(fs, 3300.0, 4);
  std::vector<double> pulse(4001, 0.0);
  for (std::size_t i = 0; i < pulse.size(); ++i) {
    const double u = (static_cast<double>(i) - 2000.0) / 40.0;
    pulse[i] = std::exp(-0.5 * u * u);
  }
  std::vector<double> y(pulse.size());
  filtfilt(d, pulse, y);
  const auto peak = std::max_element(y.begin(), y.end()) - y.begin();
  EXPECT_EQ(peak, 2000);
  for (int k = 1; k < 500; ++k) {
    EXPECT_NEAR(y[static_cast<std::size_t>(2000 + k)], y[static_cast<std::size_t>(2000 - k)], 1e-9);
  }
  const auto slow = tone(300.0, fs, 20000, 0.4);
  std::vector<double> ys(slow.size());
  filtfilt(d, slow, ys);
  for (std::size_t i = 2000; i < 18000; ++i) {
    EXPECT_NEAR(ys[i], slow[i] * std::norm(d.response(300.0)), 1e-6);
  }
  std::vector<double> flat(3000, -1.7), yf(3000);
  filtfilt(d, flat, yf);
  for (double v : yf) {
    EXPECT_NEAR(v, -1.7, 1e-9);
  }
}

TEST(ButterworthLowPass, ProcessAllocatesNothing) {
  LowPassFilter f(ButterworthDesign::lowpass(50000.0, 3300.0, 4));
  std::vector<double> x(4096, 1.0), y(4096);
  test::AllocationCounter counter;
  f.process(x, y);
  f.process(y, y);
  EXPECT_EQ(counter.allocations(), 0);
}

TEST(ButterworthLowPass, InvalidArgumentsNameTheParameter) {
  auto message = [](auto f) {
    try {
      f();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(message([] { ButterworthDesign::lowpass(50000.0, 30000.0); }).find("cutoff_hz"),
            std::string::npos);
  EXPECT_NE(message([] { ButterworthDesign::lowpass(-1.0, 300.0); }).find("sample_rate_hz"),
            std::string::npos);
  EXPECT_NE(message([] { ButterworthDesign::lowpass(50000.0, 300.0, 9); }).find("order"),
            std::string::npos);
}

}  // namespace
}  // namespace millwatch::signal
