#pragma once
// The monitor's test of a raw sample against its input channel's limit
// (monitor::InputCheck::sample_limits: plausible and below saturation): |x| ≤ limit, false for a
// NaN. The input check's own pass and the filters that test the samples as they read them
// (GridLowPass::process_checked, LowPassFilter::process_three_checked) share it.

#include <cmath>

namespace millwatch::signal {

[[nodiscard]] inline bool within_limit(double x, double limit) {
  return std::fabs(x) <= limit;
}

}  // namespace millwatch::signal
