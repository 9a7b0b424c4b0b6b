#include "core/signal/welch_spectrum.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

namespace millwatch::signal {
namespace {

constexpr double kPi = std::numbers::pi;

/// c + a·cos(2π·f·t + φ) + white noise of σ, at rate_hz.
std::vector<double> tone(std::size_t n, double rate_hz, double f_hz, double a, double c,
                         double sigma = 0.0, unsigned seed = 1) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<double> x(n);
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = c + a * std::cos(2.0 * kPi * f_hz * static_cast<double>(i) / rate_hz + 0.3) +
           (sigma > 0.0 ? sigma * noise(rng) : 0.0);
  }
  return x;
}

// A line at a bin's frequency reads its peak amplitude (Hann: no scalloping at the bin); the
// offset is removed; the segments are the largest power of two the record and the cap allow,
// half overlapping.
TEST(WelchSpectrum, ALineAtABinReadsItsAmplitudeAndTheMeanIsRemoved) {
  const double rate_hz = 50000.0;
  const std::size_t n = 5000;  // segments of 4096: one
  const double bin_hz = rate_hz / 4096.0;
  const double f_hz = 40 * bin_hz;
  const auto x = tone(n, rate_hz, f_hz, 3.5, 120.0);
  const AmplitudeSpectrum s = welch_amplitude_spectrum(x, rate_hz, 1 << 15);
  ASSERT_EQ(s.segment, 4096U);
  EXPECT_EQ(s.segments, 1U);
  EXPECT_EQ(s.covered, 4096U);
  ASSERT_EQ(s.amplitude.size(), 2049U);
  EXPECT_NEAR(s.frequency_hz[40], f_hz, 1e-9);
  // The mean is the record's (the tone's own over 5000 samples is not quite zero): what is
  // left of the offset leaks into the first bins alone.
  EXPECT_NEAR(s.amplitude[40], 3.5, 0.02);
  EXPECT_LT(s.amplitude[0], 0.05);  // 120 N of offset gone
  for (std::size_t k = 45; k < s.amplitude.size(); ++k) {
    EXPECT_LT(s.amplitude[k], 1e-3) << "bin " << k;
  }

  // A longer record: segments of the cap, half overlapping.
  const auto y = tone(40000, rate_hz, 3 * rate_hz / 1024.0, 2.0, 0.0);
  const AmplitudeSpectrum t = welch_amplitude_spectrum(y, rate_hz, 1024);
  EXPECT_EQ(t.segment, 1024U);
  EXPECT_EQ(t.segments, 1 + (40000U - 1024U) / 512U);
  EXPECT_EQ(t.covered, 1024U + (t.segments - 1) * 512U);
  EXPECT_NEAR(t.amplitude[3], 2.0, 1e-6);
}

// White noise of σ: the mean power per bin of a Hann-windowed segment is σ²·Σw², so the
// amplitude reads 2σ·√(Σw²)/Σw = 2σ·√(3/(2N)) (Σw = N/2, Σw² = 3N/8), averaged over segments.
TEST(WelchSpectrum, WhiteNoiseReadsItsExpectedFloor) {
  const double sigma = 0.5;
  const auto x = tone(1 << 17, 50000.0, 1000.0, 0.0, 0.0, sigma, 7);
  const AmplitudeSpectrum s = welch_amplitude_spectrum(x, 50000.0, 1024);
  double power = 0.0;
  std::size_t bins = 0;
  for (std::size_t k = 10; k + 10 < s.amplitude.size(); ++k, ++bins) {
    power += s.amplitude[k] * s.amplitude[k];
  }
  const double expected = 2.0 * sigma * std::sqrt(1.5 / 1024.0);
  EXPECT_NEAR(std::sqrt(power / static_cast<double>(bins)), expected, 0.03 * expected);
}

TEST(WelchSpectrum, ShortOrBadRecordsGiveNoNumberThatIsNotFinite) {
  EXPECT_TRUE(
      welch_amplitude_spectrum(std::vector<double>(63, 1.0), 1000.0, 1 << 15).amplitude.empty());
  auto x = tone(300, 1000.0, 1000.0 * 8 / 256, 1.0, 0.0);
  x[100] = std::numeric_limits<double>::quiet_NaN();
  x[101] = std::numeric_limits<double>::infinity();
  const AmplitudeSpectrum s = welch_amplitude_spectrum(x, 1000.0, 1 << 15);
  EXPECT_EQ(s.segment, 256U);
  for (const double a : s.amplitude) {
    EXPECT_TRUE(std::isfinite(a));
  }
}

}  // namespace
}  // namespace millwatch::signal
