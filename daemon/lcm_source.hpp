#pragma once
// Live source (c): raw sample blocks published on an LCM channel by a DAQ bridge. The LCM
// thread decodes each message and copies it into the block queue; what does not decode, does
// not fit a slot or finds the queue full is dropped and counted (never the daemon).

#include <atomic>
#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <string>

#include "daemon/block_queue.hpp"

namespace millwatch::daemon {

struct SourceCounters {
  std::atomic<std::int64_t> messages{0};
  std::atomic<std::int64_t> undecodable{0};
  std::atomic<std::int64_t> oversized{0};
  std::atomic<std::int64_t> queue_full{0};
  std::atomic<std::int64_t> samples_dropped{0};
};

class LcmSource {
 public:
  /// Subscribes on `lcm` (whose handle() the caller runs in its LCM thread).
  LcmSource(lcm::LCM& lcm, const std::string& channel, BlockQueue& queue, SourceCounters& counters);
  ~LcmSource();
  LcmSource(const LcmSource&) = delete;
  LcmSource& operator=(const LcmSource&) = delete;

 private:
  void on_message(const lcm::ReceiveBuffer* rbuf, const std::string& channel);

  lcm::LCM& lcm_;
  lcm::Subscription* subscription_ = nullptr;
  BlockQueue& queue_;
  SourceCounters& counters_;
  BlockSlot slot_;  // filled here (LCM thread), then copied into the queue
};

}  // namespace millwatch::daemon
