// The sample ring against what was pushed into it: rows addressed by absolute sample index across
// the ring's wrap, by push() and push_rows(), through row() and through rows() (the
// rows by value that SIMD loops read), channels padded to a power of two; and the pipeline's
// force rows (force_rows.hpp) against their definition.

#include "core/monitor/sample_ring.hpp"

#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/monitor/force_rows.hpp"
#include "core/signal/cpu_features.hpp"

namespace millwatch::monitor {
namespace {

double value(std::int64_t sample, std::size_t channel) {
  return static_cast<double>(sample) + 0.25 * static_cast<double>(channel);
}

// Three channels take rows of four doubles (the fourth is padding, readable); 16 samples are
// kept. A run of 40 from sample 1,000 wraps the ring twice: the last 16 are there, each at its
// own index, the same row through row() and rows().
TEST(SampleRing, KeepsTheNewestSamplesAcrossItsWrapByIndex) {
  for (const int channels : {3, 4}) {
    SampleRing ring(channels, 10);
    ASSERT_EQ(ring.capacity(), 16U);
    ring.push_rows(1000, 40, [&](std::size_t i, std::size_t n, double* rows) {
      for (std::size_t k = 0; k < n; ++k) {
        for (std::size_t c = 0; c < static_cast<std::size_t>(channels); ++c) {
          rows[4 * k + c] = value(1000 + static_cast<std::int64_t>(i + k), c);
        }
      }
    });
    const SampleRing& kept = ring;
    EXPECT_EQ(kept.newest(), 1039);
    EXPECT_EQ(kept.oldest(), 1024);
    const SampleRing::Rows rows = kept.rows();
    for (std::int64_t n = kept.oldest(); n <= kept.newest(); ++n) {
      ASSERT_EQ(rows.row(n), kept.row(n)) << "sample " << n;
      for (std::size_t c = 0; c < static_cast<std::size_t>(channels); ++c) {
        ASSERT_EQ(kept.at(static_cast<int>(c), n), value(n, c)) << "sample " << n;
        ASSERT_EQ(rows.row(n)[c], value(n, c)) << "sample " << n;
      }
    }
    // Rows are 2^k doubles apart: consecutive samples are one row apart but at the ring's end.
    EXPECT_EQ(kept.row(1025) - kept.row(1024), 4);
    EXPECT_EQ(kept.row(1024), kept.row(1040));
  }
}

// push_rows() hands its fill stretches of consecutive rows, at most two (the ring's end splits
// them; of a run longer than the ring, the samples it keeps): the same ring as push() sample by
// sample, for runs from every place in the ring, across its end, and longer than it.
TEST(SampleRing, RowsInStretchesAreTheRowsOneByOne) {
  for (const std::size_t count : {1U, 5U, 16U, 23U, 40U}) {
    for (std::int64_t first = 1000; first < 1016; ++first) {
      SampleRing stretches(3, 16), one_by_one(3, 16);
      int calls = 0;
      stretches.push_rows(first, count, [&](std::size_t i, std::size_t n, double* rows) {
        ++calls;
        for (std::size_t k = 0; k < n; ++k) {
          for (std::size_t c = 0; c < 3; ++c) {
            rows[4 * k + c] = value(first + static_cast<std::int64_t>(i + k), c);
          }
        }
      });
      for (std::size_t i = 0; i < count; ++i) {
        const std::int64_t n = first + static_cast<std::int64_t>(i);
        // A row's room (push() of a four-channel ring reads four; this one reads three).
        const std::array<double, 4> v = {value(n, 0), value(n, 1), value(n, 2), 0.0};
        one_by_one.push(n, v.data());
      }
      EXPECT_LE(calls, 2);
      ASSERT_EQ(stretches.oldest(), one_by_one.oldest());
      ASSERT_EQ(stretches.newest(), one_by_one.newest());
      for (std::int64_t n = stretches.oldest(); n <= stretches.newest(); ++n) {
        for (int c = 0; c < 3; ++c) {
          ASSERT_EQ(stretches.at(c, n), one_by_one.at(c, n))
              << count << " from " << first << ": sample " << n;
          ASSERT_EQ(stretches.at(c, n), value(n, static_cast<std::size_t>(c)));
        }
      }
    }
  }
}

// The pipeline's rows (fx, fy, fz, fx² + fy²): the AVX kernel (four samples a transpose) gives
// the scalar one's rows bit for bit, for every count (whole fours and the rest), signed zeros,
// subnormals, a large fz and an fx whose square overflows among the samples; a stride takes
// every stride-th sample.
TEST(ForceRows, FourAtATimeAreTheRowsOneByOne) {
  std::vector<double> fx, fy, fz;
  for (int i = 0; i < 40; ++i) {
    const double t = 0.37 * i;
    fx.push_back(i == 3 ? -0.0 : i == 9 ? 1e200 : 12.5 * std::sin(t) - 3.0);
    fy.push_back(i == 5 ? 4e-310 : -7.25 * std::cos(1.3 * t));
    fz.push_back(i == 7 ? 1e150 : 0.5 * t);
  }
  const auto bits = [](double x) { return std::bit_cast<std::uint64_t>(x); };
  for (std::size_t count = 0; count <= 13; ++count) {
    std::vector<double> fast(4 * count, -1.0), plain(4 * count, -2.0);
    force_rows(fx.data(), fy.data(), fz.data(), 1, count, fast.data());
    force_rows(fx.data(), fy.data(), fz.data(), 1, count, plain.data(), false);
    for (std::size_t i = 0; i < count; ++i) {
      const double want[4] = {fx[i], fy[i], fz[i], fx[i] * fx[i] + fy[i] * fy[i]};
      for (std::size_t c = 0; c < 4; ++c) {
        ASSERT_EQ(bits(fast[4 * i + c]), bits(plain[4 * i + c])) << count << " " << i << " " << c;
        ASSERT_EQ(bits(plain[4 * i + c]), bits(want[c])) << count << " " << i << " " << c;
      }
    }
  }
  std::vector<double> strided(4 * 10);
  force_rows(fx.data(), fy.data(), fz.data(), 3, 10, strided.data());
  for (std::size_t i = 0; i < 10; ++i) {
    EXPECT_EQ(strided[4 * i], fx[3 * i]);
    EXPECT_EQ(strided[4 * i + 1], fy[3 * i]);
    EXPECT_EQ(strided[4 * i + 2], fz[3 * i]);
    EXPECT_EQ(strided[4 * i + 3], fx[3 * i] * fx[3 * i] + fy[3 * i] * fy[3 * i]);
  }
  if (!signal::cpu_has_avx()) {
    GTEST_SKIP() << "this CPU has no AVX: the scalar rows alone were compared";
  }
}

// The pipeline's rows (four channels, 32 bytes) each lie within one cache line, whatever block
// the allocator hands out: a row straddling two would make each SIMD load or store of it two.
TEST(SampleRing, RowsStartOnCacheLines) {
  for (const std::size_t capacity : {16u, 4096u, 65536u}) {
    const SampleRing ring(4, capacity);
    EXPECT_EQ(std::bit_cast<std::uintptr_t>(ring.rows().data) % 64, 0u) << capacity;
  }
}

// push() continues a stretch; a sample that does not follow the newest starts a new one.
TEST(SampleRing, ASampleOutOfSequenceStartsANewStretch) {
  SampleRing ring(4, 16);
  for (std::int64_t n = 0; n < 5; ++n) {
    const std::array<double, 4> v = {value(n, 0), value(n, 1), value(n, 2), value(n, 3)};
    ring.push(n, v.data());
  }
  EXPECT_EQ(ring.oldest(), 0);
  EXPECT_EQ(ring.newest(), 4);
  const std::array<double, 4> v = {value(9, 0), value(9, 1), value(9, 2), value(9, 3)};
  ring.push(9, v.data());
  EXPECT_EQ(ring.oldest(), 9);
  EXPECT_EQ(ring.newest(), 9);
  EXPECT_EQ(ring.rows().row(9)[3], value(9, 3));
  ring.clear();
  EXPECT_TRUE(ring.empty());
}

}  // namespace
}  // namespace millwatch::monitor
