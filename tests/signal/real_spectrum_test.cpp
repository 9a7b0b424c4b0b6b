#include "core/signal/real_spectrum.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace millwatch::signal {
namespace {

constexpr double kPi = std::numbers::pi;

// x[n] = a·cos(2π·k·n/N + φ) has X[k] = (N/2)·a·e^{iφ}, X[N − k] its conjugate, and nothing
// elsewhere; a constant c has X[0] = N·c. Checked for even and odd N, and at the Nyquist bin.
TEST(RealSpectrum, CosinesAndAConstantGiveTheirAnalyticBins) {
  for (const int n : {7, 180, 720, 1440}) {
    SCOPED_TRACE("N = " + std::to_string(n));
    const int k = n / 3;
    const double a = 2.5, phi = 0.7, c = -1.25;
    std::vector<double> x(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
      x[static_cast<std::size_t>(i)] = c + a * std::cos(2.0 * kPi * k * i / n + phi);
    }
    RealSpectrum spectrum(n);
    const auto bins = spectrum.transform(x);
    ASSERT_EQ(bins.size(), static_cast<std::size_t>(n / 2 + 1));
    const std::complex<double> expected = 0.5 * n * std::polar(a, phi);
    const double tolerance = 1e-12 * n;
    for (int m = 0; m < 2 * n + 3; ++m) {  // past N: aliased to m mod N
      const int r = m % n;
      const std::complex<double> want = r == 0       ? std::complex<double>(n * c, 0.0)
                                        : r == k     ? expected
                                        : r == n - k ? std::conj(expected)
                                                     : std::complex<double>(0.0, 0.0);
      EXPECT_LT(std::abs(spectrum.bin(m) - want), tolerance) << "bin " << m;
      if (m <= n / 2) {
        EXPECT_EQ(spectrum.bin(m), bins[static_cast<std::size_t>(m)]);
      }
    }
  }
  // The Nyquist bin of an even N: (−1)ⁿ gives X[N/2] = N.
  std::vector<double> alternating(8);
  for (std::size_t i = 0; i < alternating.size(); ++i) {
    alternating[i] = i % 2 == 0 ? 1.0 : -1.0;
  }
  RealSpectrum eight(8);
  eight.transform(alternating);
  EXPECT_LT(std::abs(eight.bin(4) - std::complex<double>(8.0, 0.0)), 1e-14);
}

TEST(RealSpectrum, AWrongLengthOrNoPlanIsRefusedAndAMovedPlanWorks) {
  EXPECT_THROW(RealSpectrum(0), std::invalid_argument);
  RealSpectrum none;
  const std::vector<double> four(4, 1.0);
  EXPECT_THROW(none.transform(four), std::invalid_argument);
  EXPECT_THROW(static_cast<void>(none.bin(0)), std::invalid_argument);
  RealSpectrum spectrum(5);
  EXPECT_THROW(spectrum.transform(four), std::invalid_argument);
  RealSpectrum moved(std::move(spectrum));
  EXPECT_EQ(spectrum.samples(), 0);  // moved from: empty
  EXPECT_EQ(moved.samples(), 4 + 1);
  const std::vector<double> five(5, 1.0);
  EXPECT_LT(std::abs(moved.transform(five)[0] - std::complex<double>(5.0, 0.0)), 1e-15);
  EXPECT_THROW(static_cast<void>(moved.bin(-1)), std::invalid_argument);
  none = std::move(moved);
  EXPECT_LT(std::abs(none.transform(five)[0] - std::complex<double>(5.0, 0.0)), 1e-15);
}

}  // namespace
}  // namespace millwatch::signal
