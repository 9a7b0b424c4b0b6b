// The sample thread's account of a source's dropped samples: each counted once — by the gap the
// pipeline counts before the next block it takes with timing, or else as unseen.

#include "daemon/drop_ledger.hpp"

#include <gtest/gtest.h>

namespace millwatch::daemon {
namespace {

TEST(DropLedger, TheGapOfATimedBlockShowsThemElseTheyAreUnseen) {
  SourceCounters c;
  DropLedger ledger(c);
  // The stream's first block, after 50 dropped samples: taken without timing, no gap shows them.
  ledger.before_block(50, false);
  EXPECT_EQ(c.samples_dropped_unseen(), 50);  // before the block: a status it publishes has them
  ledger.after_block(true, true);
  // 30 dropped, then a block taken with timing: its gap shows them.
  ledger.before_block(30, true);
  ledger.after_block(true, true);
  EXPECT_EQ(c.samples_dropped_unseen(), 50);
  // 20 dropped, then a block rejected as out of order: the next block's gap will show them.
  ledger.before_block(20, true);
  ledger.after_block(false, true);
  EXPECT_EQ(ledger.pending(), 20);
  ledger.before_block(0, true);
  ledger.after_block(true, true);
  EXPECT_EQ(c.samples_dropped_unseen(), 50);
  // 10 dropped, then a block rejected that costs the timing (a reload's successor dropping its
  // predecessor's time): no gap will show them.
  ledger.before_block(10, true);
  ledger.after_block(false, false);
  EXPECT_EQ(c.samples_dropped_unseen(), 60);
  EXPECT_EQ(ledger.pending(), 0);
  // 5 dropped before a rejected block, then the stream ends.
  ledger.before_block(5, true);
  ledger.after_block(false, true);
  ledger.close();
  EXPECT_EQ(c.samples_dropped_unseen(), 65);
}

}  // namespace
}  // namespace millwatch::daemon
