#include "core/monitor/in_plane_force.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>
#include <vector>

namespace millwatch::monitor {
namespace {

TEST(InPlaneForce, NoSamplesGiveNoFigures) {
  InPlaneForce f;
  EXPECT_EQ(f.samples(), 0);
  EXPECT_FALSE(f.rms_N().has_value());
  EXPECT_FALSE(f.max_N().has_value());
  const std::vector<double> nan = {std::numeric_limits<double>::quiet_NaN()};
  f.add(nan, nan);
  EXPECT_EQ(f.samples(), 0);
  EXPECT_FALSE(f.rms_N().has_value());
}

TEST(InPlaneForce, RmsAndLargestOfTheResultantAcrossBlocks) {
  // 3-4-5 and 6-8-10 triangles, and a sample of zero force: resultants 5, 10 and 0.
  InPlaneForce f;
  const std::vector<double> x1 = {3.0, -6.0}, y1 = {-4.0, 8.0};
  const std::vector<double> x2 = {0.0}, y2 = {0.0};
  f.add(x1, y1);
  f.add(x2, y2);
  EXPECT_EQ(f.samples(), 3);
  EXPECT_DOUBLE_EQ(*f.rms_N(), std::sqrt((25.0 + 100.0 + 0.0) / 3.0));
  EXPECT_DOUBLE_EQ(*f.max_N(), 10.0);
}

TEST(InPlaneForce, NonFiniteAndImplausibleSamplesAreLeftOutNotCounted) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  InPlaneForce f;
  // A NaN in either axis, an infinity, a square that overflows (1e200² = inf) and values the
  // input check takes for corrupt (beyond ±1e6 N, on either axis): all left out; 1e6 N itself
  // is a force.
  const std::vector<double> x = {nan, 1.0, inf, 1e200, 6.0, 2.0, 2e7, 0.0, 1e6};
  const std::vector<double> y = {1.0, nan, 0.0, 0.0, 8.0, 0.0, 0.0, -1.0000001e6, 0.0};
  f.add(x, y);
  EXPECT_EQ(f.samples(), 3);
  EXPECT_DOUBLE_EQ(*f.rms_N(), std::sqrt((100.0 + 4.0 + 1e12) / 3.0));
  EXPECT_DOUBLE_EQ(*f.max_N(), 1e6);
}

TEST(InPlaneForce, SumsInTheSamplesOrderWhateverTheBlocks) {
  // The samples' squares added one by one, in order, whatever the blocks (the summary's figure
  // does not depend on the reader's block size). A first square of 1e12 (the largest force
  // taken, 1e6 N) and then 1,000 of 4.9e-5: each added to 1e12 rounds away (the doubles there
  // are 2⁻¹³ ≈ 1.2e-4 apart), so the sum stays 1e12; a block's squares summed first and then
  // added would not vanish.
  std::vector<double> x(1001, 0.007), y(1001, 0.0);
  x[0] = 1e6;
  double sum_sq = 0.0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    sum_sq += x[k] * x[k] + y[k] * y[k];
  }
  ASSERT_EQ(sum_sq, 1e12);
  for (std::size_t block = 1; block <= 7; ++block) {
    InPlaneForce parts;
    for (std::size_t k = 0; k < x.size(); k += block) {
      const std::size_t n = std::min(block, x.size() - k);
      parts.add(std::span(x).subspan(k, n), std::span(y).subspan(k, n));
    }
    EXPECT_EQ(parts.samples(), 1001);
    EXPECT_EQ(*parts.rms_N(), std::sqrt(1e12 / 1001.0)) << "blocks of " << block;
    EXPECT_EQ(*parts.max_N(), 1e6) << "blocks of " << block;
  }
}

}  // namespace
}  // namespace millwatch::monitor
