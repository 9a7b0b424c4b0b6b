// The speed's σ from the scatter of the record's segment delays (core/diagnose/speed_scatter.hpp)
// against two independent truths: the Cramér–Rao bound of a frequency in white noise, and a
// noise-free record whose segments are delayed by a known pattern.

#include "core/diagnose/speed_scatter.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace millwatch::diagnose {
namespace {

constexpr double kFs_hz = 20000.0;
constexpr double kSpindle_hz = 400.0;  // 50 samples a revolution
constexpr double kTheta = 2.0 * std::numbers::pi * kSpindle_hz / kFs_hz;
// Two channels, three harmonics each: amplitudes (N) and phases (rad).
constexpr std::array<std::array<double, 3>, 2> kAmplitude_N = {{{3.0, 1.5, 0.6}, {2.0, 0.8, 0.4}}};
constexpr std::array<std::array<double, 3>, 2> kPhase_rad = {{{0.3, 1.9, -2.2}, {-1.0, 0.4, 2.7}}};

/// Channel a's waveform at spindle angle φ.
double waveform(std::size_t a, double phi) {
  double v = 0.0;
  for (std::size_t k = 0; k < 3; ++k) {
    v += kAmplitude_N[a][k] * std::cos(static_cast<double>(k + 1) * phi + kPhase_rad[a][k]);
  }
  return v;
}

// Over white noise of σ per sample, a frequency θ (rad/sample) estimated over N samples from
// harmonics of amplitudes A_k has var θ = 24σ² / (N(N² − 1)·Σ k²A_k²) (the Cramér–Rao bound,
// amplitudes and phases unknown; summed over the channels). The segments' σ is that, to the
// scatter of a variance on 14 degrees of freedom (±38 % a record): its mean square over 200
// records within ±10 % (3.7σ of that mean). Without the leave-one-out template's correction
// (speed_scatter.cpp) it was 1.14 over 1,000 records.
TEST(SegmentSpeedSigma, IsTheCramerRaoBoundInWhiteNoise) {
  // 48.48… samples a revolution (a segment of whole revolutions holds a non-whole number of
  // samples) and a mean of 5 N, which the segments' harmonics must not see.
  constexpr double kSpindleHere_hz = 412.5;
  constexpr double kThetaHere = 2.0 * std::numbers::pi * kSpindleHere_hz / kFs_hz;
  constexpr std::size_t kSamples = 16000;  // 330 revolutions, 16 segments of 20–21
  constexpr double kNoise_N = 0.5;
  double sum_k2a2 = 0.0;
  for (std::size_t a = 0; a < 2; ++a) {
    for (std::size_t k = 0; k < 3; ++k) {
      sum_k2a2 += static_cast<double>((k + 1) * (k + 1)) * kAmplitude_N[a][k] * kAmplitude_N[a][k];
    }
  }
  const auto n = static_cast<double>(kSamples);
  const double bound_rel =
      std::sqrt(24.0 * kNoise_N * kNoise_N / (n * (n * n - 1.0) * sum_k2a2)) / kThetaHere;
  constexpr int kRecords = 200;
  double sum_ratio2 = 0.0;
  for (int r = 0; r < kRecords; ++r) {
    std::mt19937_64 rng(100 + static_cast<unsigned>(r));
    std::normal_distribution<double> noise(0.0, kNoise_N);
    std::array<std::vector<double>, 2> x;
    for (std::size_t a = 0; a < 2; ++a) {
      x[a].resize(kSamples);
      for (std::size_t i = 0; i < kSamples; ++i) {
        x[a][i] = 5.0 + waveform(a, kThetaHere * static_cast<double>(i)) + noise(rng);
      }
    }
    int segments = 0;
    const double sigma_rel = segment_speed_sigma_rel(x, kFs_hz, kSpindleHere_hz, 3, &segments);
    ASSERT_EQ(segments, 16);
    sum_ratio2 += (sigma_rel / bound_rel) * (sigma_rel / bound_rel);
  }
  const double mean_ratio2 = sum_ratio2 / kRecords;
  std::printf("bound %.3e, mean (σ/bound)² %.3f\n", bound_rel, mean_ratio2);
  EXPECT_GT(mean_ratio2, 0.9);
  EXPECT_LT(mean_ratio2, 1.1);
}

// No noise; the first and last four of 16 segments (20 revolutions each) delayed by +δ samples,
// the middle eight by −δ. About the line through the centres (slope 0, by symmetry) the
// segments' own delays leave ±δ, so σ = √(16·δ²/14 / Σ(t_j − t̄)²), the centres 1,000 samples
// apart. (Against the rest of the record, its mean delay ∓δ/15, a segment is ±16δ/15 off: the
// leave-one-out correction brings that back to ±δ.)
TEST(SegmentSpeedSigma, IsTheSlopesStandardErrorOfKnownSegmentDelays) {
  constexpr double kDelay_samples = 0.3;
  constexpr std::size_t kSegmentSamples = 1000;
  std::array<std::vector<double>, 2> x;
  for (std::size_t a = 0; a < 2; ++a) {
    x[a].resize(16 * kSegmentSamples);
    for (std::size_t i = 0; i < x[a].size(); ++i) {
      const std::size_t j = i / kSegmentSamples;
      const double d = (j < 4 || j >= 12) ? kDelay_samples : -kDelay_samples;
      x[a][i] = waveform(a, kTheta * (static_cast<double>(i) - d));
    }
  }
  double stt = 0.0;
  for (int j = 0; j < 16; ++j) {
    const double t = (j - 7.5) * static_cast<double>(kSegmentSamples);
    stt += t * t;
  }
  const double expected = std::sqrt(16.0 * kDelay_samples * kDelay_samples / 14.0 / stt);
  int segments = 0;
  const double sigma_rel = segment_speed_sigma_rel(x, kFs_hz, kSpindle_hz, 3, &segments);
  EXPECT_EQ(segments, 16);
  EXPECT_NEAR(sigma_rel, expected, 0.01 * expected);
}

// Fewer than four whole revolutions leave no scatter to measure: 0, not a number made up.
TEST(SegmentSpeedSigma, NeedsFourRevolutions) {
  std::array<std::vector<double>, 2> x;
  for (auto& c : x) {
    c.assign(199, 1.0);  // 3.98 revolutions
  }
  int segments = -1;
  EXPECT_EQ(segment_speed_sigma_rel(x, kFs_hz, kSpindle_hz, 3, &segments), 0.0);
  EXPECT_EQ(segments, 0);
  for (auto& c : x) {
    c.assign(200, 0.0);  // four revolutions, no harmonic power
  }
  EXPECT_EQ(segment_speed_sigma_rel(x, kFs_hz, kSpindle_hz, 3, &segments), 0.0);
}

}  // namespace
}  // namespace millwatch::diagnose
