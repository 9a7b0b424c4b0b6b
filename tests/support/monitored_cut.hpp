#pragma once
// A simulated cut through the monitor, as identification sees it: the synchronous-average
// windows the pipeline hands over (each with its revolutions' mean speed) and the filter the
// measurement went through.

#include <vector>

#include "core/identify/window_fit.hpp"
#include "core/monitor/monitor_config.hpp"
#include "core/sim/scenario.hpp"

namespace millwatch::test {

struct MonitoredCut {
  std::vector<identify::MeasuredRevolution> windows;
  identify::FilterResponse filter;  ///< the pipeline's (causal H, or |H|² for zero phase)
  long revolutions = 0;             ///< revolutions the monitor measured
};

/// Simulates `scenario` and runs the pipeline of `config` over it (blocks of 1000 samples).
MonitoredCut monitor_cut(const sim::Scenario& scenario, const monitor::MonitorConfig& config);

}  // namespace millwatch::test
