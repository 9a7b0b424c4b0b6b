#include "daemon/lcm_source.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <stdexcept>

#include "msgs/force_block_check.hpp"

namespace millwatch::daemon {

LcmSource::LcmSource(lcm::LCM& lcm, const std::string& channel, std::int64_t max_block_samples,
                     BlockQueue& queue, SourceCounters& counters)
    : lcm_(&lcm),
      channel_(channel),
      max_block_samples_(
          std::min(max_block_samples, static_cast<std::int64_t>(BlockSlot::kMaxSamples))),
      queue_(queue),
      counters_(counters) {
  subscription_ =
      lcm_subscribe(lcm_->getUnderlyingLCM(), channel_.c_str(), &LcmSource::receive, this);
  if (subscription_ == nullptr) {
    throw std::runtime_error("cannot subscribe to the LCM channel " + channel_);
  }
  lcm_subscription_set_queue_capacity(subscription_, 1000);
}

LcmSource::LcmSource(const UdpmEndpoint& endpoint, const std::string& channel,
                     std::int64_t max_block_samples, BlockQueue& queue, SourceCounters& counters)
    : udpm_(std::make_unique<UdpmReceiver>(endpoint)),
      channel_(channel),
      max_block_samples_(
          std::min(max_block_samples, static_cast<std::int64_t>(BlockSlot::kMaxSamples))),
      queue_(queue),
      counters_(counters) {}

LcmSource::~LcmSource() {
  if (subscription_ != nullptr) {
    lcm_unsubscribe(lcm_->getUnderlyingLCM(), subscription_);
  }
}

bool LcmSource::is_plain_channel(std::string_view channel) {
  return !channel.empty() && std::all_of(channel.begin(), channel.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '-' || c == '/' ||
           c == ':';
  });
}

bool LcmSource::take_waiting() {
  if (udpm_ == nullptr) {
    return lcm_->handleTimeout(0) > 0;
  }
  for (;;) {
    if (datagrams_taken_ == datagrams_read_) {
      datagrams_read_ = udpm_->read_waiting();
      datagrams_taken_ = 0;
      say_kernel_drops();
      if (datagrams_read_ == 0) {
        return false;
      }
    }
    if (on_datagram(messaging::parse_lcm_datagram(udpm_->datagram(datagrams_taken_++)))) {
      return true;
    }
  }
}

void LcmSource::say_kernel_drops() {
  const std::uint64_t dropped = udpm_->dropped_datagrams();
  if (dropped == kernel_drops_said_) {
    return;
  }
  // The blocks among them are gaps in the stream, counted as such by the pipeline; this says
  // why (the first ten times, then the total at most every 10,000 datagrams).
  if (++kernel_drop_warnings_ <= 10 || dropped / 10000 != kernel_drops_said_ / 10000) {
    spdlog::warn(
        "{}: the kernel dropped {} datagrams on the udpm socket ({} in all): its buffer was full "
        "while the sample thread was busy; the blocks lost show as gaps (a larger recv_buf_size "
        "in lcm.url, within net.core.rmem_max, holds more)",
        channel_, dropped - kernel_drops_said_, dropped);
  }
  kernel_drops_said_ = dropped;
}

void LcmSource::wait(std::chrono::milliseconds timeout) {
  if (udpm_ == nullptr) {
    lcm_->handleTimeout(static_cast<int>(timeout.count()));
  } else if (datagrams_taken_ < datagrams_read_ || udpm_->wait(timeout)) {
    take_waiting();
  }
}

bool LcmSource::on_datagram(const messaging::LcmDatagram& d) {
  using Kind = messaging::LcmDatagram::Kind;
  // Other channels on the group, the later fragments of a long message and what is not LCM's
  // are not this source's: LCM's receive drops them too.
  if (d.kind == Kind::kNotLcm || d.channel != channel_) {
    return false;
  }
  if (d.kind == Kind::kShort) {
    on_message(d.payload.data(), d.payload.size());
    return true;
  }
  // Fragment 0 of a message over 64 KiB. Its start tells whether it is a force_block_t (of
  // more than 2,726 samples) and how many samples it held: those are lost, as a block over
  // max_block_samples is; anything else is garbage.
  const std::int64_t number = ++counters_.messages;
  const messaging::ForceBlockCheck c =
      d.payload.size() >= messaging::kForceBlockHeaderBytes
          ? messaging::check_force_block(d.payload.data(), d.message_bytes, max_block_samples_)
          : messaging::ForceBlockCheck{.problem = messaging::ForceBlockProblem::kShorterThanHeader};
  if (c.ok() || c.problem == messaging::ForceBlockProblem::kTooManySamples) {
    const auto n = ++counters_.oversized;
    counters_.dropped(c.num_samples);
    if (n <= 10) {
      spdlog::warn(
          "{}: message {}: block of {} samples ({} bytes) came in {} fragments, over 64 KiB; the "
          "batched receive takes whole datagrams (a force_block_t holds at most 2,000 samples): "
          "dropped (source.receive \"lcm\" reassembles fragments)",
          channel_, number, c.num_samples, d.message_bytes, d.fragments);
    }
    return true;
  }
  const auto n = ++counters_.undecodable;
  if (n <= 10) {
    spdlog::warn("{}: message {} of {} bytes came in {} fragments and is no force_block_t; dropped",
                 channel_, number, d.message_bytes, d.fragments);
  } else if (n == 11) {
    spdlog::warn("{}: more messages that do not decode follow; counted in the status", channel_);
  }
  return true;
}

void LcmSource::receive(const lcm_recv_buf_t* rbuf, const char* /*channel*/, void* self) {
  static_cast<LcmSource*>(self)->on_message(rbuf->data, rbuf->data_size);
}

void LcmSource::on_message(const void* data, std::size_t size_bytes) {
  const std::string& channel = channel_;
  const std::int64_t number = ++counters_.messages;
  // Decoded straight into the queue's free slot (no message object in between); a message that
  // does not pass the check leaves the slot unpublished, for the next one.
  BlockSlot* slot = queue_.claim();
  messaging::ForceBlockHeader header;
  const messaging::ForceBlockCheck c =
      slot != nullptr
          ? messaging::decode_force_block_into(data, size_bytes, max_block_samples_, header,
                                               slot->fx.data(), slot->fy.data(), slot->fz.data())
          : messaging::check_force_block(data, size_bytes, max_block_samples_);
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
          channel, number, size_bytes, c.describe());
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
