#include "tests/support/exact_window.hpp"

#include "core/model/steady_state.hpp"

namespace millwatch::test {

identify::MeasuredRevolution exact_window(const model::ModelConfig& truth) {
  model::SteadyStateWorkspace ws;
  const auto& ss = model::evaluate_steady_state(truth, truth.process.spindle_rpm, 1440, ws);
  identify::MeasuredRevolution m;
  m.force_N = {ss.mean.fx_N, ss.mean.fy_N, ss.mean.fz_N};
  m.spindle_rpm = truth.process.spindle_rpm;
  m.revolutions = 30;
  m.shared_bins = false;
  return m;
}

identify::MeasuredRevolution finer_window(const model::ModelConfig& m) {
  model::ModelConfig fine = m;
  fine.effects.helix_lag.discs = 20;
  return exact_window(fine);
}

std::complex<double> ideal_lowpass(double frequency_hz) {
  return {frequency_hz < 3300.0 ? 1.0 : 0.0, 0.0};
}

}  // namespace millwatch::test
