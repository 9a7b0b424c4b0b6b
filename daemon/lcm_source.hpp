#pragma once
// Live source (c): raw sample blocks published on an LCM channel by a DAQ bridge. The thread
// that runs the LCM instance's handle() (millwatchd's sample thread) checks each message before
// decoding it (msgs/force_block_check.hpp: one malformed datagram must neither crash the daemon nor
// make it allocate what its count asks for) and decodes it straight into the block queue's free
// slot (the one copy on the way to the pipeline, which reads the slot in place); what is not a
// whole force_block_t, has more samples than source.max_block_samples or finds the queue full is
// dropped and counted (never the daemon). Subscribed through LCM's C interface: the C++ one builds
// a std::string of the channel name for every message (a heap allocation for a name of more than 15
// characters, as MILLWATCH_FORCE_RAW): in steady state a block costs no allocation here.

#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <string>

#include "daemon/block_queue.hpp"
#include "daemon/source_counters.hpp"

namespace millwatch::daemon {

class LcmSource {
 public:
  /// The queue an LCM source needs when the thread that runs handle() processes each block
  /// before it handles the next (millwatchd's sample thread): one block at a time, and one slot
  /// of slack. LCM's subscription queue holds the backlog.
  static constexpr std::size_t kQueueCapacity = 2;

  /// Subscribes on `lcm` (whose handle() the caller runs in its LCM thread); blocks of more
  /// than `max_block_samples` (at most BlockSlot::kMaxSamples) are dropped.
  LcmSource(lcm::LCM& lcm, const std::string& channel, std::int64_t max_block_samples,
            BlockQueue& queue, SourceCounters& counters);
  ~LcmSource();
  LcmSource(const LcmSource&) = delete;
  LcmSource& operator=(const LcmSource&) = delete;

 private:
  static void receive(const lcm_recv_buf_t* rbuf, const char* channel, void* self);
  void on_message(const lcm_recv_buf_t& rbuf);

  lcm::LCM& lcm_;
  std::string channel_;
  lcm_subscription_t* subscription_ = nullptr;
  std::int64_t max_block_samples_;
  BlockQueue& queue_;
  SourceCounters& counters_;
};

}  // namespace millwatch::daemon
