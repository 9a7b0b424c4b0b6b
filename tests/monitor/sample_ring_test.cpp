// The sample ring against what was pushed into it: rows addressed by absolute sample index across
// the ring's wrap, by push() and push_run(), through row() and through rows() (the rows by value
// that SIMD loops read), channels padded to a power of two.

#include "core/monitor/sample_ring.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>

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
    ring.push_run(1000, 40, [&](std::size_t i, double* row) {
      for (std::size_t c = 0; c < static_cast<std::size_t>(channels); ++c) {
        row[c] = value(1000 + static_cast<std::int64_t>(i), c);
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
