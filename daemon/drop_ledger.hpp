#pragma once
// The sample thread's account of the samples a source dropped before each block it queued
// (BlockSlot::dropped_before): the pipeline shows them as the gap before the next block it
// takes with timing; any it cannot show — before a block taken or rejected without timing (the
// stream's first blocks, a reload's successor without its predecessor's time), or when the
// stream ended — count as unseen in SourceCounters, once.

#include <cstdint>

#include "daemon/source_counters.hpp"

namespace millwatch::daemon {

class DropLedger {
 public:
  explicit DropLedger(SourceCounters& counters) : counters_(counters) {}

  /// Before the pipeline processes a block that carries `dropped_before`; `timed`: the pipeline
  /// knows when its next sample is due (it would count the samples missing before the block).
  void before_block(std::int64_t dropped_before, bool timed) {
    pending_ += dropped_before;
    if (!timed) {  // counted before the block, so that a status it publishes has them
      settle_unseen();
    }
  }
  /// After it: whether the pipeline took the block (then the gap before it showed what was
  /// pending), and whether it still knows when its next sample is due.
  void after_block(bool accepted, bool timed) {
    if (accepted) {
      pending_ = 0;
    } else if (!timed) {
      settle_unseen();
    }
  }
  /// The stream ends: no block will show what is pending.
  void close() { settle_unseen(); }

  [[nodiscard]] std::int64_t pending() const { return pending_; }

 private:
  void settle_unseen() {
    counters_.unseen_by_pipeline(pending_);
    pending_ = 0;
  }

  SourceCounters& counters_;
  std::int64_t pending_ = 0;  // dropped before blocks the pipeline has not taken with timing yet
};

}  // namespace millwatch::daemon
