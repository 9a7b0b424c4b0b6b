#include "core/monitor/input_check.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "tests/support/allocation_counter.hpp"

namespace millwatch::monitor {
namespace {

struct Block {
  std::vector<double> fx, fy, fz;
  SampleBlock view(std::int64_t utime_us, double rate = 50000.0) const {
    return {utime_us, 0, rate, fx, fy, fz};
  }
};

Block ramp(std::size_t n, double start = 0.0) {
  Block b;
  for (std::size_t i = 0; i < n; ++i) {
    b.fx.push_back(start + static_cast<double>(i));
    b.fy.push_back(-1.0);
    b.fz.push_back(0.5);
  }
  return b;
}

/// A malformed block: its fz has a sample fewer.
Block unequal(std::size_t n) {
  Block b = ramp(n);
  b.fz.pop_back();
  return b;
}

InputCheckConfig config() {
  InputCheckConfig c;
  c.sample_rate_hz = 50000.0;  // 20 µs per sample
  c.saturation_N = {100.0, 100.0, 100.0};
  return c;
}

TEST(InputCheck, ContinuousBlocksPassUnchanged) {
  InputCheck check(config());
  const Block a = ramp(100);
  const Block b = ramp(100, 100.0);
  const auto ca = check.check(a.view(1'000'000));
  EXPECT_EQ(ca.verdict, BlockVerdict::kAccepted);
  EXPECT_EQ(ca.first_sample, 0);
  const auto cb = check.check(b.view(1'002'000));
  EXPECT_EQ(cb.verdict, BlockVerdict::kAccepted);
  EXPECT_EQ(cb.first_sample, 100);
  EXPECT_EQ(cb.gap_samples, 0);
  EXPECT_EQ(cb.fx_N[5], 105.0);
  EXPECT_EQ(check.counters().samples_accepted, 200);
  EXPECT_EQ(check.counters().samples_dropped, 0);
  EXPECT_EQ(check.utime_of(150), 1'003'000);
}

TEST(InputCheck, NonFiniteSamplesAreReplacedFlaggedAndCounted) {
  InputCheck check(config());
  Block a = ramp(10);
  a.fx[3] = std::numeric_limits<double>::quiet_NaN();
  a.fy[7] = std::numeric_limits<double>::infinity();
  const auto c = check.check(a.view(0));
  EXPECT_EQ(c.fx_N[3], 2.0);  // last good value of the channel
  EXPECT_EQ(c.fy_N[7], -1.0);
  EXPECT_EQ(c.flags[3], kFlagNonFinite);
  EXPECT_EQ(c.flags[4], 0);
  EXPECT_EQ(check.counters().nonfinite_samples, 2);
  EXPECT_EQ(check.counters().samples_flagged, 2);
  EXPECT_EQ(check.counters().samples_accepted, 10);
}

// The clean-block test takes two samples at a time: one bad value at any position of a block
// of any length (the pairs and the odd tail), in any channel, of any kind, is still found.
TEST(InputCheck, OneBadValueAnywhereIsFound) {
  const std::vector<double> bad = {std::numeric_limits<double>::quiet_NaN(),
                                   -std::numeric_limits<double>::infinity(), -100.0, 100.0};
  for (std::size_t n = 1; n <= 9; ++n) {
    for (std::size_t at = 0; at < n; ++at) {
      for (std::size_t channel = 0; channel < 3; ++channel) {
        for (const double value : bad) {
          InputCheck check(config());
          Block b = ramp(n, -50.0);
          (channel == 0 ? b.fx : channel == 1 ? b.fy : b.fz)[at] = value;
          const auto c = check.check(b.view(0));
          ASSERT_EQ(c.verdict, BlockVerdict::kAccepted);
          EXPECT_NE(c.flags[at], 0) << n << " " << at << " " << channel << " " << value;
          EXPECT_EQ(check.counters().samples_flagged, 1) << n << " " << at << " " << value;
        }
      }
    }
  }
}

// The hand-on buffers are left uninitialised at construction (only a block that long touches
// them all): a block of max_block_samples with a bad sample last comes out whole, every sample
// and flag written, and a clean block after it has no flag left over.
TEST(InputCheck, ABlockOfTheMaximumLengthIsHandedOnWhole) {
  InputCheckConfig c = config();
  c.max_block_samples = 3000;
  InputCheck check(c);
  Block a = ramp(3000, -1500.0);
  for (double& x : a.fx) {
    x *= 0.05;  // within ±75 N: below saturation
  }
  a.fz.back() = std::numeric_limits<double>::quiet_NaN();
  const auto ca = check.check(a.view(0));
  ASSERT_EQ(ca.verdict, BlockVerdict::kAccepted);
  ASSERT_EQ(ca.fx_N.size(), 3000U);
  for (std::size_t i = 0; i < 3000; ++i) {
    ASSERT_EQ(ca.fx_N[i], a.fx[i]) << i;
    ASSERT_EQ(ca.fy_N[i], -1.0) << i;
    ASSERT_EQ(ca.fz_N[i], 0.5) << i;  // the NaN last: the channel's last good value
    ASSERT_EQ(ca.flags[i], i + 1 == 3000 ? kFlagNonFinite : 0) << i;
  }
  Block b = ramp(3000, -1500.0);
  b.fx = a.fx;
  const auto cb = check.check(b.view(60'000));
  ASSERT_EQ(cb.verdict, BlockVerdict::kAccepted);
  for (std::size_t i = 0; i < 3000; ++i) {
    ASSERT_EQ(cb.flags[i], 0) << i;
  }
  EXPECT_EQ(check.check(ramp(3001).view(120'000)).verdict, BlockVerdict::kRejected);
  EXPECT_EQ(check.counters().samples_flagged, 1);
}

TEST(InputCheck, ImplausibleValuesAreTreatedLikeNonFiniteOnes) {
  InputCheck check(config());
  Block a = ramp(4);
  a.fy[2] = 1.4e306;  // a corrupt value
  const auto c = check.check(a.view(0));
  EXPECT_EQ(c.fy_N[2], -1.0);
  EXPECT_EQ(c.flags[2], kFlagNonFinite);
  EXPECT_EQ(check.counters().nonfinite_samples, 1);
}

TEST(InputCheck, ABlockRejectedAtItsTimeLeavesOneHoleCountedOnce) {
  InputCheck check(config());
  check.check(ramp(100).view(0));
  const auto bad = check.check(ramp(100).view(2000, 20000.0));  // wrong rate, right time
  EXPECT_EQ(bad.verdict, BlockVerdict::kRejected);
  const auto next = check.check(ramp(100).view(4000));
  EXPECT_EQ(next.verdict, BlockVerdict::kAccepted);
  EXPECT_EQ(next.gap_samples, 100);
  EXPECT_EQ(next.first_sample, 200);
  EXPECT_EQ(check.counters().samples_dropped, 100);
  EXPECT_EQ(check.counters().gaps, 1);
}

// A hole and samples missing after it are one discontinuity before the next good block.
TEST(InputCheck, AHoleFollowedByAGapIsOneGap) {
  InputCheck check(config());
  check.check(ramp(100).view(0));
  EXPECT_EQ(check.check(unequal(100).view(2000)).verdict, BlockVerdict::kRejected);  // a hole
  const auto next = check.check(ramp(100).view(4000 + 50 * 20));  // then 50 samples missing
  EXPECT_EQ(next.verdict, BlockVerdict::kAccepted);
  EXPECT_EQ(next.gap_samples, 150);
  EXPECT_EQ(next.first_sample, 250);
  EXPECT_EQ(check.counters().samples_dropped, 150);
  EXPECT_EQ(check.counters().gaps, 1);
  EXPECT_EQ(check.utime_of(250), 5000);
}

// A block rejected at its time whose length or rate says more than the stream skipped: the next
// good block, within that slot, cuts the hole short instead of being refused as out of order
// (with the hole's full length, every good block for 1.4 s after it was).
TEST(InputCheck, ABlockWithinAHoleCutsItShort) {
  InputCheck check(config());
  check.check(ramp(100).view(0));
  const auto longer = check.check(ramp(70'000).view(2000));  // beyond max_block_samples
  EXPECT_EQ(longer.verdict, BlockVerdict::kRejected);
  const auto next = check.check(ramp(100).view(4000));  // 100 samples after the first block
  EXPECT_EQ(next.verdict, BlockVerdict::kAccepted);
  EXPECT_EQ(next.gap_samples, 100);
  EXPECT_EQ(next.first_sample, 200);
  EXPECT_EQ(check.counters().gaps, 1);
  EXPECT_EQ(check.counters().out_of_order_blocks, 0);
  EXPECT_EQ(check.counters().samples_dropped, 70'000);  // the rejected block's own samples
  EXPECT_EQ(check.check(ramp(100).view(6000)).verdict, BlockVerdict::kAccepted);
  EXPECT_EQ(check.utime_of(300), 6000);

  // 100 samples at twice the rate last 1 ms, not 2: the block after them is not refused.
  InputCheck rate(config());
  rate.check(ramp(100).view(0));
  EXPECT_EQ(rate.check(ramp(100).view(2000, 100000.0)).verdict, BlockVerdict::kRejected);
  const auto after = rate.check(ramp(100).view(3000));
  EXPECT_EQ(after.verdict, BlockVerdict::kAccepted);
  EXPECT_EQ(after.gap_samples, 50);
  EXPECT_EQ(after.first_sample, 150);
  EXPECT_EQ(rate.counters().gaps, 1);
  EXPECT_EQ(rate.counters().samples_dropped, 100);

  // A block before the hole is still out of order; one where the hole began ends it at once.
  InputCheck again(config());
  again.check(ramp(100).view(0));
  again.check(unequal(100).view(2000));
  EXPECT_EQ(again.check(ramp(100).view(0)).verdict, BlockVerdict::kRejected);
  EXPECT_EQ(again.counters().out_of_order_blocks, 1);
  const auto resent = again.check(ramp(100).view(2000));
  EXPECT_EQ(resent.verdict, BlockVerdict::kAccepted);
  EXPECT_EQ(resent.gap_samples, 0);
  EXPECT_EQ(resent.first_sample, 100);
  EXPECT_EQ(again.counters().gaps, 0);

  // A block rejected later than expected, then the too long block, then a good one within its
  // slot: the gap before the next good block finds the first one's samples counted once, whether
  // it came before the too long block or within its slot.
  for (const bool late_block_first : {true, false}) {
    InputCheck spans(config());
    spans.check(ramp(100).view(0));
    if (late_block_first) {
      spans.check(unequal(100).view(4000));  // 100 samples late: covers 4,000–6,000 µs
    }
    spans.check(ramp(70'000).view(2000));  // at its time, too long
    if (!late_block_first) {
      spans.check(unequal(100).view(4000));  // within the long block's slot
    }
    EXPECT_EQ(spans.check(ramp(100).view(2000)).gap_samples, 0);  // at the hole's start
    const auto later = spans.check(ramp(100).view(6000));         // after 4,000–6,000 µs
    EXPECT_EQ(later.verdict, BlockVerdict::kAccepted);
    EXPECT_EQ(later.gap_samples, 100);
    EXPECT_EQ(spans.counters().samples_dropped, 70'100) << late_block_first;
    EXPECT_EQ(spans.counters().gaps, 1);
  }

  // Across a reload, the successor's first block within the hole ends it too.
  InputCheck before(config());
  before.check(ramp(100).view(0));
  before.check(ramp(70'000).view(2000));
  InputCheck successor(config());
  successor.continue_after(before);
  const auto first = successor.check(ramp(100).view(2000 + 30 * 20));
  EXPECT_EQ(first.verdict, BlockVerdict::kAccepted);
  EXPECT_EQ(first.gap_samples, 30);
  EXPECT_EQ(successor.counters().gaps, 1);
}

// A hole just before a reload is the successor's gap: its first block reports it and counts it.
TEST(InputCheck, AHoleBeforeAReloadIsCountedAsAGap) {
  InputCheck before(config());
  before.check(ramp(100).view(0));
  before.check(unequal(100).view(2000));  // rejected at its time
  EXPECT_EQ(before.counters().gaps, 0);
  InputCheck after(config());
  after.continue_after(before);
  EXPECT_EQ(after.next_utime(), 4000);
  const auto first = after.check(ramp(100).view(4000));
  EXPECT_EQ(first.verdict, BlockVerdict::kAccepted);
  EXPECT_EQ(first.gap_samples, 100);
  EXPECT_EQ(after.counters().gaps, 1);
  EXPECT_EQ(before.counters().samples_dropped + after.counters().samples_dropped, 100);
  // Late as well: still one gap, with both parts.
  InputCheck late(config());
  late.continue_after(before);
  const auto first_late = late.check(ramp(100).view(4000 + 30 * 20));
  EXPECT_EQ(first_late.gap_samples, 130);
  EXPECT_EQ(late.counters().gaps, 1);
  EXPECT_EQ(before.counters().samples_dropped + late.counters().samples_dropped, 130);
}

// A block rejected later than expected (malformed, after a drop) lies in the gap before the
// next good block: its samples are counted once, as the rejected block's, not again in the gap.
TEST(InputCheck, ABlockRejectedInsideAGapIsNotCountedTwice) {
  InputCheck check(config());
  check.check(ramp(100).view(0));                         // due next at 2,000 µs
  const auto bad = check.check(unequal(100).view(4000));  // 100 samples late
  EXPECT_EQ(bad.verdict, BlockVerdict::kRejected);
  EXPECT_EQ(check.counters().samples_dropped, 100);
  const auto next = check.check(ramp(100).view(6000));  // 200 samples after the first block
  EXPECT_EQ(next.verdict, BlockVerdict::kAccepted);
  EXPECT_EQ(next.gap_samples, 200);
  EXPECT_EQ(next.first_sample, 300);
  EXPECT_EQ(check.counters().samples_dropped, 200);
  EXPECT_EQ(check.counters().gaps, 1);
  EXPECT_EQ(check.counters().blocks_rejected, 1);
}

// A rejected block with a corrupt but plausible utime ahead of the stream refuses none of the
// good blocks after it; once the stream has passed its time it covers no later gap.
TEST(InputCheck, ARejectedBlockTheStreamPassesCoversNoLaterGap) {
  InputCheck check(config());
  check.check(ramp(100).view(0));
  EXPECT_EQ(check.check(ramp(100).view(5000, 20000.0)).verdict, BlockVerdict::kRejected);
  for (std::int64_t utime = 2000; utime <= 8000; utime += 2000) {  // over 5,000 µs, no gap
    const auto c = check.check(ramp(100).view(utime));
    EXPECT_EQ(c.verdict, BlockVerdict::kAccepted) << utime;
    EXPECT_EQ(c.gap_samples, 0) << utime;
  }
  const auto after_gap = check.check(ramp(100).view(12'000));  // 100 samples missing
  EXPECT_EQ(after_gap.gap_samples, 100);
  EXPECT_EQ(check.counters().samples_dropped, 200);  // the rejected block's and the gap's
}

// More rejected blocks far ahead (corrupt times) than the check keeps spans for: the gap the
// stream meets first still counts each missing sample once.
TEST(InputCheck, ManyRejectedBlocksFarAheadLeaveTheGapNearByAlone) {
  InputCheck check(config());
  check.check(ramp(100).view(0));
  for (int i = 0; i < 20; ++i) {  // far ahead, apart (corrupt times), then two in the coming gap
    check.check(unequal(100).view(1'000'000'000 + i * 1'000'000));
  }
  check.check(unequal(100).view(2000));  // at its time: a hole, not ahead
  check.check(unequal(100).view(6000));
  check.check(unequal(100).view(8000));
  const std::int64_t dropped_before = check.counters().samples_dropped;
  EXPECT_EQ(dropped_before, 2300);
  const auto next = check.check(ramp(100).view(10'000));  // the hole, then 300 samples missing
  EXPECT_EQ(next.verdict, BlockVerdict::kAccepted);
  EXPECT_EQ(next.first_sample, 500);
  EXPECT_EQ(check.counters().samples_dropped, dropped_before + 100);
}

// A run of rejected blocks (a DAQ briefly at another rate, a sender writing broken blocks) is
// one stretch of time, however many blocks: each sample is counted once.
TEST(InputCheck, ARunOfRejectedBlocksInAGapIsCountedOnce) {
  InputCheck check(config());
  check.check(ramp(100).view(0));  // due next at 2,000 µs; that block is lost
  for (int i = 0; i < 20; ++i) {
    EXPECT_EQ(check.check(unequal(100).view(4000 + i * 2000)).verdict, BlockVerdict::kRejected);
  }
  const auto next = check.check(ramp(100).view(44'000));
  EXPECT_EQ(next.gap_samples, 2100);
  EXPECT_EQ(check.counters().samples_dropped, 2100);  // 2,000 rejected, 100 lost
}

// Only what a rejected block covers of the gap is counted already: not the part beyond the next
// good block, not a block covered twice, not one the stream's time has moved past.
TEST(InputCheck, OnlyWhatARejectedBlockCoversOfTheGapIsCountedAlready) {
  {
    InputCheck check(config());
    check.check(ramp(100).view(0));
    check.check(unequal(300).view(4000));  // 4,000–10,000 µs
    EXPECT_EQ(check.check(ramp(100).view(6000)).gap_samples, 200);
    EXPECT_EQ(check.counters().samples_dropped, 300 + 100);  // 2,000–4,000 µs were lost
  }
  {
    InputCheck check(config());
    check.check(ramp(100).view(0));
    check.check(unequal(100).view(4000));
    check.check(unequal(100).view(4000));  // the same block again
    EXPECT_EQ(check.check(ramp(100).view(6000)).gap_samples, 200);
    EXPECT_EQ(check.counters().samples_dropped, 200 + 100);
  }
  {
    InputCheck check(config());
    check.check(ramp(100).view(0));
    check.check(unequal(100).view(4000));  // ahead
    check.check(unequal(300).view(2000));  // at its time: a hole to 8,000 µs, over the first
    const auto next = check.check(ramp(100).view(10'000));
    EXPECT_EQ(next.gap_samples, 300 + 100);
    EXPECT_EQ(next.first_sample, 500);
    EXPECT_EQ(check.counters().samples_dropped, 100 + 300 + 100);  // 8,000–10,000 µs lost
  }
}

// More separate rejected blocks in one gap than spans are kept (every other block lost), a
// sender briefly at a lower rate, empty blocks, and spans a hole passed over: each sample once.
TEST(InputCheck, RejectedBlocksInAGapAreCountedOnceHoweverManyAndWhateverTheirRate) {
  {
    InputCheck check(config());
    check.check(ramp(100).view(0));
    for (int i = 0; i < 9; ++i) {
      check.check(unequal(100).view(4000 + i * 4000));
    }
    EXPECT_EQ(check.check(ramp(100).view(40'000)).gap_samples, 1900);
    EXPECT_EQ(check.counters().samples_dropped, 1900);
  }
  {
    InputCheck check(config());
    check.check(ramp(100).view(0));
    for (int i = 0; i < 9; ++i) {  // 5,000 µs each, one after the other
      check.check(ramp(100).view(7000 + i * 5000, 20000.0));
    }
    EXPECT_EQ(check.check(ramp(100).view(52'000)).gap_samples, 2500);
    EXPECT_EQ(check.counters().samples_dropped, 2500);
  }
  {
    InputCheck check(config());
    check.check(ramp(100).view(0));
    for (int i = 0; i < 8; ++i) {
      check.check(Block{}.view(3000 + i * 100));
    }
    check.check(ramp(100).view(6000, 20000.0));  // 6,000–11,000 µs
    EXPECT_EQ(check.check(ramp(100).view(12'000)).gap_samples, 500);
    EXPECT_EQ(check.counters().samples_dropped, 500);
  }
  {
    InputCheck check(config());
    check.check(ramp(100).view(0));
    for (int i = 0; i < 8; ++i) {
      check.check(unequal(100).view(4000 + i * 4000));
    }
    check.check(unequal(1700).view(2000));  // at its time: a hole over all eight, to 36,000 µs
    check.check(unequal(100).view(38'000));
    EXPECT_EQ(check.check(ramp(100).view(40'000)).gap_samples, 1700 + 200);
    EXPECT_EQ(check.counters().samples_dropped, 800 + 1700 + 200);
  }
}

// At 333.3 kHz a sample is 3.0003 µs and a DAQ's utimes are whole µs: what two runs of rejected
// blocks held is subtracted exactly, not rounded from their µs.
TEST(InputCheck, RejectedRunsAtA333kHzRateAreSubtractedExactly) {
  InputCheckConfig c = config();
  c.sample_rate_hz = 333300.0;
  InputCheck check(c);
  auto at = [](int k) { return static_cast<std::int64_t>(k * 3000.3); };  // 1,000-sample blocks
  Block b = ramp(1000);
  check.check(b.view(at(0), 333300.0));
  for (const int k : {10, 11, 12, 13, 20, 21, 22, 23}) {
    Block bad = unequal(1000);
    check.check(bad.view(at(k), 333300.0));
  }
  EXPECT_EQ(check.check(b.view(at(25), 333300.0)).gap_samples, 24000);
  EXPECT_EQ(check.counters().samples_dropped, 24000);
}

// A rejected block only partly in a gap (the next good block lies inside its time) is subtracted
// by its share, and its share beyond that block by the next gap: never more than it counted, even
// with a corrupt rate in its header that makes its span 1,000× too long.
TEST(InputCheck, ARejectedBlockPartlyInAGapIsSubtractedByItsShare) {
  {
    InputCheck check(config());
    check.check(ramp(100).view(0));
    check.check(ramp(100).view(6000, 20000.0));  // 6,000–11,000 µs
    EXPECT_EQ(check.check(ramp(100).view(8000)).gap_samples, 300);
    EXPECT_EQ(check.counters().samples_dropped, 100 + 300 - 40);  // 2,000 of its 5,000 µs
    EXPECT_EQ(check.check(ramp(100).view(12'000)).gap_samples, 100);
    EXPECT_EQ(check.counters().samples_dropped, 360 + 100 - 20);  // 10,000–11,000 µs
  }
  {
    InputCheck check(config());
    check.check(ramp(100).view(0));
    check.check(ramp(100).view(4000, 50.0));  // "50 Hz": 4,000–2,004,000 µs
    std::int64_t lost = 100;                  // 2,000–4,000 µs
    for (std::int64_t utime = 6000; utime <= 104'000; utime += 4000) {  // every other one lost
      check.check(ramp(100).view(utime));
      lost += 100;
    }
    EXPECT_GE(check.counters().samples_dropped, lost - 100);
    EXPECT_LE(check.counters().samples_dropped, lost + 100);
  }
}

// restart() forgets a hole and a continuation: the new stream starts at its first block.
TEST(InputCheck, RestartForgetsAHoleAndAContinuation) {
  InputCheck check(config());
  check.check(ramp(100).view(0));
  check.check(unequal(100).view(2000));  // a hole
  check.restart();
  const auto c = check.check(ramp(100).view(50'000));
  EXPECT_EQ(c.gap_samples, 0);
  EXPECT_EQ(check.counters().gaps, 0);
  InputCheck continued(config());
  continued.continue_after(2000);
  continued.restart();
  EXPECT_FALSE(continued.next_utime());
}

// A reload's successor takes over what its predecessor's rejected blocks covered.
TEST(InputCheck, AReloadKeepsWhatRejectedBlocksCovered) {
  InputCheck before(config());
  before.check(ramp(100).view(0));
  before.check(unequal(100).view(4000));
  InputCheck after(config());
  after.continue_after(before);
  EXPECT_EQ(after.next_utime(), 2000);
  EXPECT_EQ(after.check(ramp(100).view(6000)).gap_samples, 200);
  EXPECT_EQ(before.counters().samples_dropped + after.counters().samples_dropped, 200);
  // At another rate the successor starts a stream of its own.
  InputCheckConfig other = config();
  other.sample_rate_hz = 25000.0;
  InputCheck elsewhere(other);
  elsewhere.continue_after(before);
  EXPECT_FALSE(elsewhere.next_utime());
}

TEST(InputCheck, SaturatedSamplesAreKeptAndFlagged) {
  InputCheck check(config());
  Block a = ramp(5);
  a.fz[2] = -100.0;
  const auto c = check.check(a.view(0));
  EXPECT_EQ(c.fz_N[2], -100.0);
  EXPECT_EQ(c.flags[2], kFlagSaturated);
  EXPECT_EQ(check.counters().saturated_samples, 1);
}

// Each channel is held to its own charge amplifier's range: 30 N is within x's (50 N) and y's
// (200 N) but at z's (30 N) — flagged where it is z's sample, not where it is x's or y's — and
// −60 N is beyond x's and z's ranges, within y's; at every position of blocks of odd and even
// lengths.
TEST(InputCheck, EachChannelIsHeldToItsOwnRange) {
  InputCheckConfig cfg = config();
  cfg.saturation_N = {50.0, 200.0, 30.0};
  for (std::size_t n = 2; n <= 5; ++n) {
    for (std::size_t at = 0; at < n; ++at) {
      for (std::size_t channel = 0; channel < 3; ++channel) {
        for (const double value : {30.0, -60.0}) {
          InputCheck check(cfg);
          Block b;
          b.fx.assign(n, 1.0);
          b.fy.assign(n, 1.0);
          b.fz.assign(n, 1.0);
          (channel == 0 ? b.fx : channel == 1 ? b.fy : b.fz)[at] = value;
          const auto c = check.check(b.view(0));
          ASSERT_EQ(c.verdict, BlockVerdict::kAccepted);
          const double range = cfg.saturation_N[channel];
          const bool saturated = std::fabs(value) >= range;
          EXPECT_EQ(c.flags[at], saturated ? kFlagSaturated : 0)
              << n << " " << at << " " << channel << " " << value;
          EXPECT_EQ(check.counters().saturated_samples, saturated ? 1 : 0);
          EXPECT_EQ((channel == 0 ? c.fx_N : channel == 1 ? c.fy_N : c.fz_N)[at], value);
        }
      }
    }
  }
}

/// Whether a sample of input channel a is handed on as it is, by the definition: finite,
/// plausible and below the channel's saturation.
bool as_it_is(double v, const InputCheckConfig& c, std::size_t a) {
  return std::isfinite(v) && std::fabs(v) <= c.plausible_N && std::fabs(v) < c.saturation_N[a];
}

// sample_limits() is the definition: |v| ≤ limit[a] exactly when a sample of channel a is
// handed on as it is, at the edges of the saturation and of plausibility.
TEST(InputCheck, SampleLimitsAreWhatIsHandedOnAsItIs) {
  InputCheckConfig cfg = config();
  cfg.saturation_N = {50.0, 2e6, std::numeric_limits<double>::infinity()};
  const InputCheck check(cfg);
  const std::array<double, 3>& limit = check.sample_limits();
  const double inf = std::numeric_limits<double>::infinity();
  for (std::size_t a = 0; a < 3; ++a) {
    for (const double edge : {50.0, 1e6, 2e6}) {
      for (const double v : {std::nextafter(edge, 0.0), edge, std::nextafter(edge, inf)}) {
        for (const double sv : {v, -v}) {
          EXPECT_EQ(std::fabs(sv) <= limit[a], as_it_is(sv, cfg, a)) << a << " " << sv;
        }
      }
    }
    EXPECT_FALSE(std::numeric_limits<double>::quiet_NaN() <= limit[a]);
    EXPECT_FALSE(inf <= limit[a]);
  }
}

// check_time() and check_samples() — given whether every sample is handed on as it is, found
// by the definition — give what check() gives, block after block and in the counters: on time
// and late, with a NaN, a saturated or an implausible sample, a rejected block, a gap.
TEST(InputCheck, InTwoStepsItIsCheck) {
  InputCheckConfig cfg = config();
  cfg.saturation_N = {50.0, 200.0, 30.0};
  InputCheck one(cfg), two(cfg);
  struct Step {
    std::int64_t utime_us;
    std::size_t at;  // a sample to change (n: none)
    double value;
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Step> steps = {
      {1'000'000, 99, 0.0},  {1'000'200, 3, nan},  {1'000'400, 9, 40.0},   // saturated in z
      {1'000'600, 0, 2e6},   {1'000'600, 99, 0.0},                         // then out of order
      {1'001'000, 99, 0.0},                                                // a gap of 10
      {1'001'200, 9, -31.0}, {1'001'400, 99, 0.0}, {1'001'400, 99, 0.0}};  // repeated
  std::int64_t k = 0;
  for (const Step& step : steps) {
    Block b = ramp(10, static_cast<double>(k++));
    for (auto* channel : {&b.fx, &b.fy, &b.fz}) {
      if (step.at < channel->size()) {
        (*channel)[step.at] = step.value;
      }
    }
    const SampleBlock view = b.view(step.utime_us);
    const CheckedBlock a = one.check(view);
    const CheckedBlock timed = two.check_time(view);
    CheckedBlock c = timed;
    if (timed.verdict == BlockVerdict::kAccepted) {
      bool within = true;
      for (std::size_t i = 0; i < b.fx.size(); ++i) {
        within = within && as_it_is(b.fx[i], cfg, 0) && as_it_is(b.fy[i], cfg, 1) &&
                 as_it_is(b.fz[i], cfg, 2);
      }
      c = two.check_samples(view, timed, within);
    }
    ASSERT_EQ(a.verdict, c.verdict) << step.utime_us;
    EXPECT_EQ(a.first_sample, c.first_sample) << step.utime_us;
    EXPECT_EQ(a.gap_samples, c.gap_samples) << step.utime_us;
    EXPECT_EQ(a.nonfinite_samples, c.nonfinite_samples) << step.utime_us;
    EXPECT_EQ(a.saturated_samples, c.saturated_samples) << step.utime_us;
    EXPECT_EQ(a.problem, c.problem) << step.utime_us;
    ASSERT_EQ(a.fx_N.size(), c.fx_N.size());
    for (std::size_t i = 0; i < a.fx_N.size(); ++i) {
      EXPECT_EQ(a.flags[i], c.flags[i]) << step.utime_us << " " << i;
      for (const auto& [x, y] : {std::pair{a.fx_N[i], c.fx_N[i]}, std::pair{a.fy_N[i], c.fy_N[i]},
                                 std::pair{a.fz_N[i], c.fz_N[i]}}) {
        EXPECT_TRUE(x == y || (std::isnan(x) && std::isnan(y))) << step.utime_us << " " << i;
      }
    }
    const InputCounters& p = one.counters();
    const InputCounters& q = two.counters();
    EXPECT_EQ(p.samples_in, q.samples_in);
    EXPECT_EQ(p.samples_accepted, q.samples_accepted);
    EXPECT_EQ(p.samples_dropped, q.samples_dropped);
    EXPECT_EQ(p.samples_flagged, q.samples_flagged);
    EXPECT_EQ(p.nonfinite_samples, q.nonfinite_samples);
    EXPECT_EQ(p.saturated_samples, q.saturated_samples);
    EXPECT_EQ(p.gaps, q.gaps);
    EXPECT_EQ(p.out_of_order_blocks, q.out_of_order_blocks);
    EXPECT_EQ(p.blocks_rejected, q.blocks_rejected);
    EXPECT_EQ(one.next_sample(), two.next_sample());
  }
  EXPECT_EQ(one.counters().blocks_rejected, 2);  // both out of order
  EXPECT_EQ(one.counters().gaps, 1);
  EXPECT_EQ(one.counters().nonfinite_samples, 2);
  EXPECT_EQ(one.counters().saturated_samples, 2);
}

TEST(InputCheck, GapsAreCountedAsDroppedSamplesAndKeepTime) {
  InputCheck check(config());
  check.check(ramp(100).view(0));
  const auto c = check.check(ramp(100).view(2000 + 50 * 20));  // 50 samples missing
  EXPECT_EQ(c.verdict, BlockVerdict::kAccepted);
  EXPECT_EQ(c.gap_samples, 50);
  EXPECT_EQ(c.first_sample, 150);
  EXPECT_EQ(check.counters().gaps, 1);
  EXPECT_EQ(check.counters().samples_dropped, 50);
}

TEST(InputCheck, OutOfOrderAndRepeatedBlocksAreRejected) {
  InputCheck check(config());
  check.check(ramp(100).view(10'000));
  check.check(ramp(100).view(12'000));
  const auto repeated = check.check(ramp(100).view(12'000));
  EXPECT_EQ(repeated.verdict, BlockVerdict::kRejected);
  const auto older = check.check(ramp(100).view(10'000));
  EXPECT_EQ(older.verdict, BlockVerdict::kRejected);
  EXPECT_EQ(check.counters().out_of_order_blocks, 2);
  EXPECT_EQ(check.counters().samples_dropped, 200);
  // The stream continues where it was.
  EXPECT_EQ(check.check(ramp(100).view(14'000)).gap_samples, 0);
}

TEST(InputCheck, MalformedBlocksAreRejectedWithAReason) {
  InputCheck check(config());
  Block bad = ramp(10);
  bad.fy.pop_back();
  const auto c = check.check(bad.view(0));
  EXPECT_EQ(c.verdict, BlockVerdict::kRejected);
  EXPECT_EQ(c.problem, "channels of unequal length");
  EXPECT_EQ(check.check(ramp(10).view(0, 20000.0)).problem,
            "sample rate differs from the configured one (the block's 20000 Hz, "
            "sample_rate_hz 50000 Hz)");
  EXPECT_EQ(check.check(Block{}.view(0)).problem, "empty block");
  EXPECT_EQ(check.counters().blocks_rejected, 3);
}

// A block from the network can carry any utime: one beyond ±2⁵³ µs is rejected with its
// reason and counted, before any time arithmetic (UBSan saw a signed overflow here with −2⁶³),
// and leaves the stream's timing as it was.
TEST(InputCheck, CorruptUtimesAreRejectedWithoutOverflowAndLeaveTheTimingAlone) {
  constexpr std::int64_t kMin = std::numeric_limits<std::int64_t>::min();
  constexpr std::int64_t kMax = std::numeric_limits<std::int64_t>::max();
  InputCheck check(config());
  const Block a = ramp(100);
  // Before the stream has started, then after it.
  EXPECT_EQ(check.check(a.view(kMin)).problem, "utime beyond +-2^53 us (a corrupt time)");
  EXPECT_EQ(check.check(a.view(0)).verdict, BlockVerdict::kAccepted);
  for (const std::int64_t utime :
       {kMin, kMax, kMin + 1, -kMaxAbsUtime_us - 1, kMaxAbsUtime_us + 1}) {
    const auto c = check.check(a.view(utime));
    EXPECT_EQ(c.verdict, BlockVerdict::kRejected) << utime;
    EXPECT_EQ(c.problem, "utime beyond +-2^53 us (a corrupt time)") << utime;
  }
  // Rejected for another reason as well (wrong rate): still no arithmetic on the time.
  EXPECT_EQ(check.check(a.view(kMin, 20000.0)).verdict, BlockVerdict::kRejected);
  EXPECT_EQ(check.counters().blocks_rejected, 7);
  EXPECT_EQ(check.counters().samples_dropped, 700);
  EXPECT_EQ(check.counters().gaps, 0);
  EXPECT_EQ(check.counters().out_of_order_blocks, 0);
  // The stream goes on where it was: no hole, no gap.
  const auto next = check.check(a.view(2000));
  EXPECT_EQ(next.verdict, BlockVerdict::kAccepted);
  EXPECT_EQ(next.first_sample, 100);
  EXPECT_EQ(next.gap_samples, 0);
  EXPECT_EQ(check.utime_of(200), 4000);
}

// Near the ends of the accepted range, one after the other: a gap of almost 2⁵⁴ µs, no
// overflow. (At that distance from the stream's start a double resolves 4 µs.)
TEST(InputCheck, UtimesAtTheEndsOfTheRangeMakeAGapWithoutOverflow) {
  InputCheck check(config());
  const Block a = ramp(100);
  const std::int64_t end_us = kMaxAbsUtime_us - kMaxAbsUtime_us % 20;  // on the 20 µs grid
  EXPECT_EQ(check.check(a.view(-end_us)).verdict, BlockVerdict::kAccepted);
  const auto far = check.check(a.view(end_us));
  EXPECT_EQ(far.verdict, BlockVerdict::kAccepted);
  const std::int64_t expected_gap = (2 * end_us - 2000) / 20;  // 20 µs per sample
  EXPECT_NEAR(static_cast<double>(far.gap_samples), static_cast<double>(expected_gap), 1.0);
  EXPECT_NEAR(static_cast<double>(check.utime_of(far.first_sample)), static_cast<double>(end_us),
              4.0);
  EXPECT_EQ(check.counters().samples_dropped, far.gap_samples);
  // Going back from there is out of order, however far.
  const auto back = check.check(a.view(-kMaxAbsUtime_us));
  EXPECT_EQ(back.verdict, BlockVerdict::kRejected);
  EXPECT_EQ(check.counters().out_of_order_blocks, 1);
}

TEST(InputCheck, ANanSampleRateIsRejected) {
  InputCheck check(config());
  const auto c = check.check(ramp(10).view(0, std::numeric_limits<double>::quiet_NaN()));
  EXPECT_EQ(c.verdict, BlockVerdict::kRejected);
  EXPECT_EQ(c.problem,
            "sample rate differs from the configured one (the block's nan Hz, "
            "sample_rate_hz 50000 Hz)");
  // Both rates said (after a reload that changed the configured one, which is wrong is the
  // user's to see).
  const auto other = check.check(ramp(10).view(0, 333300.0));
  EXPECT_EQ(other.problem,
            "sample rate differs from the configured one (the block's 333300 Hz, "
            "sample_rate_hz 50000 Hz)");
}

// After restart() the next block starts a new stream at its own time; sample numbers go on.
TEST(InputCheck, RestartStartsANewStreamAtTheNextBlocksTime) {
  InputCheck check(config());
  check.check(ramp(100).view(1'000'000));
  check.restart();
  const auto c = check.check(ramp(100).view(-5'000'000));
  EXPECT_EQ(c.verdict, BlockVerdict::kAccepted);
  EXPECT_EQ(c.first_sample, 100);
  EXPECT_EQ(c.gap_samples, 0);
  EXPECT_EQ(check.utime_of(100), -5'000'000);
  EXPECT_EQ(check.utime_of(150), -4'999'000);
}

// A reload's successor goes on from the time its predecessor expected next (2,000 µs here):
// samples lost in between are a gap counted once, and a block the predecessor had is rejected.
TEST(InputCheck, AContinuedStreamCountsTheGapSinceItsPredecessorOnce) {
  {
    InputCheck check(config());
    EXPECT_FALSE(check.next_utime());
    check.continue_after(2000);
    EXPECT_EQ(check.next_utime(), 2000);
    const auto c = check.check(ramp(100).view(2000));  // on time: nothing lost
    EXPECT_EQ(c.verdict, BlockVerdict::kAccepted);
    EXPECT_EQ(c.gap_samples, 0);
    EXPECT_EQ(check.counters().samples_dropped, 0);
    EXPECT_EQ(check.next_utime(), 4000);
  }
  {
    InputCheck check(config());
    check.continue_after(2000);
    const auto c = check.check(ramp(100).view(22000));  // 1,000 samples later
    EXPECT_EQ(c.verdict, BlockVerdict::kAccepted);
    EXPECT_EQ(c.gap_samples, 1000);
    EXPECT_EQ(c.first_sample, 0);  // the stream's timing starts at it
    EXPECT_EQ(check.utime_of(0), 22000);
    EXPECT_EQ(check.counters().samples_dropped, 1000);
    EXPECT_EQ(check.counters().gaps, 1);
  }
  {
    InputCheck check(config());
    check.continue_after(2000);
    const auto old = check.check(ramp(100).view(0));  // the predecessor's last block again
    EXPECT_EQ(old.verdict, BlockVerdict::kRejected);
    EXPECT_EQ(check.counters().out_of_order_blocks, 1);
    EXPECT_EQ(check.check(ramp(100).view(2000)).gap_samples, 0);  // the continuation holds
    EXPECT_EQ(check.counters().samples_dropped, 100);             // the repeated block's
  }
  {
    InputCheck check(config());
    check.continue_after(2000);
    // Rejected at the time expected: the continuation holds (a good block at the same time is
    // not refused), and the samples it covered are not counted again in a gap.
    EXPECT_EQ(check.check(ramp(100).view(2000, 20000.0)).verdict, BlockVerdict::kRejected);
    EXPECT_EQ(check.next_utime(), 2000);
    const auto good = check.check(ramp(100).view(2000));
    EXPECT_EQ(good.verdict, BlockVerdict::kAccepted);
    EXPECT_EQ(good.gap_samples, 0);
    EXPECT_EQ(check.counters().samples_dropped, 100);
  }
  {
    InputCheck check(config());
    check.continue_after(2000);
    EXPECT_EQ(check.check(unequal(100).view(2000)).verdict, BlockVerdict::kRejected);
    EXPECT_EQ(check.check(ramp(100).view(4000)).gap_samples, 100);  // its slot
    EXPECT_EQ(check.counters().samples_dropped, 100);
  }
  {
    InputCheck check(config());
    check.continue_after(2000);
    // Later: 2,000–12,000 µs were lost, 12,000–17,000 rejected (100 samples at 20 kHz).
    EXPECT_EQ(check.check(ramp(100).view(12000, 20000.0)).verdict, BlockVerdict::kRejected);
    EXPECT_EQ(check.next_utime(), 2000);
    EXPECT_EQ(check.check(ramp(100).view(17000)).gap_samples, 750);
    EXPECT_EQ(check.counters().samples_dropped, 750);
  }
}

TEST(InputCheck, SteadyStateAllocatesNothing) {
  InputCheck check(config());
  const Block a = ramp(1000);
  check.check(a.view(0));
  test::AllocationCounter counter;
  for (int i = 1; i < 10; ++i) {
    check.check(a.view(i * 20'000));
  }
  EXPECT_EQ(counter.allocations(), 0);
}

}  // namespace
}  // namespace millwatch::monitor
