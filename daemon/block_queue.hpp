#pragma once
// Sample blocks handed from a source's thread to the sample thread: fixed-size slots in a
// bounded lock-free queue, so neither side allocates; a full queue drops the block and the
// source counts it. Assigning a slot (the queue's push and pop) copies only its `count` samples,
// not the whole 98 KB of the three arrays: 8 KB for a 1 ms block at 333.3 kHz.

#include <algorithm>
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

  BlockSlot() = default;
  BlockSlot(const BlockSlot&) = default;
  BlockSlot& operator=(const BlockSlot& other) {
    if (this != &other) {
      utime_us = other.utime_us;
      seq = other.seq;
      sample_rate_hz = other.sample_rate_hz;
      count = std::min(other.count, kMaxSamples);
      std::copy_n(other.fx.begin(), count, fx.begin());
      std::copy_n(other.fy.begin(), count, fy.begin());
      std::copy_n(other.fz.begin(), count, fz.begin());
    }
    return *this;
  }
  ~BlockSlot() = default;

  [[nodiscard]] monitor::SampleBlock view() const {
    return {utime_us,          seq, sample_rate_hz, {fx.data(), count}, {fy.data(), count},
            {fz.data(), count}};
  }
};

using BlockQueue = messaging::SpscQueue<BlockSlot, 64>;

}  // namespace millwatch::daemon
