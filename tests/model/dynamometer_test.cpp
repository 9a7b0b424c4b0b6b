#include "core/model/dynamometer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace millwatch::model {
namespace {

// H(s) = ω_n²/(s² + 2ζω_n s + ω_n²): unit gain at DC, 1/(2ζ) at the (pre-warped) natural
// frequency with −90° phase, and a steady sine comes out scaled by |H|.
TEST(Resonance, MatchesTheContinuousSecondOrderResponse) {
  const double fs = 50000.0;
  const Resonance r(2145.0, 0.05, fs);
  EXPECT_NEAR(std::abs(r.response(0.0)), 1.0, 1e-12);
  EXPECT_NEAR(std::abs(r.response(2145.0)), 1.0 / (2 * 0.05), 1e-9);
  EXPECT_NEAR(std::arg(r.response(2145.0)), -std::numbers::pi / 2, 1e-9);
  Resonance s(2145.0, 0.05, fs);
  const double f = 800.0;
  double peak = 0.0;
  for (int n = 0; n < 50000; ++n) {
    const double y = s.step(std::sin(2 * std::numbers::pi * f * n / fs));
    if (n > 40000) {
      peak = std::max(peak, std::fabs(y));
    }
  }
  EXPECT_NEAR(peak, std::abs(r.response(f)), 2e-3);
  // continuous |H| at 800 Hz (bilinear warping is small this far below fs/2)
  const double u = f / 2145.0;
  const double continuous =
      1.0 / std::sqrt((1 - u * u) * (1 - u * u) + (2 * 0.05 * u) * (2 * 0.05 * u));
  EXPECT_NEAR(std::abs(r.response(f)), continuous, 0.01 * continuous);
}

TEST(Resonance, SettleGivesTheSteadyStateOfAConstant) {
  Resonance r(2000.0, 0.1, 20000.0);
  r.settle(3.5);
  for (int n = 0; n < 10; ++n) {
    EXPECT_NEAR(r.step(3.5), 3.5, 1e-12);
  }
}

TEST(Resonance, RejectsFrequenciesItCannotRepresent) {
  EXPECT_THROW(Resonance(12000.0, 0.05, 20000.0), std::invalid_argument);
  EXPECT_THROW(Resonance(2000.0, 0.0, 20000.0), std::invalid_argument);
  EXPECT_THROW(Resonance(2000.0, 0.05, -1.0), std::invalid_argument);
}

}  // namespace
}  // namespace millwatch::model
