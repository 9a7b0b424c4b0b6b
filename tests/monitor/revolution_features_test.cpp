#include "core/monitor/revolution_features.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "core/signal/cpu_features.hpp"

namespace millwatch::monitor {
namespace {

/// Rows of four channels, sample n at rows[n − first].
struct Rows {
  std::int64_t first = 0;
  std::vector<std::array<double, 4>> rows;
  const double* operator()(std::int64_t n) const {
    return rows[static_cast<std::size_t>(n - first)].data();
  }
};

/// The definition, sample by sample: each channel's smallest and largest value, and the first
/// sample at its peak (fx, fy, fz: the extreme of larger magnitude, the highest on a tie; the
/// fourth channel: its highest).
RowExtremes brute_extremes(const Rows& r, std::int64_t from, std::int64_t to) {
  RowExtremes e;
  for (std::size_t c = 0; c < 4; ++c) {
    double lo = r(from)[c], hi = lo;
    for (std::int64_t n = from; n <= to; ++n) {
      lo = std::min(lo, r(n)[c]);
      hi = std::max(hi, r(n)[c]);
    }
    e.lowest[c] = lo;
    e.highest[c] = hi;
    const double peak = c < 3 && std::fabs(lo) > std::fabs(hi) ? lo : hi;
    std::int64_t at = from;
    while (r(at)[c] != peak) {
      ++at;
    }
    e.peak_at[c] = at;
  }
  return e;
}

void expect_same(const RowExtremes& got, const RowExtremes& want, const char* kernel) {
  for (std::size_t c = 0; c < 4; ++c) {
    ASSERT_EQ(got.lowest[c], want.lowest[c]) << kernel << " channel " << c;
    ASSERT_EQ(got.highest[c], want.highest[c]) << kernel << " channel " << c;
    // Bit for bit: a zero's sign too.
    ASSERT_EQ(std::signbit(got.lowest[c]), std::signbit(want.lowest[c])) << kernel << " " << c;
    ASSERT_EQ(std::signbit(got.highest[c]), std::signbit(want.highest[c])) << kernel << " " << c;
    ASSERT_EQ(got.peak_at[c], want.peak_at[c]) << kernel << " channel " << c;
  }
}

TEST(RowExtremes, BothKernelsFindTheExtremesAndTheFirstSampleAtEachPeak) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> force(0.0, 3.0);
  std::uniform_int_distribution<int> level(-3, 3);
  for (int trial = 0; trial < 400; ++trial) {
    Rows r;
    r.first = 1'000'000'000 + trial;        // sample numbers of a long stream
    const bool quantised = trial % 2 == 0;  // repeated values: ties at the extremes
    r.rows.resize(static_cast<std::size_t>(1 + trial % 150));
    for (auto& row : r.rows) {
      for (std::size_t c = 0; c < 3; ++c) {
        row[c] = quantised ? 0.5 * level(rng) : force(rng);
      }
      row[3] = row[0] * row[0] + row[1] * row[1];
    }
    if (trial % 7 == 0) {  // fz all zeros of either sign: equal, and the first one counts
      for (auto& row : r.rows) {
        row[2] = level(rng) < 0 ? -0.0 : 0.0;
      }
    }
    const std::int64_t to = r.first + static_cast<std::int64_t>(r.rows.size()) - 1;
    const RowExtremes want = brute_extremes(r, r.first, to);
    expect_same(row_extremes(r, r.first, to, false), want, "SSE2");
    expect_same(row_extremes(r, r.first, to, true), want, "AVX");
  }
  if (!signal::cpu_has_avx()) {
    GTEST_SKIP() << "no AVX here: only the SSE2 kernel was checked";
  }
}

TEST(MeasureRevolution, PeaksOfParabolicPulsesAreTheirVertices) {
  // Two flutes over 200 samples at 50 kHz: valleys (events) at 1000 and 1090, the next
  // revolution's first at 1200. Within each flute, fx, fy and fz are parabolas whose vertices lie
  // between samples: the three-point refinement is exact on a parabola.
  Rows r;
  r.first = 990;
  const std::array<double, 2> vertex{1041.3, 1137.8};
  const std::array<std::array<double, 3>, 2> height{{{12.0, -20.0, 3.0}, {9.0, -16.5, 2.5}}};
  for (std::int64_t n = r.first; n <= 1210; ++n) {
    const std::size_t j = n < 1090 ? 0 : 1;
    const double u = static_cast<double>(n) - vertex[j];
    std::array<double, 4> row{};
    for (std::size_t c = 0; c < 3; ++c) {
      row[c] = height[j][c] * (1.0 - 1e-4 * u * u);
    }
    row[3] = row[0] * row[0] + row[1] * row[1];
    r.rows.push_back(row);
  }
  RevolutionMeasurement m;
  m.flutes = 2;
  m.event_sample[0] = m.boundary_sample[0] = 1000.0;
  m.event_sample[1] = m.boundary_sample[1] = 1090.0;
  m.event_sample[2] = m.boundary_sample[2] = 1200.0;
  measure_revolution(r, 50000.0, m);
  EXPECT_DOUBLE_EQ(m.period_s, 200.0 / 50000.0);
  EXPECT_DOUBLE_EQ(m.alpha_deg, 360.0 * 110.0 / 200.0);
  for (std::size_t j = 0; j < 2; ++j) {
    for (std::size_t c = 0; c < 3; ++c) {
      EXPECT_NEAR(m.peak_N[j][c], height[j][c], 1e-12) << "flute " << j << " channel " << c;
    }
  }
  EXPECT_NEAR(m.delta_fy_N, 20.0 - 16.5, 1e-12);
}

}  // namespace
}  // namespace millwatch::monitor
