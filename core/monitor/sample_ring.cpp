#include "core/monitor/sample_ring.hpp"

#include <algorithm>
#include <bit>

namespace millwatch::monitor {

SampleRing::SampleRing(int channels, std::size_t min_capacity)
    : channels_(static_cast<std::size_t>(std::max(channels, 0))),
      capacity_(std::bit_ceil(std::max<std::size_t>(min_capacity, 16))) {
  mask_ = capacity_ - 1;
  row_shift_ = static_cast<std::size_t>(
      std::countr_zero(std::bit_ceil(std::max<std::size_t>(channels_, 1))));
  data_.assign(capacity_ << row_shift_, 0.0);
}

void SampleRing::clear() {
  oldest_ = 0;
  newest_ = -1;
}

}  // namespace millwatch::monitor
