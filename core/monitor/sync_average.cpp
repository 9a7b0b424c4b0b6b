#include "core/monitor/sync_average.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace millwatch::monitor {

SyncAverage::SyncAverage(int bins, int window_revolutions)
    : bins_(bins), window_(window_revolutions) {
  // window_ closed revolutions, the one being filled, and the window's total.
  sums_.assign(
      static_cast<std::size_t>(window_ + 2) * (kChannels + 1) * static_cast<std::size_t>(bins_),
      0.0);
}

void SyncAverage::clear() {
  std::fill(sums_.begin(), sums_.end(), 0.0);
  slot_ = 0;
  filled_ = 0;
}

void SyncAverage::add(double angle_rad, const std::array<double, kChannels>& values) {
  const double pos = angle_rad / (2.0 * std::numbers::pi) * bins_;
  double whole = std::floor(pos);
  const double w = pos - whole;
  int k0 = static_cast<int>(whole) % bins_;
  if (k0 < 0) {
    k0 += bins_;
  }
  const int k1 = k0 + 1 == bins_ ? 0 : k0 + 1;
  for (int c = 0; c < kChannels; ++c) {
    sums_[index(slot_, c, k0)] += (1.0 - w) * values[static_cast<std::size_t>(c)];
    sums_[index(slot_, c, k1)] += w * values[static_cast<std::size_t>(c)];
  }
  sums_[index(slot_, kChannels, k0)] += 1.0 - w;
  sums_[index(slot_, kChannels, k1)] += w;
}

void SyncAverage::end_revolution() {
  const int total = window_ + 1;
  const int next = (slot_ + 1) % (window_ + 1);  // the oldest closed revolution, when full
  for (int c = 0; c <= kChannels; ++c) {
    for (int k = 0; k < bins_; ++k) {
      sums_[index(total, c, k)] += sums_[index(slot_, c, k)];
      if (filled_ == window_) {
        sums_[index(total, c, k)] -= sums_[index(next, c, k)];  // the oldest leaves
      }
      sums_[index(next, c, k)] = 0.0;
    }
  }
  filled_ = std::min(filled_ + 1, window_);
  slot_ = next;
}

double SyncAverage::average(int channel, int bin) const {
  const double weight = sums_[index(window_ + 1, kChannels, bin)];
  return weight > 0.0 ? sums_[index(window_ + 1, channel, bin)] / weight : 0.0;
}

void SyncAverage::average(int channel, std::vector<double>& out) const {
  out.resize(static_cast<std::size_t>(bins_));
  for (int k = 0; k < bins_; ++k) {
    out[static_cast<std::size_t>(k)] = average(channel, k);
  }
  // Bins no sample has reached yet take their neighbours' mean.
  for (int k = 0; k < bins_; ++k) {
    if (sums_[index(window_ + 1, kChannels, k)] <= 0.0) {
      const int prev = (k + bins_ - 1) % bins_;
      const int next = (k + 1) % bins_;
      out[static_cast<std::size_t>(k)] =
          0.5 * (out[static_cast<std::size_t>(prev)] + out[static_cast<std::size_t>(next)]);
    }
  }
}

}  // namespace millwatch::monitor
