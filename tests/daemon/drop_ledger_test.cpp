// The sample thread's account of a source's dropped samples: each counted once — by the gap the
// pipeline counts before the next block it takes with timing, or else as unseen.

#include "daemon/drop_ledger.hpp"

#include <gtest/gtest.h>

namespace millwatch::daemon {
namespace {

TEST(DropLedger, TheGapOfATimedBlockShowsThemElseTheyAreUnseen) {
  SourceCounters c;
  DropLedger ledger(c);
  // One block through the pipeline: dropped before it, whether the pipeline was timed before,
  // took it, and is timed after.
  const auto block = [&](std::int64_t dropped, bool timed, bool accepted, bool timed_after) {
    ledger.before_block(dropped, timed);
    ledger.after_block(accepted, timed_after);
    return c.samples_dropped_unseen();
  };
  // The stream's first block, after 50 dropped samples: taken without timing, no gap shows them
  // (counted before the block: a status it publishes has them).
  ledger.before_block(50, false);
  EXPECT_EQ(c.samples_dropped_unseen(), 50);
  ledger.after_block(true, true);
  EXPECT_EQ(block(30, true, true, true), 50);  // a block taken with timing: its gap shows them
  // Before a block rejected as out of order: the next block's gap will show them.
  EXPECT_EQ(block(20, true, false, true), 50);
  EXPECT_EQ(ledger.pending(), 20);
  EXPECT_EQ(block(0, true, true, true), 50);
  // Before a block rejected that costs the timing (a reload's successor dropping its
  // predecessor's time): no gap will show them.
  EXPECT_EQ(block(10, true, false, false), 60);
  EXPECT_EQ(ledger.pending(), 0);
  // Before a rejected block, and then the stream ends.
  EXPECT_EQ(block(5, true, false, true), 60);
  ledger.close();
  EXPECT_EQ(c.samples_dropped_unseen(), 65);
}

}  // namespace
}  // namespace millwatch::daemon
