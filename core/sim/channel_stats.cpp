#include "core/sim/channel_stats.hpp"

#include <algorithm>
#include <cmath>

namespace millwatch::sim {

void ChannelStats::add(const std::array<double, 3>& f) {
  for (std::size_t a = 0; a < 3; ++a) {
    min_[a] = count_ == 0 ? f[a] : std::min(min_[a], f[a]);
    max_[a] = count_ == 0 ? f[a] : std::max(max_[a], f[a]);
    sum_[a] += f[a];
    sum_sq_[a] += f[a] * f[a];
  }
  peak_xy_ = std::max(peak_xy_, std::hypot(f[0], f[1]));
  ++count_;
}

double ChannelStats::mean(int axis) const {
  return count_ == 0 ? 0.0 : sum_[static_cast<std::size_t>(axis)] / static_cast<double>(count_);
}

double ChannelStats::rms(int axis) const {
  return count_ == 0
             ? 0.0
             : std::sqrt(sum_sq_[static_cast<std::size_t>(axis)] / static_cast<double>(count_));
}

}  // namespace millwatch::sim
