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
//
// On a udpm:// URL the source reads the group itself by default (source.receive "batched":
// daemon/udpm_receiver.hpp), a round's datagrams at a time, and LCM starts no receive thread;
// "lcm" keeps LCM's. The batched receive takes whole datagrams: a message LCM sent in fragments
// (over 64 KiB, more than a force_block_t of 2,000 samples) is dropped and counted, saying so.

#include <chrono>
#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <string>
#include <string_view>

#include "daemon/block_queue.hpp"
#include "daemon/source_counters.hpp"
#include "daemon/udpm_receiver.hpp"
#include "msgs/lcm_datagram.hpp"

namespace millwatch::daemon {

class LcmSource {
 public:
  /// The queue an LCM source needs when the thread that runs handle() processes each block
  /// before it handles the next (millwatchd's sample thread): one block at a time, and one slot
  /// of slack. LCM's subscription queue holds the backlog.
  static constexpr std::size_t kQueueCapacity = 2;

  /// Subscribes on `lcm` (whose handle() take_waiting() and wait() run, in the caller's
  /// thread); blocks of more than `max_block_samples` (at most BlockSlot::kMaxSamples) are
  /// dropped.
  LcmSource(lcm::LCM& lcm, const std::string& channel, std::int64_t max_block_samples,
            BlockQueue& queue, SourceCounters& counters);
  /// Reads `endpoint`'s group itself (batched): the channel's messages, by its exact name.
  /// @throws std::runtime_error if the socket cannot be opened, bound or joined
  LcmSource(const UdpmEndpoint& endpoint, const std::string& channel,
            std::int64_t max_block_samples, BlockQueue& queue, SourceCounters& counters);
  ~LcmSource();
  LcmSource(const LcmSource&) = delete;
  LcmSource& operator=(const LcmSource&) = delete;

  /// Whether the batched receive can take `channel`: LCM subscribes by regular expression, the
  /// batched receive by name, so only a channel with no character special to a regex.
  [[nodiscard]] static bool is_plain_channel(std::string_view channel);

  /// Takes the next message that has come, without waiting: decoded into the queue, or dropped
  /// and counted. False when none was waiting.
  bool take_waiting();
  /// Sleeps until a message comes (then takes it) or `timeout` has passed.
  void wait(std::chrono::milliseconds timeout);
  [[nodiscard]] bool batched() const { return udpm_ != nullptr; }
  /// The batched receive's socket buffer as the kernel set it (0 with LCM's receive).
  [[nodiscard]] int receive_buffer_bytes() const {
    return udpm_ != nullptr ? udpm_->buffer_bytes() : 0;
  }

 private:
  static void receive(const lcm_recv_buf_t* rbuf, const char* channel, void* self);
  void on_message(const void* data, std::size_t size_bytes);
  /// A datagram of the batched receive: true if it was a message on the channel.
  bool on_datagram(const messaging::LcmDatagram& d);
  /// Warns of datagrams the kernel dropped since the last warning.
  void say_kernel_drops();

  lcm::LCM* lcm_ = nullptr;             // LCM's receive
  std::unique_ptr<UdpmReceiver> udpm_;  // or the batched one
  std::size_t datagrams_read_ = 0;      // by the last read_waiting()
  std::size_t datagrams_taken_ = 0;     // of those
  std::uint64_t kernel_drops_said_ = 0;
  int kernel_drop_warnings_ = 0;
  std::string channel_;
  lcm_subscription_t* subscription_ = nullptr;
  std::int64_t max_block_samples_;
  BlockQueue& queue_;
  SourceCounters& counters_;
};

}  // namespace millwatch::daemon
