#pragma once
// A record's in-plane force √(Fx² + Fy²) over all its samples, before any filter: what a record
// holds even where no revolution can be measured (a campaign's first, light cuts). Samples the
// input check would not take for a force — a NaN, an infinity, or beyond ±kPlausibleForce_N
// (1e6 N, a corrupt value) on either axis — are left out and not counted.

#include <cstdint>
#include <optional>
#include <span>

namespace millwatch::monitor {

class InPlaneForce {
 public:
  /// Adds the samples x[k], y[k] (the model's x and y axes), k below the shorter span's length.
  void add(std::span<const double> x_N, std::span<const double> y_N);

  [[nodiscard]] std::int64_t samples() const { return samples_; }
  /// Root mean square over the samples added; none without samples.
  [[nodiscard]] std::optional<double> rms_N() const;
  /// The largest; none without samples.
  [[nodiscard]] std::optional<double> max_N() const;

 private:
  // (Not side by side: GCC packed the two sums into one register for the store at the end,
  // and then shuffled it at every sample.)
  double sum_sq_ = 0.0;  // Σ (x² + y²), in the samples' order
  std::int64_t samples_ = 0;
  double max_sq_ = 0.0;  // √ once, at the end
};

}  // namespace millwatch::monitor
