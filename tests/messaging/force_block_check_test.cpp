// Encoded force_block_t messages checked before they are decoded: crafted buffers with a count
// that wraps lcm-gen's int size check, a negative count, short and long buffers, another type's
// fingerprint, more samples than allowed.

#include "msgs/force_block_check.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <limits>
#include <vector>

#include "msgs/lcm_convert.hpp"

namespace millwatch::messaging {
namespace {

/// A well-formed message of n samples (fx = i, fy = −i, fz = 0.5 i).
std::vector<std::uint8_t> encoded(int n) {
  std::vector<double> fx, fy, fz;
  for (int i = 0; i < n; ++i) {
    fx.push_back(i);
    fy.push_back(-i);
    fz.push_back(0.5 * i);
  }
  const force_block_t m = to_message({1'000'000, 7, 50000.0, fx, fy, fz});
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  EXPECT_EQ(m.encode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  return bytes;
}

/// Writes num_samples (big-endian int32 at byte 32).
void set_count(std::vector<std::uint8_t>& bytes, std::int32_t n) {
  const auto u = static_cast<std::uint32_t>(n);
  for (int i = 0; i < 4; ++i) {
    bytes[static_cast<std::size_t>(32 + i)] = static_cast<std::uint8_t>(u >> (24 - 8 * i));
  }
}

ForceBlockCheck check(const std::vector<std::uint8_t>& bytes, std::int64_t max = 4096) {
  return check_force_block(bytes.data(), bytes.size(), max);
}

TEST(ForceBlockCheck, TheLayoutIsLcmGensEncoding) {
  for (int n : {0, 1, 40, 2000}) {
    const auto bytes = encoded(n);
    EXPECT_EQ(bytes.size(), kForceBlockHeaderBytes + kForceBlockSampleBytes * n);
    const ForceBlockCheck c = check(bytes);
    EXPECT_TRUE(c.ok()) << c.describe();
    EXPECT_EQ(c.num_samples, n);
  }
}

TEST(ForceBlockCheck, AWholeMessageDecodes) {
  const auto bytes = encoded(40);
  force_block_t m;
  const ForceBlockCheck c = decode_force_block(bytes.data(), bytes.size(), 4096, m);
  ASSERT_TRUE(c.ok()) << c.describe();
  EXPECT_EQ(m.utime, 1'000'000);
  EXPECT_EQ(m.seq, 7);
  EXPECT_EQ(m.sample_rate_hz, 50000.0);
  ASSERT_EQ(m.fx_N.size(), 40u);
  ASSERT_EQ(m.fy_N.size(), 40u);
  ASSERT_EQ(m.fz_N.size(), 40u);
  EXPECT_EQ(m.fx_N[39], 39.0);
  EXPECT_EQ(m.fy_N[39], -39.0);
  EXPECT_EQ(m.fz_N[39], 19.5);
}

// lcm-gen's decode checks 8 · num_samples in int: 2²⁸ + 1 samples wrap it to a negative size, so
// it passes and the decode reads 2 GiB past a 44-byte buffer (ASan: heap-buffer-overflow in
// __double_decode_array) after resizing the arrays to what the count asks for.
TEST(ForceBlockCheck, ACountThatWrapsTheGeneratedSizeCheckIsRejectedBeforeDecoding) {
  auto bytes = encoded(0);
  bytes.resize(bytes.size() + 8);  // one double's worth of bytes after the header
  set_count(bytes, (1 << 28) + 1);
  force_block_t m;
  m.fx_N = {1.0, 2.0};
  const ForceBlockCheck c = decode_force_block(bytes.data(), bytes.size(), 4096, m);
  EXPECT_EQ(c.problem, ForceBlockProblem::kWrongLength);
  EXPECT_EQ(c.num_samples, 268435457);
  EXPECT_EQ(c.describe(),
            "36 + 24 x 268435457 = 6442451004 bytes expected for num_samples 268435457, got 44");
  EXPECT_EQ(m.fx_N, (std::vector<double>{1.0, 2.0}));  // untouched
  // The largest count, and one whose 24 · n wraps a 32-bit size to exactly the buffer's length.
  set_count(bytes, std::numeric_limits<std::int32_t>::max());
  EXPECT_EQ(check(bytes).problem, ForceBlockProblem::kWrongLength);
  auto wrapped = encoded(1);  // 60 bytes = 36 + 24 · 1 = (36 + 24 · (1 + 2²⁹)) mod 2³²
  set_count(wrapped, static_cast<std::int32_t>(1 + (1u << 29)));
  EXPECT_EQ(check(wrapped).problem, ForceBlockProblem::kWrongLength);
}

TEST(ForceBlockCheck, ANegativeCountIsRejected) {
  auto bytes = encoded(3);
  set_count(bytes, -1);
  EXPECT_EQ(check(bytes).problem, ForceBlockProblem::kNegativeCount);
  EXPECT_EQ(check(bytes).describe(), "num_samples -1 is negative");
  set_count(bytes, std::numeric_limits<std::int32_t>::min());
  EXPECT_EQ(check(bytes).problem, ForceBlockProblem::kNegativeCount);
}

TEST(ForceBlockCheck, ShortAndLongBuffersAreRejected) {
  const auto whole = encoded(40);
  for (std::size_t size : {std::size_t{0}, std::size_t{8}, std::size_t{35}}) {
    const ForceBlockCheck c = check_force_block(whole.data(), size, 4096);
    EXPECT_EQ(c.problem, ForceBlockProblem::kShorterThanHeader) << size;
  }
  EXPECT_EQ(check_force_block(whole.data(), 35, 4096).describe(),
            "35 bytes, fewer than force_block_t's 36-byte header");
  auto shorter = whole;
  shorter.pop_back();
  EXPECT_EQ(check(shorter).problem, ForceBlockProblem::kWrongLength);
  EXPECT_EQ(check(shorter).describe(),
            "36 + 24 x 40 = 996 bytes expected for num_samples 40, got 995");
  auto longer = whole;
  longer.push_back(0);
  EXPECT_EQ(check(longer).problem, ForceBlockProblem::kWrongLength);
  // A header alone that declares samples.
  std::vector<std::uint8_t> header(whole.begin(), whole.begin() + 36);
  EXPECT_EQ(check(header).problem, ForceBlockProblem::kWrongLength);
}

TEST(ForceBlockCheck, AnotherTypesFingerprintIsRejected) {
  auto bytes = encoded(2);
  bytes[7] ^= 0x01;
  const ForceBlockCheck c = check(bytes);
  EXPECT_EQ(c.problem, ForceBlockProblem::kWrongFingerprint);
  EXPECT_NE(c.describe().find("is not force_block_t's 0x"), std::string::npos) << c.describe();
}

TEST(ForceBlockCheck, MoreSamplesThanTheMaximumAreRejected) {
  const auto bytes = encoded(100);
  EXPECT_TRUE(check(bytes, 100).ok());
  const ForceBlockCheck c = check(bytes, 99);
  EXPECT_EQ(c.problem, ForceBlockProblem::kTooManySamples);
  EXPECT_EQ(c.describe(), "num_samples 100 is more than the maximum of 99");
  EXPECT_EQ(check(encoded(0), 0).problem, ForceBlockProblem::kNone);
  EXPECT_EQ(check(encoded(1), -5).problem, ForceBlockProblem::kTooManySamples);
}

// lcm-gen's decode leaves the arrays alone for num_samples 0: a reused message would keep the
// last block's samples.
TEST(ForceBlockCheck, AnEmptyBlockDecodedIntoAReusedMessageIsEmpty) {
  force_block_t m;
  const auto full = encoded(10);
  ASSERT_TRUE(decode_force_block(full.data(), full.size(), 4096, m).ok());
  ASSERT_EQ(m.fx_N.size(), 10u);
  const auto empty = encoded(0);
  ASSERT_TRUE(decode_force_block(empty.data(), empty.size(), 4096, m).ok());
  EXPECT_EQ(m.num_samples, 0);
  EXPECT_TRUE(m.fx_N.empty());
  EXPECT_TRUE(m.fy_N.empty());
  EXPECT_TRUE(m.fz_N.empty());
}

// The daemon's decode straight into its queue slot gives what lcm-gen's decode gives, to the bit
// (negative zero, a subnormal, infinities and NaN included), and touches nothing of a message
// that does not pass the check.
TEST(ForceBlockCheck, DecodingIntoArraysGivesLcmGensValues) {
  const std::vector<double> fx = {0.0, -0.0, 4.9e-324, -1.25, 1e300};
  const std::vector<double> fy = {std::numeric_limits<double>::infinity(), 2.5, -3.0, 7.0, 8.0};
  const std::vector<double> fz = {std::numeric_limits<double>::quiet_NaN(), 1.0, 2.0, 3.0, 4.0};
  const force_block_t m = to_message({123'456'789, -3, 333300.0, fx, fy, fz});
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  ASSERT_EQ(m.encode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  force_block_t generated;
  ASSERT_TRUE(decode_force_block(bytes.data(), bytes.size(), 8, generated).ok());

  std::vector<double> x(8, 99.0), y(8, 99.0), z(8, 99.0);
  ForceBlockHeader h;
  const ForceBlockCheck c =
      decode_force_block_into(bytes.data(), bytes.size(), 8, h, x.data(), y.data(), z.data());
  ASSERT_TRUE(c.ok()) << c.describe();
  EXPECT_EQ(h.utime, generated.utime);
  EXPECT_EQ(h.seq, generated.seq);
  EXPECT_EQ(h.sample_rate_hz, generated.sample_rate_hz);
  ASSERT_EQ(h.num_samples, 5u);
  const auto bits = [](double v) { return std::bit_cast<std::uint64_t>(v); };
  for (std::size_t i = 0; i < 5; ++i) {
    EXPECT_EQ(bits(x[i]), bits(generated.fx_N[i])) << i;
    EXPECT_EQ(bits(y[i]), bits(generated.fy_N[i])) << i;
    EXPECT_EQ(bits(z[i]), bits(generated.fz_N[i])) << i;
  }
  EXPECT_EQ(x[5], 99.0);  // nothing written past the block

  std::vector<double> untouched(4, 99.0);
  ForceBlockHeader h2;
  EXPECT_EQ(decode_force_block_into(bytes.data(), bytes.size(), 4, h2, untouched.data(),
                                    untouched.data(), untouched.data())
                .problem,
            ForceBlockProblem::kTooManySamples);
  EXPECT_EQ(untouched, std::vector<double>(4, 99.0));
  EXPECT_EQ(h2.num_samples, 0u);
}

}  // namespace
}  // namespace millwatch::messaging
