#pragma once
// Revolution-synchronous average: the filtered force of the last W revolutions on a uniform
// spindle-angle grid (bin k at 2πk/B from the tracker's angle zero). Each sample is shared
// between its two neighbouring bins in proportion to its angle, so a grid finer than the
// samples of one revolution still fills in over several revolutions.

#include <array>
#include <cstdint>
#include <vector>

namespace millwatch::monitor {

class SyncAverage {
 public:
  static constexpr int kChannels = 4;  ///< fx, fy, fz, resultant √(fx² + fy²)

  SyncAverage() = default;
  SyncAverage(int bins, int window_revolutions);

  /// Adds one sample at spindle angle `angle_rad` ∈ [0, 2π) to the current revolution.
  void add(double angle_rad, const std::array<double, kChannels>& values);
  /// Closes the current revolution: it joins the window, the oldest leaves it.
  void end_revolution();
  /// Average of channel c at bin k over the window (revolutions closed so far).
  [[nodiscard]] double average(int channel, int bin) const;
  /// The average of a channel on the whole grid, into `out` (size bins()).
  void average(int channel, std::vector<double>& out) const;
  [[nodiscard]] int bins() const { return bins_; }
  [[nodiscard]] int revolutions() const { return filled_; }
  [[nodiscard]] int window() const { return window_; }
  void clear();

 private:
  [[nodiscard]] double total(int channel, int bin) const;
  // Layout [slot][bin][channel]: a sample's two bins are two short contiguous runs.
  [[nodiscard]] std::size_t index(int slot, int channel, int bin) const {
    return (static_cast<std::size_t>(slot) * static_cast<std::size_t>(bins_) +
            static_cast<std::size_t>(bin)) *
               (kChannels + 1) +
           static_cast<std::size_t>(channel);
  }

  int bins_ = 0;
  double bins_per_rad_ = 0.0;
  int window_ = 0;
  int slot_ = 0;    // ring slot of the revolution being filled
  int filled_ = 0;  // closed revolutions in the window
  // Per ring slot (window_ + 1 of them: the closed revolutions and the one being filled):
  // kChannels weighted sums and the weights, per bin.
  std::vector<double> sums_;
};

}  // namespace millwatch::monitor
