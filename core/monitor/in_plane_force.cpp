#include "core/monitor/in_plane_force.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "core/monitor/input_check.hpp"

namespace millwatch::monitor {

void InPlaneForce::add(std::span<const double> x_N, std::span<const double> y_N) {
  // In locals over the block: kept in members, the compiler reloaded and stored the maximum at
  // every sample, a store-to-load wait twice as long as the additions' own chain.
  double sum_sq = sum_sq_;
  double max_sq = max_sq_;
  std::int64_t samples = samples_;
  const std::size_t n = std::min(x_N.size(), y_N.size());
  for (std::size_t k = 0; k < n; ++k) {
    const double r2 = x_N[k] * x_N[k] + y_N[k] * y_N[k];
    if (std::fabs(x_N[k]) <= kPlausibleForce_N && std::fabs(y_N[k]) <= kPlausibleForce_N) {
      sum_sq += r2;
      max_sq = std::max(max_sq, r2);
      ++samples;
    }
  }
  sum_sq_ = sum_sq;
  max_sq_ = max_sq;
  samples_ = samples;
}

std::optional<double> InPlaneForce::rms_N() const {
  if (samples_ == 0) {
    return std::nullopt;
  }
  return std::sqrt(sum_sq_ / static_cast<double>(samples_));
}

std::optional<double> InPlaneForce::max_N() const {
  if (samples_ == 0) {
    return std::nullopt;
  }
  return std::sqrt(max_sq_);
}

}  // namespace millwatch::monitor
