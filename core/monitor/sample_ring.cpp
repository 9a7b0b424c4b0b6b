#include "core/monitor/sample_ring.hpp"

#include <bit>

namespace millwatch::monitor {

SampleRing::SampleRing(int channels, std::size_t min_capacity)
    : channels_(channels), capacity_(std::bit_ceil(std::max<std::size_t>(min_capacity, 16))) {
  mask_ = capacity_ - 1;
  data_.assign(static_cast<std::size_t>(channels_) * capacity_, 0.0);
}

void SampleRing::push(std::int64_t sample, const double* values) {
  if (empty() || sample != newest_ + 1) {
    oldest_ = sample;  // a new stretch (or the first sample)
  }
  newest_ = sample;
  if (newest_ - oldest_ >= static_cast<std::int64_t>(capacity_)) {
    oldest_ = newest_ - static_cast<std::int64_t>(capacity_) + 1;
  }
  const std::size_t slot = static_cast<std::size_t>(sample) & mask_;
  for (int c = 0; c < channels_; ++c) {
    data_[static_cast<std::size_t>(c) * capacity_ + slot] = values[c];
  }
}

void SampleRing::clear() {
  oldest_ = 0;
  newest_ = -1;
}

}  // namespace millwatch::monitor
