#include "core/monitor/sync_average.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace millwatch::monitor {

SyncAverage::SyncAverage(int bins, int window_revolutions)
    : bins_(bins), bins_per_rad_(bins / (2.0 * std::numbers::pi)), window_(window_revolutions) {
  // window_ closed revolutions and the one being filled.
  sums_.assign(
      static_cast<std::size_t>(window_ + 1) * (kChannels + 1) * static_cast<std::size_t>(bins_),
      0.0);
  totals_.assign((kChannels + 1) * static_cast<std::size_t>(bins_), 0.0);
  totals_stale_ = true;
}

void SyncAverage::clear() {
  std::fill(sums_.begin(), sums_.end(), 0.0);
  slot_ = 0;
  filled_ = 0;
  totals_stale_ = true;
}

void SyncAverage::add(double angle_rad, const std::array<double, kChannels>& values) {
  const double pos = angle_rad * bins_per_rad_;
  const double whole = std::floor(pos);
  const double w = pos - whole;
  int k0 = static_cast<int>(whole);
  if (k0 >= bins_ || k0 < 0) {
    k0 %= bins_;
    k0 += k0 < 0 ? bins_ : 0;
  }
  const int k1 = k0 + 1 == bins_ ? 0 : k0 + 1;
  double* a = &sums_[index(slot_, 0, k0)];
  double* b = &sums_[index(slot_, 0, k1)];
  for (std::size_t c = 0; c < static_cast<std::size_t>(kChannels); ++c) {
    a[c] += (1.0 - w) * values[c];
    b[c] += w * values[c];
  }
  a[kChannels] += 1.0 - w;
  b[kChannels] += w;
}

void SyncAverage::end_revolution() {
  // The closed revolution stays in its slot; the oldest one's slot is reused (cleared). Totals
  // are summed only when an average is asked for (rarely), keeping this per-revolution step short.
  slot_ = (slot_ + 1) % (window_ + 1);
  const auto begin = sums_.begin() + static_cast<std::ptrdiff_t>(index(slot_, 0, 0));
  std::fill(begin, begin + static_cast<std::ptrdiff_t>((kChannels + 1) * bins_), 0.0);
  filled_ = std::min(filled_ + 1, window_);
  totals_stale_ = true;
}

void SyncAverage::sum_window() const {
  if (!totals_stale_) {
    return;
  }
  const std::size_t size = totals_.size();
  std::fill(totals_.begin(), totals_.end(), 0.0);
  for (int s = 0; s <= window_; ++s) {
    if (s != slot_) {
      const double* slot = &sums_[index(s, 0, 0)];
      for (std::size_t i = 0; i < size; ++i) {
        totals_[i] += slot[i];
      }
    }
  }
  totals_stale_ = false;
}

double SyncAverage::average(int channel, int bin) const {
  sum_window();
  const double* t = &totals_[static_cast<std::size_t>(bin) * (kChannels + 1)];
  return t[kChannels] > 0.0 ? t[channel] / t[kChannels] : 0.0;
}

void SyncAverage::average(int channel, std::vector<double>& out) const {
  out.resize(static_cast<std::size_t>(bins_));
  for (int k = 0; k < bins_; ++k) {
    out[static_cast<std::size_t>(k)] = average(channel, k);
  }
  // Bins no sample has reached yet take their neighbours' mean.
  for (int k = 0; k < bins_; ++k) {
    if (totals_[static_cast<std::size_t>(k) * (kChannels + 1) + kChannels] <= 0.0) {
      const int prev = (k + bins_ - 1) % bins_;
      const int next = (k + 1) % bins_;
      out[static_cast<std::size_t>(k)] =
          0.5 * (out[static_cast<std::size_t>(prev)] + out[static_cast<std::size_t>(next)]);
    }
  }
}

}  // namespace millwatch::monitor
