#include "core/model/periodic_response.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "core/model/dynamometer.hpp"
#include "core/signal/butterworth_lowpass.hpp"
#include "tests/support/allocation_counter.hpp"

namespace millwatch::model {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

/// A spiky periodic waveform (like a cutting force): a half-wave rectified sine plus a step.
std::vector<double> spiky(int n) {
  std::vector<double> x(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const double phi = kTwoPi * i / n;
    x[static_cast<std::size_t>(i)] = std::max(0.0, std::sin(2.0 * phi)) + (i < n / 3 ? 0.3 : 0.0);
  }
  return x;
}

// Each harmonic k comes out times gains[k]: cos(k·φ + a) → |g|·cos(k·φ + a + arg g).
TEST(PeriodicResponse, ScalesAndShiftsEachHarmonic) {
  const int n = 90;
  PeriodicResponse r(n);
  std::vector<std::complex<double>> gains(static_cast<std::size_t>(r.harmonics()));
  for (std::size_t k = 0; k < gains.size(); ++k) {
    gains[k] =
        std::polar(1.0 / (1.0 + 0.1 * static_cast<double>(k)), -0.05 * static_cast<double>(k));
  }
  gains[0] = 0.7;
  std::vector<double> x(static_cast<std::size_t>(n));
  const std::array<int, 3> harmonic = {3, 7, 20};
  const std::array<double, 3> amplitude = {1.0, 0.5, 0.25};
  const std::array<double, 3> phase = {0.3, -1.0, 2.0};
  for (int i = 0; i < n; ++i) {
    double v = 2.0;  // DC
    for (int h = 0; h < 3; ++h) {
      v += amplitude[h] * std::cos(kTwoPi * harmonic[h] * i / n + phase[h]);
    }
    x[static_cast<std::size_t>(i)] = v;
  }
  r.apply(x, gains);
  for (int i = 0; i < n; ++i) {
    double expected = 2.0 * 0.7;
    for (int h = 0; h < 3; ++h) {
      const std::complex<double> g = gains[static_cast<std::size_t>(harmonic[h])];
      expected += amplitude[h] * std::abs(g) *
                  std::cos(kTwoPi * harmonic[h] * i / n + phase[h] + std::arg(g));
    }
    ASSERT_NEAR(x[static_cast<std::size_t>(i)], expected, 1e-12) << i;
  }
}

// The frequency-domain steady state equals a discrete filter run sample by sample until its
// start-up transient has died away (the filter's sample rate is N·f₀: exact).
TEST(PeriodicResponse, EqualsTheSettledTimeDomainResonance) {
  const int n = 240;
  const double f0 = 400.0;  // a 24,000 rpm revolution
  const double fs = n * f0;
  const Resonance design(2145.0, 0.05, fs);
  Resonance filter = design;
  const std::vector<double> x = spiky(n);
  std::vector<double> settled(static_cast<std::size_t>(n));
  for (int period = 0; period < 400; ++period) {  // the envelope decays as e^(−t/6.7 ms)
    for (int i = 0; i < n; ++i) {
      settled[static_cast<std::size_t>(i)] = filter.step(x[static_cast<std::size_t>(i)]);
    }
  }
  std::vector<double> y = x;
  PeriodicResponse r(n);
  r.apply(y, f0, [&](double f) { return design.response(f); });
  for (int i = 0; i < n; ++i) {
    ASSERT_NEAR(y[static_cast<std::size_t>(i)], settled[static_cast<std::size_t>(i)], 1e-9) << i;
  }
}

// The monitor's use: the causal Butterworth's steady state (H), and forwards + backwards (|H|²)
// which is what filtfilt gives in the middle of a long periodic record.
TEST(PeriodicResponse, ButterworthCausalAndZeroPhaseMatchTheTimeDomainFilters) {
  const int n = 125;  // 50 kHz at 400 Hz spindle
  const double f0 = 400.0;
  const auto design = signal::ButterworthDesign::lowpass(n * f0, 3300.0, 4);
  const std::vector<double> x = spiky(n);
  const int periods = 60;
  std::vector<double> record;
  for (int p = 0; p < periods; ++p) {
    record.insert(record.end(), x.begin(), x.end());
  }
  signal::LowPassFilter causal(design);
  std::vector<double> out(record.size());
  causal.process(record, out);
  std::vector<double> both(record.size());
  signal::filtfilt(design, record, both);

  std::vector<double> y = x;
  std::vector<double> z = x;
  PeriodicResponse r(n);
  r.apply(
      y, f0, [&](double f) { return design.response(f); }, ResponseUse::kComplex);
  r.apply(
      z, f0, [&](double f) { return design.response(f); }, ResponseUse::kPower);
  const std::size_t last = static_cast<std::size_t>((periods - 1) * n);
  const std::size_t middle = static_cast<std::size_t>((periods / 2) * n);
  for (std::size_t i = 0; i < static_cast<std::size_t>(n); ++i) {
    ASSERT_NEAR(y[i], out[last + i], 1e-9) << i;
    ASSERT_NEAR(z[i], both[middle + i], 1e-9) << i;
  }
}

// |H| keeps the waveform's timing: a symmetric pulse stays symmetric about the same centre.
TEST(PeriodicResponse, MagnitudeOnlyKeepsSymmetry) {
  const int n = 200;
  std::vector<double> x(static_cast<std::size_t>(n), 0.0);
  for (int i = 90; i <= 110; ++i) {
    x[static_cast<std::size_t>(i)] = 1.0 - std::fabs(i - 100) / 11.0;
  }
  const Resonance design(2000.0, 0.1, n * 400.0);
  PeriodicResponse r(n);
  r.apply(
      x, 400.0, [&](double f) { return design.response(f); }, ResponseUse::kMagnitude);
  for (int d = 1; d < 100; ++d) {
    ASSERT_NEAR(x[static_cast<std::size_t>(100 + d)], x[static_cast<std::size_t>(100 - d)], 1e-12);
  }
}

// An even length's Nyquist harmonic (−1)ⁿ is a real cosine: only Re(g) acts on it.
TEST(PeriodicResponse, NyquistHarmonicTakesTheRealPartOfItsGain) {
  const int n = 16;
  std::vector<double> x(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    x[static_cast<std::size_t>(i)] = i % 2 == 0 ? 1.0 : -1.0;
  }
  PeriodicResponse r(n);
  std::vector<std::complex<double>> gains(static_cast<std::size_t>(r.harmonics()), 1.0);
  gains.back() = std::polar(2.0, 1.0);
  r.apply(x, gains);
  for (int i = 0; i < n; ++i) {
    EXPECT_NEAR(x[static_cast<std::size_t>(i)], (i % 2 == 0 ? 1.0 : -1.0) * 2.0 * std::cos(1.0),
                1e-12);
  }
}

TEST(PeriodicResponse, ApplyAllocatesNothingAndChecksSizes) {
  PeriodicResponse r(720);
  std::vector<double> x = spiky(720);
  std::vector<std::complex<double>> gains(static_cast<std::size_t>(r.harmonics()), 0.5);
  const Resonance design(2145.0, 0.05, 720 * 416.0);
  test::AllocationCounter counter;
  r.apply(x, gains);
  r.apply(x, 416.0, [&](double f) { return design.response(f); });
  r.apply(
      x, 416.0, [&](double f) { return resonance_response(2145.0, 0.05, f); }, ResponseUse::kPower);
  EXPECT_EQ(counter.allocations(), 0);
  std::vector<double> wrong(719);
  EXPECT_THROW(r.apply(wrong, gains), std::invalid_argument);
  EXPECT_THROW(r.apply(x, std::span<const std::complex<double>>(gains).first(10)),
               std::invalid_argument);
  EXPECT_THROW(PeriodicResponse(1), std::invalid_argument);
  PeriodicResponse empty;
  EXPECT_THROW(empty.apply(x, gains), std::invalid_argument);
}

// The continuous resonance: unit gain at DC, 1/(2ζ) and −90° at f_n, |H| = 1/√((1−u²)² + (2ζu)²).
TEST(Resonance, ContinuousResponseIsTheSecondOrderSystem) {
  EXPECT_NEAR(std::abs(resonance_response(2145.0, 0.05, 0.0)), 1.0, 1e-15);
  EXPECT_NEAR(std::abs(resonance_response(2145.0, 0.05, 2145.0)), 10.0, 1e-12);
  EXPECT_NEAR(std::arg(resonance_response(2145.0, 0.05, 2145.0)), -std::numbers::pi / 2, 1e-12);
  const double u = 800.0 / 2145.0;
  EXPECT_NEAR(std::abs(resonance_response(2145.0, 0.05, 800.0)),
              1.0 / std::sqrt((1 - u * u) * (1 - u * u) + 0.01 * u * u), 1e-12);
  // The discrete (bilinear, pre-warped) response far below fs/2 agrees closely.
  const Resonance discrete(2145.0, 0.05, 300000.0);
  EXPECT_NEAR(std::abs(discrete.response(800.0)), std::abs(resonance_response(2145.0, 0.05, 800.0)),
              1e-4);
}

}  // namespace
}  // namespace millwatch::model
