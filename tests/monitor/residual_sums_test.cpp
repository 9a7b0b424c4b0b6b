#include "core/monitor/residual_sums.hpp"

#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cstdint>
#include <random>
#include <vector>

#include "core/monitor/sample_ring.hpp"
#include "core/signal/cpu_features.hpp"

namespace millwatch::monitor {
namespace {

// Both kernels give the definition's sums, added sample after sample, bit for bit: on measured
// rows read through a sample ring that wraps within the run, in runs of 1 to 40 samples that
// carry the sums on from each other, with the flute's and the sector's sums started apart.
TEST(ResidualSums, BothKernelsAddTheDefinitionsTermsInTheSamplesOrder) {
  SampleRing ring(4, 64);  // 64 rows: the runs below wrap around it
  std::mt19937 rng(7);
  std::normal_distribution<double> force_N(0.0, 30.0);
  std::vector<double> model;  // a row of four per sample from `first`
  const std::int64_t first = 1000;
  for (std::int64_t n = 0; n < first + 60; ++n) {
    const double fx = force_N(rng), fy = force_N(rng);
    const std::array<double, 4> measured = {fx, fy, force_N(rng), fx * fx + fy * fy};
    ring.push(n, measured.data());
    if (n >= first) {
      const double mx = fx + 0.1 * force_N(rng), my = fy - 0.1 * force_N(rng);
      for (const double v : {mx, my, 0.5 * force_N(rng), mx * mx + my * my}) {
        model.push_back(v);
      }
    }
  }
  ASSERT_EQ(ring.oldest(), first - 4);
  const auto rows = [r = ring.rows()](std::int64_t n) { return r.row(n); };
  const bool avx = signal::cpu_has_avx();
  if (!avx) {
    GTEST_LOG_(INFO) << "no AVX on this CPU: the scalar kernel alone";
  }
  for (const int run : {1, 2, 3, 7, 19, 40}) {
    ResidualSums scalar, vector, defined;
    // Sums carried on from earlier runs: none starts at zero.
    scalar.sums_N2 = vector.sums_N2 = defined.sums_N2 = {1.5, 0.125, 7.0, 2.0e3};
    scalar.flute_sector_N2 = vector.flute_sector_N2 = defined.flute_sector_N2 = {0.25, -3.0};
    const auto bits = [](double x) { return std::bit_cast<std::uint64_t>(x); };
    for (std::int64_t from = first; from + run - 1 < first + 60; from += run) {
      const std::int64_t to = from + run - 1;
      const double* m = &model[static_cast<std::size_t>(4 * (from - first))];
      add_residuals(rows, m, from, to, scalar, false);
      add_residuals(rows, m, from, to, vector, true);
      for (std::int64_t n = from; n <= to; ++n, m += 4) {
        const double* v = rows(n);
        const double dx = v[0] - m[0], dy = v[1] - m[1], dz = v[2] - m[2];
        defined.sums_N2[0] += dx * dx;
        defined.sums_N2[1] += dy * dy;
        defined.sums_N2[2] += dz * dz;
        defined.sums_N2[3] += v[3];
        defined.flute_sector_N2[0] += dx * dx + dy * dy;
        defined.flute_sector_N2[1] += dx * dx + dy * dy;
      }
      for (std::size_t a = 0; a < 4; ++a) {
        ASSERT_EQ(bits(scalar.sums_N2[a]), bits(defined.sums_N2[a])) << run << " " << from;
        ASSERT_EQ(bits(vector.sums_N2[a]), bits(defined.sums_N2[a])) << run << " " << from;
      }
      for (std::size_t a = 0; a < 2; ++a) {
        ASSERT_EQ(bits(scalar.flute_sector_N2[a]), bits(defined.flute_sector_N2[a])) << run;
        ASSERT_EQ(bits(vector.flute_sector_N2[a]), bits(defined.flute_sector_N2[a])) << run;
      }
    }
    EXPECT_GT(defined.sums_N2[0], 10.0);
    EXPECT_GT(defined.sums_N2[3], 1e4);  // Fx² + Fy² of forces of tens of newtons
  }
}

}  // namespace
}  // namespace millwatch::monitor
