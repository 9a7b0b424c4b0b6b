#include "daemon/scan_timing.hpp"

#include <fmt/format.h>

#include <cmath>

namespace millwatch::daemon {

std::uint32_t scan_period_ns(double sample_rate_hz) {
  return static_cast<std::uint32_t>(std::llround(1e9 / sample_rate_hz));
}

std::string scan_rate_mismatch(double sample_rate_hz, std::uint64_t period_ns) {
  constexpr double kRelativeRateTolerance = 1e-6;
  if (period_ns == 0) {
    return fmt::format("the board gives no scan period for {} Hz", sample_rate_hz);
  }
  const double board_hz = 1e9 / static_cast<double>(period_ns);
  const double off = board_hz / sample_rate_hz - 1.0;
  if (std::fabs(off) <= kRelativeRateTolerance) {
    return {};
  }
  return fmt::format(
      "the board scans every {} ns ({:.6f} Hz), not at monitor.sample_rate_hz {} Hz: every "
      "speed and period would be {:+.4f} % off; set monitor.sample_rate_hz to {:.6f}",
      period_ns, board_hz, sample_rate_hz, 100.0 * off, board_hz);
}

}  // namespace millwatch::daemon
