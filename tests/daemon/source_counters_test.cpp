// A live source's dropped samples: each counted once, by the gap the pipeline sees before the next
// block, or here when no such gap shows them.

#include "daemon/source_counters.hpp"

#include <gtest/gtest.h>

namespace millwatch::daemon {
namespace {

TEST(SourceCounters, DropsNoGapShowsAreCountedHere) {
  SourceCounters c;
  c.dropped(50);  // before the stream's first block
  EXPECT_EQ(c.samples_dropped_unseen(), 50);
  EXPECT_EQ(c.queuing_block(), 50);  // handed to the block ...
  EXPECT_EQ(c.samples_dropped_unseen(), 0);
  c.unseen_by_pipeline(50);  // ... which the pipeline took without timing: no gap showed them
  EXPECT_EQ(c.samples_dropped_unseen(), 50);
  c.dropped(30);  // between two blocks: the gap before the next one shows them
  c.dropped(20);
  EXPECT_EQ(c.samples_dropped_unseen(), 100);
  EXPECT_EQ(c.queuing_block(), 50);
  EXPECT_EQ(c.samples_dropped_unseen(), 50);
  c.dropped(40);  // after the last block: for good
  EXPECT_EQ(c.samples_dropped_unseen(), 90);
  EXPECT_EQ(c.samples_dropped.load(), 140);  // every dropped block's samples, in its own count
}

}  // namespace
}  // namespace millwatch::daemon
