#include "core/identify/cpu_budget.hpp"

#include <limits>
#include <stdexcept>
#include <string>

namespace millwatch::identify {

CpuBudget::CpuBudget(double fraction)
    : fraction_(fraction), rest_until_s_(-std::numeric_limits<double>::infinity()) {
  if (!(fraction > 0.0 && fraction <= 1.0)) {
    throw std::invalid_argument("CPU budget " + std::to_string(fraction) +
                                ": a fraction of one core in (0, 1]");
  }
}

void CpuBudget::fit_done(double cpu_s, double end_s) {
  const double t = cpu_s > 0.0 ? cpu_s : 0.0;
  period_s_ = t / fraction_;
  rest_until_s_ = end_s + (period_s_ - t);  // t·(1/fraction − 1)
}

}  // namespace millwatch::identify
