#pragma once
// Running statistics of three force channels (min, max, mean, RMS, peak |F_xy|), for summaries.

#include <array>
#include <cstdint>

namespace millwatch::sim {

class ChannelStats {
 public:
  void add(const std::array<double, 3>& f);

  [[nodiscard]] std::int64_t count() const { return count_; }
  [[nodiscard]] double min(int axis) const { return min_[static_cast<std::size_t>(axis)]; }
  [[nodiscard]] double max(int axis) const { return max_[static_cast<std::size_t>(axis)]; }
  [[nodiscard]] double mean(int axis) const;
  [[nodiscard]] double rms(int axis) const;
  /// Largest magnitude of the in-plane resultant √(Fx² + Fy²).
  [[nodiscard]] double peak_resultant_xy() const { return peak_xy_; }

 private:
  std::int64_t count_ = 0;
  std::array<double, 3> min_{}, max_{}, sum_{}, sum_sq_{};
  double peak_xy_ = 0.0;
};

}  // namespace millwatch::sim
