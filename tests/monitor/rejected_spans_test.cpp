#include "core/monitor/rejected_spans.hpp"

#include <gtest/gtest.h>

namespace millwatch::monitor {
namespace {

constexpr double kPerUs = 0.05;  // 50 kHz

TEST(RejectedSpans, MergesWhatOverlapsOrTouchesAndCountsEachSampleOnce) {
  RejectedSpans spans;
  spans.add(100, 200, 5, 5);
  spans.add(300, 400, 5, 5);
  spans.add(250, 250, 5, 5);  // empty: nothing
  spans.add(500, 600, 0, 5);  // no samples counted: nothing
  EXPECT_EQ(spans.size(), 2U);
  EXPECT_EQ(spans.counted_within(0, 1000, kPerUs), 10);
  spans.add(203, 297, 4, 5);  // within the tolerance of both: bridges them into one
  EXPECT_EQ(spans.size(), 1U);
  EXPECT_EQ(spans.counted_within(0, 1000, kPerUs), 14);  // the gap holds all of it (300 µs)
  EXPECT_EQ(spans.counted_within(100, 160, kPerUs), 3);  // 60 µs of it
  EXPECT_EQ(spans.counted_within(500, 600, kPerUs), 0);
}

TEST(RejectedSpans, BeyondItsCapacityJoinsTheClosestTwoAndAGapHoldingBothCountsThemExactly) {
  RejectedSpans spans;
  for (std::int64_t i = 0; i < static_cast<std::int64_t>(RejectedSpans::kCapacity); ++i) {
    spans.add(i * 1000, i * 1000 + 100, 5, 0);
  }
  spans.add(7150, 7250, 5, 0);  // 50 µs after 7,000–7,100, the closest two: joined
  EXPECT_EQ(spans.size(), RejectedSpans::kCapacity);
  EXPECT_EQ(spans.counted_within(0, 10'000, kPerUs), 5 * 9);
  EXPECT_EQ(spans.counted_within(6900, 7300, kPerUs), 10);
  // 100 of the joined span's 250 µs: a share, approximate (the 5 samples lay in 7,150–7,250)
  EXPECT_EQ(spans.counted_within(7150, 7300, kPerUs), 4);
}

// The same block twice: its samples were counted twice, the time it took once.
TEST(RejectedSpans, ABlockReceivedTwiceCoversItsTimeOnce) {
  RejectedSpans spans;
  spans.add(4000, 6000, 100, 10);
  spans.add(4000, 6000, 100, 10);
  EXPECT_EQ(spans.counted_within(2000, 6000, kPerUs), 100);
}

TEST(RejectedSpans, ForgetsWhatTheStreamPassed) {
  RejectedSpans spans;
  spans.add(1000, 3000, 100, 0);
  spans.add(5000, 7000, 100, 0);
  spans.forget_before(2000);  // half of the first span is behind the stream
  EXPECT_EQ(spans.counted_within(0, 8000, kPerUs), 50 + 100);
  spans.forget_before(9000);
  EXPECT_TRUE(spans.empty());
}

}  // namespace
}  // namespace millwatch::monitor
