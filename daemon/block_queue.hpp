#pragma once
// Sample blocks handed from a source's thread to the sample thread: fixed-size slots in a
// bounded lock-free queue, so neither side allocates; a full queue drops the block and the
// source counts it.

#include <array>
#include <cstdint>

#include "core/monitor/sample_block.hpp"
#include "msgs/spsc_queue.hpp"

namespace millwatch::daemon {

struct BlockSlot {
  static constexpr std::size_t kMaxSamples = 4096;
  std::int64_t utime_us = 0;
  std::int64_t seq = 0;
  double sample_rate_hz = 0.0;
  std::size_t count = 0;
  std::array<double, kMaxSamples> fx{}, fy{}, fz{};

  [[nodiscard]] monitor::SampleBlock view() const {
    return {utime_us,          seq, sample_rate_hz, {fx.data(), count}, {fy.data(), count},
            {fz.data(), count}};
  }
};

using BlockQueue = messaging::SpscQueue<BlockSlot, 64>;

}  // namespace millwatch::daemon
