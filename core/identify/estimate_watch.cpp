#include "core/identify/estimate_watch.hpp"

namespace millwatch::identify {

bool EstimateWatch::window_submitted(std::int64_t utime_us, double window_s,
                                     double budget_period_s) {
  if (++windows_without_ < kChances) {
    return false;
  }
  if (budget_period_s > 0.0 &&
      last_estimate_utime_us_ != std::numeric_limits<std::int64_t>::min()) {
    const double age_s = 1e-6 * static_cast<double>(utime_us - last_estimate_utime_us_);
    return age_s > kChances * (budget_period_s + window_s);
  }
  return true;
}

void EstimateWatch::estimate_accepted(std::int64_t utime_us) {
  windows_without_ = 0;
  last_estimate_utime_us_ = utime_us;
}

}  // namespace millwatch::identify
