#pragma once
// A simulated cut monitored and identified as the daemon does it, but synchronously: the
// pipeline measures every revolution, and each synchronous-average window is fitted
// (identify::WindowFitter, seeded with the previous window's result) as soon as the pipeline
// reports it. The revolutions and the identified windows are kept in the order an AlertEngine
// receives them: a window right after its last revolution.

#include <cstdint>
#include <vector>

#include "core/identify/identifier.hpp"
#include "core/monitor/alert_engine.hpp"
#include "core/monitor/monitor_config.hpp"
#include "core/monitor/revolution_record.hpp"
#include "core/sim/cut_simulator.hpp"

namespace millwatch::test {

struct IdentifiedCut {
  /// In order: a revolution (window < 0) or an identified window (its index in `windows`).
  struct Step {
    std::int64_t revolution = -1;  ///< index into `revolutions`
    int window = -1;
  };
  std::vector<monitor::RevolutionRecord> revolutions;
  std::vector<identify::IdentifiedWindow> windows;  ///< fitted windows (fit.ok or not)
  std::vector<Step> order;
  std::vector<monitor::Alert> pipeline_alerts;  ///< the pipeline's own engine (no estimates)
  std::vector<sim::RevolutionTruth> truth;      ///< the simulator's, per truth revolution
  double fit_seconds = 0.0;                     ///< wall-clock time of all fits
};

/// Simulates `s`, monitors it with `c` (blocks of 1 ms) and fits every window with `options`.
IdentifiedCut identify_cut(const sim::Scenario& s, const monitor::MonitorConfig& c,
                           const identify::FitOptions& options);

/// Feeds the cut to `engine` in order (without the windows if `with_estimates` is false) and
/// returns what it raised and cleared.
std::vector<monitor::Alert> replay_alerts(const IdentifiedCut& cut, monitor::AlertEngine& engine,
                                          bool with_estimates = true);

}  // namespace millwatch::test
