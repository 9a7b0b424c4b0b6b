#pragma once
// When the alerts stop waiting for identified estimates and follow the flute forces instead
// (the pipeline then calls AlertEngine::expect_estimates(false)).
//
// Without a CPU budget (a replay, or identification.cpu_budget 1): after kChances windows went to
// the identifier with no estimate accepted since (fits rejected, or a live worker that cannot
// keep up). With one, the worker skips windows on purpose between fits (identify::CpuBudget), so
// a count of windows says nothing: the last accepted estimate stays recent enough while it is
// younger than kChances × (budget period + window) — the same three chances for a fit to be
// accepted, at the pace the budget allows (a budget period is the last fit's CPU time over the
// budget: fit and rest). Ages are in sample time (the windows' utime), periods in wall time: live
// they run alike. Before the first accepted estimate the count alone decides.
//
//   EstimateWatch w;
//   if (w.window_submitted(utime_us, window_s, identifier.budget_period_s())) fall_back();
//   w.estimate_accepted(window_utime_us);

#include <cstdint>
#include <limits>

namespace millwatch::identify {

class EstimateWatch {
 public:
  static constexpr int kChances = 3;

  /// A window ending at `utime_us`, `window_s` long, went to the identifier, whose budget period
  /// is `budget_period_s` (0: no budget). True when the alerts should stop waiting for estimates.
  bool window_submitted(std::int64_t utime_us, double window_s, double budget_period_s);
  /// An estimate was accepted, of the window ending at `utime_us`.
  void estimate_accepted(std::int64_t utime_us);

  [[nodiscard]] int windows_without_estimate() const { return windows_without_; }

 private:
  int windows_without_ = 0;  // submitted since the last accepted estimate
  std::int64_t last_estimate_utime_us_ = std::numeric_limits<std::int64_t>::min();  // none yet
};

}  // namespace millwatch::identify
