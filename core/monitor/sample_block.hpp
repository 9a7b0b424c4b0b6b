#pragma once
// A block of dynamometer samples from any source (DAQ, LCM channel, LCM log, CSV), in the
// instrument's channel order and sign (before the axis map).

#include <cstdint>
#include <span>

namespace millwatch::monitor {

struct SampleBlock {
  std::int64_t utime_us = 0;  ///< time of the first sample, microseconds
  std::int64_t seq = 0;       ///< block number from the source
  double sample_rate_hz = 0.0;
  std::span<const double> fx_N;
  std::span<const double> fy_N;
  std::span<const double> fz_N;
};

}  // namespace millwatch::monitor
