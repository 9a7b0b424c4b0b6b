#include "core/monitor/rejected_spans.hpp"

#include <gtest/gtest.h>

namespace millwatch::monitor {
namespace {

TEST(RejectedSpans, MergesWhatOverlapsOrTouchesAndCountsTheUnionOnce) {
  RejectedSpans spans;
  spans.add(100, 200, 5);
  spans.add(300, 400, 5);
  EXPECT_EQ(spans.size(), 2U);
  spans.add(150, 250, 5);  // overlaps the first
  spans.add(250, 250, 5);  // empty, touching: nothing new
  EXPECT_EQ(spans.covered_us(0, 1000), 150 + 100);
  spans.add(253, 297, 5);  // within the tolerance of both: bridges them into one
  EXPECT_EQ(spans.size(), 1U);
  EXPECT_EQ(spans.covered_us(0, 1000), 300);
  EXPECT_EQ(spans.covered_us(120, 320), 200);
  EXPECT_EQ(spans.covered_us(500, 600), 0);
}

TEST(RejectedSpans, ForgetsWhatTheStreamPassedAndGivesUpTheFurthestWhenFull) {
  RejectedSpans spans;
  for (int i = RejectedSpans::kCapacity; i >= 1; --i) {  // added furthest first
    spans.add(i * 1000, i * 1000 + 10, 0);
  }
  EXPECT_EQ(spans.size(), RejectedSpans::kCapacity);
  spans.add(500, 510, 0);  // nearer than all: the furthest (8,000) is given up
  EXPECT_EQ(spans.covered_us(8000, 9000), 0);
  EXPECT_EQ(spans.covered_us(0, 1000), 10);
  spans.add(20'000, 20'010, 0);  // further than all: given up
  EXPECT_EQ(spans.covered_us(20'000, 21'000), 0);
  spans.forget_before(1005);  // half of the span at 1,000 is behind the stream
  EXPECT_EQ(spans.covered_us(0, 2000), 5);
  EXPECT_EQ(spans.size(), RejectedSpans::kCapacity - 1);
  spans.clear();
  EXPECT_TRUE(spans.empty());
}

}  // namespace
}  // namespace millwatch::monitor
