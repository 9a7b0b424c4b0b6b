#include "core/monitor/revolution_stats.hpp"

#include <algorithm>
#include <array>
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
  if (seeded_ < kSeedRevolutions) {
    seed_N_[static_cast<std::size_t>(seeded_++)] = peak;
    const auto [a, b, c] = seed_N_;
    typical_peak_N_ = seeded_ == 1   ? a
                      : seeded_ == 2 ? std::min(a, b)
                                     : std::max(std::min(a, b), std::min(std::max(a, b), c));
    return true;
  }
  if (typical_peak_N_ == 0.0) {  // the first revolutions at 0 N: no usual peak yet
    typical_peak_N_ = peak;
    return true;
  }
  if (peak < kIdleFraction * typical_peak_N_) {
    return false;
  }
  typical_peak_N_ += kPeakGain * (std::min(peak, kMostRise * typical_peak_N_) - typical_peak_N_);
  return true;
}

void RevolutionStats::add(RevolutionRecord& r) {
  const auto w = static_cast<int>(alpha_.size());
  if (r.measured.valid) {
    alpha_[static_cast<std::size_t>(next_)] = r.measured.alpha_deg;
    delta_fy_[static_cast<std::size_t>(next_)] = r.measured.delta_fy_N;
    next_ = next_ + 1 < w ? next_ + 1 : 0;  // not `% w`: an integer division per revolution
    count_ = std::min(count_ + 1, w);
  }
  r.window_revolutions = count_;
  if (count_ == 0) {
    r.alpha_mean_deg = r.alpha_std_deg = r.delta_fy_mean_N = 0.0;
    return;
  }
  // One pass, α shifted by a value of the window (its spread, ~1°, is far below its level,
  // ~150°: no cancellation in Σd² − (Σd)²/n), each sum in two chains that do not wait on each
  // other (even and odd values): the three sums of 30 values had been a tenth of a 50 kHz
  // revolution's statistics. Six named sums, not arrays indexed by parity: those the compiler
  // kept in memory, each addition waiting on the last one's store (a third of this function).
  const double shift = alpha_[0];
  const double* const alpha = alpha_.data();
  const double* const delta = delta_fy_.data();
  double sa0 = 0.0, sa1 = 0.0, ss0 = 0.0, ss1 = 0.0, sd0 = 0.0, sd1 = 0.0;
  const auto n_values = static_cast<std::size_t>(count_);
  std::size_t k = 0;
  for (; k + 2 <= n_values; k += 2) {
    const double d0 = alpha[k] - shift, d1 = alpha[k + 1] - shift;
    sa0 += d0;
    sa1 += d1;
    ss0 += d0 * d0;
    ss1 += d1 * d1;
    sd0 += delta[k];
    sd1 += delta[k + 1];
  }
  if (k < n_values) {
    const double d0 = alpha[k] - shift;
    sa0 += d0;
    ss0 += d0 * d0;
    sd0 += delta[k];
  }
  const double n = count_;
  const double sum = sa0 + sa1;
  r.alpha_mean_deg = shift + sum / n;
  r.alpha_std_deg =
      count_ > 1 ? std::sqrt(std::max(0.0, (ss0 + ss1 - sum * sum / n) / (n - 1.0))) : 0.0;
  r.delta_fy_mean_N = (sd0 + sd1) / n;
}

void RevolutionStats::restart() {
  typical_peak_N_ = 0.0;
  seeded_ = 0;
  count_ = 0;
  next_ = 0;
}

}  // namespace millwatch::monitor
