#include "tests/support/monitored_cut.hpp"

#include <complex>

#include "core/identify/calibration.hpp"
#include "tests/support/recording.hpp"

namespace millwatch::test {

MonitoredCut monitor_cut(const sim::Scenario& scenario, const monitor::MonitorConfig& config) {
  identify::CutWindows windows;
  monitor::Pipeline p(config, windows);
  replay(p, record(scenario), 1000);
  MonitoredCut out;
  out.windows = windows.windows();
  out.revolutions = static_cast<long>(windows.revolutions());
  const auto filter = p.filter();
  const bool zero_phase = config.filter_zero_phase;
  out.filter = [filter, zero_phase](double hz) {
    const std::complex<double> h = filter.response(hz);
    return zero_phase ? std::complex<double>(std::norm(h), 0.0) : h;
  };
  return out;
}

}  // namespace millwatch::test
