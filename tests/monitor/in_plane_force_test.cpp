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

TEST(InPlaneForce, NonFiniteSamplesAreLeftOutNotCounted) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  InPlaneForce f;
  // A NaN in either axis, an infinity, and a square that overflows (1e200² = inf): all left out.
  const std::vector<double> x = {nan, 1.0, inf, 1e200, 6.0, 2.0};
  const std::vector<double> y = {1.0, nan, 0.0, 0.0, 8.0, 0.0};
  f.add(x, y);
  EXPECT_EQ(f.samples(), 2);
  EXPECT_DOUBLE_EQ(*f.rms_N(), std::sqrt((100.0 + 4.0) / 2.0));
  EXPECT_DOUBLE_EQ(*f.max_N(), 10.0);
}

TEST(InPlaneForce, SumsInTheSamplesOrderWhateverTheBlocks) {
  // The same samples in one block or in blocks of 1 to 7: the same sums, bit for bit (the
  // summary's figure does not depend on the reader's block size).
  std::vector<double> x(1000), y(1000);
  for (std::size_t k = 0; k < x.size(); ++k) {
    x[k] = std::sin(0.37 * static_cast<double>(k)) * 40.0 + 0.1;
    y[k] = std::cos(1.3 * static_cast<double>(k)) * 25.0;
  }
  InPlaneForce whole;
  whole.add(x, y);
  for (std::size_t block = 1; block <= 7; ++block) {
    InPlaneForce parts;
    for (std::size_t k = 0; k < x.size(); k += block) {
      const std::size_t n = std::min(block, x.size() - k);
      parts.add(std::span(x).subspan(k, n), std::span(y).subspan(k, n));
    }
    EXPECT_EQ(*parts.rms_N(), *whole.rms_N()) << "blocks of " << block;
    EXPECT_EQ(*parts.max_N(), *whole.max_N()) << "blocks of " << block;
  }
}

}  // namespace
}  // namespace millwatch::monitor
