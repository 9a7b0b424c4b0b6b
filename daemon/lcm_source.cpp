#include "daemon/lcm_source.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>

#include "millwatch/force_block_t.hpp"

namespace millwatch::daemon {

LcmSource::LcmSource(lcm::LCM& lcm, const std::string& channel, BlockQueue& queue,
                     SourceCounters& counters)
    : lcm_(lcm), queue_(queue), counters_(counters) {
  subscription_ = lcm_.subscribe(channel, &LcmSource::on_message, this);
  subscription_->setQueueCapacity(1000);
}

LcmSource::~LcmSource() {
  lcm_.unsubscribe(subscription_);
}

void LcmSource::on_message(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  ++counters_.messages;
  force_block_t m;
  const int used = m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size));
  if (used < 0 || static_cast<std::uint32_t>(used) != rbuf->data_size) {
    const auto n = ++counters_.undecodable;
    if (n <= 10) {
      spdlog::warn("{}: message {} of {} bytes does not decode as millwatch.force_block_t; dropped",
                   channel, counters_.messages.load(), rbuf->data_size);
    }
    return;
  }
  const std::size_t n = m.fx_N.size();
  if (n > BlockSlot::kMaxSamples) {
    ++counters_.oversized;
    counters_.samples_dropped += static_cast<std::int64_t>(n);
    spdlog::warn("{}: block {} has {} samples, more than {}; dropped", channel, m.seq, n,
                 BlockSlot::kMaxSamples);
    return;
  }
  slot_.utime_us = m.utime;
  slot_.seq = m.seq;
  slot_.sample_rate_hz = m.sample_rate_hz;
  // Channels of unequal length stay so: the pipeline rejects such a block and says why.
  slot_.count = n;
  std::copy(m.fx_N.begin(), m.fx_N.end(), slot_.fx.begin());
  std::copy_n(m.fy_N.begin(), std::min(n, m.fy_N.size()), slot_.fy.begin());
  std::copy_n(m.fz_N.begin(), std::min(n, m.fz_N.size()), slot_.fz.begin());
  if (!queue_.try_push(slot_)) {
    ++counters_.queue_full;
    counters_.samples_dropped += static_cast<std::int64_t>(n);
  }
}

}  // namespace millwatch::daemon
