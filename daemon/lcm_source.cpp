#include "daemon/lcm_source.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <stdexcept>

#include "msgs/force_block_check.hpp"

namespace millwatch::daemon {

LcmSource::LcmSource(lcm::LCM& lcm, const std::string& channel, std::int64_t max_block_samples,
                     BlockQueue& queue, SourceCounters& counters)
    : lcm_(lcm),
      channel_(channel),
      max_block_samples_(
          std::min(max_block_samples, static_cast<std::int64_t>(BlockSlot::kMaxSamples))),
      queue_(queue),
      counters_(counters) {
  subscription_ =
      lcm_subscribe(lcm_.getUnderlyingLCM(), channel_.c_str(), &LcmSource::receive, this);
  if (subscription_ == nullptr) {
    throw std::runtime_error("cannot subscribe to the LCM channel " + channel_);
  }
  lcm_subscription_set_queue_capacity(subscription_, 1000);
}

LcmSource::~LcmSource() {
  lcm_unsubscribe(lcm_.getUnderlyingLCM(), subscription_);
}

void LcmSource::receive(const lcm_recv_buf_t* rbuf, const char* /*channel*/, void* self) {
  static_cast<LcmSource*>(self)->on_message(*rbuf);
}

void LcmSource::on_message(const lcm_recv_buf_t& rbuf) {
  const std::string& channel = channel_;
  const std::int64_t number = ++counters_.messages;
  // Decoded straight into the queue's free slot (no message object in between); a message that
  // does not pass the check leaves the slot unpublished, for the next one.
  BlockSlot* slot = queue_.claim();
  messaging::ForceBlockHeader header;
  const messaging::ForceBlockCheck c =
      slot != nullptr ? messaging::decode_force_block_into(
                            rbuf.data, rbuf.data_size, max_block_samples_, header, slot->fx.data(),
                            slot->fy.data(), slot->fz.data())
                      : messaging::check_force_block(rbuf.data, rbuf.data_size, max_block_samples_);
  if (c.problem == messaging::ForceBlockProblem::kTooManySamples) {
    // A whole block, only longer than we take: its samples are lost.
    const auto n = ++counters_.oversized;
    counters_.dropped(c.num_samples);
    if (n <= 10) {
      spdlog::warn(
          "{}: message {}: block of {} samples, more than source.max_block_samples ({}); "
          "dropped",
          channel, number, c.num_samples, max_block_samples_);
    }
    return;
  }
  if (!c.ok()) {
    const auto n = ++counters_.undecodable;
    if (n <= 10) {
      spdlog::warn(
          "{}: message {} of {} bytes does not decode as millwatch.force_block_t ({}); dropped",
          channel, number, rbuf.data_size, c.describe());
    } else if (n == 11) {
      spdlog::warn("{}: more messages that do not decode follow; counted in the status", channel);
    }
    return;
  }
  if (slot == nullptr) {
    ++counters_.queue_full;
    counters_.dropped(c.num_samples);
    return;
  }
  // The check made num_samples ≤ max_block_samples_ ≤ the slot's size.
  slot->utime_us = header.utime;
  slot->seq = header.seq;
  slot->sample_rate_hz = header.sample_rate_hz;
  slot->count = header.num_samples;
  slot->dropped_before = counters_.queuing_block();
  queue_.publish();
}

}  // namespace millwatch::daemon
