#include "core/monitor/revolution_stats.hpp"

#include <algorithm>
#include <cmath>

namespace millwatch::monitor {

RevolutionStats::RevolutionStats(int window_revolutions)
    : alpha_(static_cast<std::size_t>(std::max(1, window_revolutions)), 0.0),
      delta_fy_(alpha_.size(), 0.0) {}

bool RevolutionStats::cutting(const RevolutionMeasurement& m) {
  double peak = 0.0;
  for (int j = 0; j < m.flutes; ++j) {
    peak = std::max(peak, m.peak_resultant_N[static_cast<std::size_t>(j)]);
  }
  if (typical_peak_N_ > 0.0 && peak < kIdleFraction * typical_peak_N_) {
    return false;
  }
  typical_peak_N_ =
      typical_peak_N_ == 0.0 ? peak : typical_peak_N_ + 0.05 * (peak - typical_peak_N_);
  return true;
}

void RevolutionStats::add(RevolutionRecord& r) {
  const auto w = static_cast<int>(alpha_.size());
  if (r.measured.valid) {
    alpha_[static_cast<std::size_t>(next_)] = r.measured.alpha_deg;
    delta_fy_[static_cast<std::size_t>(next_)] = r.measured.delta_fy_N;
    next_ = (next_ + 1) % w;
    count_ = std::min(count_ + 1, w);
  }
  r.window_revolutions = count_;
  if (count_ == 0) {
    r.alpha_mean_deg = r.alpha_std_deg = r.delta_fy_mean_N = 0.0;
    return;
  }
  double sa = 0.0, sd = 0.0;
  for (int i = 0; i < count_; ++i) {
    sa += alpha_[static_cast<std::size_t>(i)];
    sd += delta_fy_[static_cast<std::size_t>(i)];
  }
  const double mean = sa / count_;
  double ss = 0.0;
  for (int i = 0; i < count_; ++i) {
    const double d = alpha_[static_cast<std::size_t>(i)] - mean;
    ss += d * d;
  }
  r.alpha_mean_deg = mean;
  r.alpha_std_deg = count_ > 1 ? std::sqrt(ss / (count_ - 1)) : 0.0;
  r.delta_fy_mean_N = sd / count_;
}

void RevolutionStats::clear_window() {
  count_ = 0;
  next_ = 0;
}

}  // namespace millwatch::monitor
