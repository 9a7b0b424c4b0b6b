#pragma once
// Revolution-synchronous average: the filtered force of the last W revolutions on a uniform
// spindle-angle grid (bin k at 2πk/B from the tracker's angle zero). Each sample is shared
// between its two neighbouring bins in proportion to its angle, so a grid finer than the
// samples of one revolution still fills in over several revolutions.

#include <algorithm>
#include <array>
#include <cmath>
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
  /// Adds `count` samples to the current revolution on a line of positions: sample i at bin
  /// position first_bin + i·bins_per_sample (any real, taken modulo bins()) with values(i)
  /// (std::array<double, kChannels>): the same sums as add() sample by sample. The position
  /// advances by a step, wrapped once a turn, instead of an angle wrapped per sample. Samples
  /// sparser than the bins (each in bins of its own: 50 kHz) go straight to their two bins;
  /// denser ones (a run sharing two bins: 333.3 kHz) are summed in registers until the run moves
  /// on (adding to memory one sample after the other would wait on each store).
  template <typename Values>
  void add_line(std::size_t count, double first_bin, double bins_per_sample, const Values& values) {
    const auto grid = static_cast<double>(bins_);
    if (!(bins_per_sample >= 0.0 && bins_per_sample < grid)) {  // not a spindle's line: any
      for (std::size_t i = 0; i < count; ++i) {
        const double pos = first_bin + bins_per_sample * static_cast<double>(i);
        add_at(pos - grid * std::floor(pos / grid), values(i));
      }
      return;
    }
    const double start = first_bin - grid * std::floor(first_bin / grid);  // [0, bins]
    double wrapped = 0.0;  // whole turns of the grid passed, in bins
    const auto position = [&](std::size_t i) {
      double pos = start + bins_per_sample * static_cast<double>(i) - wrapped;
      if (pos >= grid) {
        wrapped += grid;
        pos -= grid;
      }
      return pos;
    };
    if (bins_per_sample >= 1.0) {
      for (std::size_t i = 0; i < count; ++i) {
        add_at(position(i), values(i));
      }
      return;
    }
    int k0 = -1;
    std::array<double, kChannels + 1> lo{}, hi{};
    for (std::size_t i = 0; i < count; ++i) {
      const double pos = position(i);
      const int k = std::min(static_cast<int>(pos), bins_ - 1);
      const double w = pos - k;
      if (k != k0) {
        flush_run(k0, lo, hi);
        k0 = k;
      }
      const std::array<double, kChannels> v = values(i);
      for (std::size_t c = 0; c < static_cast<std::size_t>(kChannels); ++c) {
        lo[c] += (1.0 - w) * v[c];
        hi[c] += w * v[c];
      }
      lo[kChannels] += 1.0 - w;
      hi[kChannels] += w;
    }
    flush_run(k0, lo, hi);
  }
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
  /// The window's sums per bin (totals_), from the closed revolutions' slots, when they changed.
  void sum_window() const;
  /// Adds a run's sums to bin k and the next one (nothing for k < 0), and zeroes them.
  void flush_run(int k, std::array<double, kChannels + 1>& lo,
                 std::array<double, kChannels + 1>& hi) {
    if (k < 0) {
      return;
    }
    double* a = &sums_[index(slot_, 0, k)];
    double* b = &sums_[index(slot_, 0, k + 1 == bins_ ? 0 : k + 1)];
    for (std::size_t c = 0; c <= static_cast<std::size_t>(kChannels); ++c) {
      a[c] += lo[c];
      b[c] += hi[c];
      lo[c] = 0.0;
      hi[c] = 0.0;
    }
  }
  /// Adds one sample at bin position pos ∈ [0, bins] to its two bins.
  void add_at(double pos, const std::array<double, kChannels>& v) {
    const int k = std::min(static_cast<int>(pos), bins_ - 1);
    const double w = pos - k;
    double* a = &sums_[index(slot_, 0, k)];
    double* b = &sums_[index(slot_, 0, k + 1 == bins_ ? 0 : k + 1)];
    for (std::size_t c = 0; c < static_cast<std::size_t>(kChannels); ++c) {
      a[c] += (1.0 - w) * v[c];
      b[c] += w * v[c];
    }
    a[kChannels] += 1.0 - w;
    b[kChannels] += w;
  }
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
  // The window's sums, [bin][channel], summed once after the window changed: averages are read
  // a few times per window (a report, an alignment), each reading every bin of several
  // channels. The slot being filled is not in them, so add() leaves them valid.
  mutable std::vector<double> totals_;
  mutable bool totals_stale_ = true;
};

}  // namespace millwatch::monitor
