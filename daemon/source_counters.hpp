#pragma once
// What a live source (LCM raw channel, Comedi board) counts before the pipeline sees a block:
// messages, the blocks it drops and their samples, and whether it has ended. Shared with the
// sample thread and the status through atomics.
//
// A dropped block's samples are a hole in the stream's time, which the pipeline counts as the gap
// before the next block it takes (samples_dropped, once). Holes no such gap shows are counted
// here instead: the drops since the last block queued, and those before blocks no gap shows
// (daemon/drop_ledger.hpp: taken or rejected without timing, the stream ended).

#include <atomic>
#include <cstdint>
#include <utility>

namespace millwatch::daemon {

struct SourceCounters {
  std::atomic<std::int64_t> messages{0};
  std::atomic<std::int64_t> undecodable{0};  ///< not a whole force_block_t
  std::atomic<std::int64_t> oversized{0};    ///< a whole one of more than max_block_samples
  std::atomic<std::int64_t> queue_full{0};
  std::atomic<std::int64_t> samples_dropped{0};  ///< in the blocks dropped (their own count)
  /// The source will deliver nothing more (a Comedi board whose reads failed).
  std::atomic<bool> ended{false};

  // dropped() and queuing_block() are called by the source's one writer thread (LCM: the
  // sample thread; Comedi: its reader), unseen_by_pipeline() and samples_dropped_unseen() by
  // the sample thread.

  /// A block of `samples` dropped (oversized, or the queue full).
  void dropped(std::int64_t samples) {
    samples_dropped += samples;
    unseen_ += samples;
    since_block_ += samples;
  }
  /// Just before a block is published to the queue: the samples dropped since the block before,
  /// for the block's slot (BlockSlot::dropped_before). Taken out of the unseen count before the
  /// block is published, so that no status counts them twice (one taken meanwhile misses them
  /// until the block is processed).
  [[nodiscard]] std::int64_t queuing_block() {
    unseen_ -= since_block_;
    return std::exchange(since_block_, 0);
  }
  /// `samples` dropped before blocks the pipeline will not count as a gap (DropLedger).
  void unseen_by_pipeline(std::int64_t samples) { unseen_ += samples; }
  /// The dropped samples no gap in the pipeline's stream shows (for the status and summary):
  /// one atomic, so that a status never reads half an update.
  [[nodiscard]] std::int64_t samples_dropped_unseen() const { return unseen_.load(); }

 private:
  std::atomic<std::int64_t> unseen_{0};
  std::int64_t since_block_ = 0;  // the writer's own
};

}  // namespace millwatch::daemon
