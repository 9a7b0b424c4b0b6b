#include "core/monitor/extremum.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "core/monitor/nearest_integer.hpp"

namespace millwatch::monitor {
namespace {

// A parabola sampled around its vertex: the fit (parabola for h = 1, cubic beyond) finds the
// vertex and its value exactly, whatever the half width (the moments of the fit come in closed
// form).
TEST(Extremum, FindsTheVertexOfASampledParabolaAtEveryHalfWidth) {
  for (int h = 1; h <= 300; h += (h < 20 ? 1 : 17)) {
    for (const double vertex : {-0.45, 0.0, 0.3}) {
      for (const bool minimum : {true, false}) {
        const double curvature = minimum ? 0.7 : -0.7;
        const auto parabola = [&](std::int64_t n) {
          const double u = static_cast<double>(n - 1000) - vertex;
          return 2.5 + curvature * u * u;
        };
        const Extremum e = refine_extremum(parabola, 1000, h, minimum);
        ASSERT_TRUE(e.valid) << h << " " << vertex;
        EXPECT_NEAR(e.position, 1000.0 + vertex, 1e-9 * h) << h;
        EXPECT_NEAR(e.value, 2.5, 1e-9 * h * h) << h;
        EXPECT_FALSE(refine_extremum(parabola, 1000, h, !minimum).valid) << h;
      }
    }
  }
}

// An asymmetric valley, (u − δ)²·(1 + u/10) for |u| ≤ h: the cubic term is fitted exactly for
// h ≥ 2, and the stationary point nearest the centre is δ.
TEST(Extremum, TheCubicAbsorbsAnAsymmetricValley) {
  for (int h = 2; h <= 8; ++h) {
    const double delta = 0.2;
    const auto valley = [&](std::int64_t n) {
      const double u = static_cast<double>(n);
      return (u - delta) * (u - delta) * (1.0 + u / 10.0);
    };
    const Extremum e = refine_extremum(valley, 0, h, true);
    ASSERT_TRUE(e.valid);
    EXPECT_NEAR(e.position, delta, 1e-9) << h;
    EXPECT_NEAR(e.value, 0.0, 1e-9) << h;
  }
}

// nearest_sample() and nearest_integer() (the input check's utimes) are std::llround(): halves
// away from zero, the doubles next to a half, zeros of either sign, positions far beyond any
// record (where the library call takes over), and a million positions of a long record's range.
TEST(NearestSample, IsTheLibrarysRoundingEverywhere) {
  std::vector<double> positions = {0.0,  -0.0,      0.5,          -0.5,   1.5,     -1.5,  2.5,
                                   -2.5, 1e6 + 0.5, 0x1p52 - 0.5, 0x1p62, -0x1p62, 1e300, -1e300};
  for (const double half : {0.5, -0.5, 2.5, -7.5, 123456.5}) {
    positions.push_back(std::nextafter(half, 0.0));
    positions.push_back(std::nextafter(half, 2.0 * half));
  }
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> position(-2e9, 2e9);
  for (int i = 0; i < 1000000; ++i) {
    positions.push_back(position(rng));
  }
  for (const double p : positions) {
    ASSERT_EQ(nearest_sample(p), std::llround(p)) << p;
    ASSERT_EQ(nearest_integer(p), std::llround(p)) << p;
  }
}

// A half-width of zero fits nothing (one sample has no curvature): no extreme, and a finite
// position and value (the sample's), not the 0/0 of an empty normal equation.
TEST(Extremum, AHalfWidthOfZeroGivesNoFit) {
  const auto valley = [](std::int64_t n) { return std::pow(static_cast<double>(n) - 10.3, 2); };
  const Extremum e = refine_extremum(valley, 10, 0, true);
  EXPECT_FALSE(e.valid);
  EXPECT_EQ(e.position, 10.0);
  EXPECT_EQ(e.value, valley(10));
}

}  // namespace
}  // namespace millwatch::monitor
