// The harmonic fit energy (core/diagnose/record_spectrum.hpp) against least squares solved the
// long way (Eigen's QR on the explicit design matrix), and on a record it explains exactly.

#include "core/diagnose/record_spectrum.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <vector>

namespace millwatch::diagnose {
namespace {

constexpr double kFs_hz = 20000.0;

/// ‖P·x‖² with P the projection onto [1, cos kθn, sin kθn], solved by QR on the design matrix.
double projection_energy_by_qr(const std::vector<double>& x, double spindle_hz, int harmonics) {
  const auto n = static_cast<Eigen::Index>(x.size());
  Eigen::MatrixXd h(n, 2 * harmonics + 1);
  const double theta = 2.0 * std::numbers::pi * spindle_hz / kFs_hz;
  for (Eigen::Index i = 0; i < n; ++i) {
    h(i, 0) = 1.0;
    for (int k = 1; k <= harmonics; ++k) {
      h(i, 2 * k - 1) = std::cos(k * theta * static_cast<double>(i));
      h(i, 2 * k) = std::sin(k * theta * static_cast<double>(i));
    }
  }
  const Eigen::Map<const Eigen::VectorXd> v(x.data(), n);
  const Eigen::VectorXd fitted = h * h.colPivHouseholderQr().solve(v);
  return fitted.squaredNorm();
}

// 1,003 samples at 412.5 Hz hold 20.7 revolutions: the harmonics are not orthogonal over them.
TEST(HarmonicFitEnergy, EqualsLeastSquaresOnTheDesignMatrix) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::array<std::vector<double>, 2> x;
  for (auto& channel : x) {
    channel.resize(1003);
    for (double& v : channel) {
      v = 0.3 + gauss(rng);
    }
  }
  for (const double spindle_hz : {412.5, 409.1, 1000.0}) {
    for (const int harmonics : {1, 4, 9}) {
      const double expected = projection_energy_by_qr(x[0], spindle_hz, harmonics) +
                              projection_energy_by_qr(x[1], spindle_hz, harmonics);
      EXPECT_NEAR(harmonic_fit_energy(x, kFs_hz, spindle_hz, harmonics), expected, 1e-9 * expected)
          << spindle_hz << " Hz, " << harmonics << " harmonics";
    }
  }
}

// A mean and five harmonics over a part revolution's worth more than whole ones: at its speed the
// fit explains all of it; 0.1 % off, visibly less (the lines no longer fit).
TEST(HarmonicFitEnergy, ExplainsARecordOfHarmonicsWhollyAtItsSpeedAlone) {
  const double spindle_hz = 416.6;
  std::vector<std::vector<double>> x(1, std::vector<double>(4321));
  double total = 0.0;
  for (std::size_t i = 0; i < x[0].size(); ++i) {
    const double phi = 2.0 * std::numbers::pi * spindle_hz * static_cast<double>(i) / kFs_hz;
    double v = 12.0;
    for (int k = 1; k <= 5; ++k) {
      v += (6.0 / k) * std::cos(k * phi + 0.7 * k);
    }
    x[0][i] = v;
    total += v * v;
  }
  EXPECT_NEAR(harmonic_fit_energy(x, kFs_hz, spindle_hz, 5), total, 1e-9 * total);
  EXPECT_LT(harmonic_fit_energy(x, kFs_hz, 1.001 * spindle_hz, 5), 0.999 * total);
  EXPECT_EQ(harmonic_fit_energy(std::vector<std::vector<double>>{}, kFs_hz, spindle_hz, 5), 0.0);
}

// A long record (100 s at 20 kHz, 2,000,003 samples; 50 samples a revolution, so its whole
// revolutions make the harmonics exactly orthogonal): its synchronous harmonics are the signal's
// own to 1.3e-10 (6e-11 at most here, the rounding of the angle k·θ·n the signal was made with),
// although the phasor is rotated between exact values: rotated from the first sample to the last
// it drifts by 2.8e-10 over these two million samples.
TEST(SynchronousHarmonics, AreExactOverALongRecord) {
  const double spindle_hz = 400.0;
  std::vector<double> x(2'000'003);
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double phi = 2.0 * std::numbers::pi * spindle_hz * static_cast<double>(i) / kFs_hz;
    double v = 12.0;
    for (int k = 1; k <= 5; ++k) {
      v += (6.0 / k) * std::cos(k * phi + 0.7 * k);
    }
    x[i] = v;
  }
  std::vector<std::complex<double>> h;
  EXPECT_EQ(synchronous_harmonics(x, kFs_hz, spindle_hz, 7, h), 2'000'000U);
  ASSERT_EQ(h.size(), 8U);
  EXPECT_NEAR(h[0].real(), 12.0, 1.3e-10);
  for (int k = 1; k <= 7; ++k) {
    const std::complex<double> expected =
        k <= 5 ? std::polar(6.0 / k, 0.7 * k) : std::complex<double>{};
    EXPECT_LT(std::abs(h[static_cast<std::size_t>(k)] - expected), 1.3e-10) << "harmonic " << k;
  }
}

}  // namespace
}  // namespace millwatch::diagnose
