#include "core/monitor/conditioner.hpp"

#include <cmath>

namespace millwatch::monitor {
namespace {

constexpr double kTareTime_s = 0.05;  // time constant of the re-zeroing while quiet

}  // namespace

Conditioner::Conditioner(const MonitorConfig& config, const signal::ButterworthDesign& filter)
    : axis_map_(config.axis_map), zero_phase_on_(config.filter_zero_phase) {
  for (auto& f : lowpass_) {
    f = signal::LowPassFilter(filter);
  }
  if (zero_phase_on_) {
    zero_phase_ = signal::ZeroPhaseFilter(filter, 3);
  }
  tare_gain_ = 1.0 / (kTareTime_s * config.sample_rate_hz);
  // The envelope forgets over about two revolutions at the commanded speed.
  const double revolution_hz = config.model.process.spindle_rpm / 60.0;
  envelope_decay_ = std::exp(-2.0 / (2.0 * config.sample_rate_hz / revolution_hz));
  decay_power_[0] = 1.0;
  for (std::size_t k = 1; k < decay_power_.size(); ++k) {
    decay_power_[k] = decay_power_[k - 1] * envelope_decay_;
  }
}

void Conditioner::set_stride(int stride) {
  stride_ = std::max(1, stride);
  const signal::ButterworthDesign& design = lowpass_[0].design();
  on_grid_ = stride_ > 1 && !zero_phase_on_ && signal::GridLowPass::supports(design, stride_);
  if (on_grid_) {
    grid_ = signal::GridLowPass(design, stride_, axis_map_.sign);
  }
  grid_decay_ = on_grid_ ? decay_power_[static_cast<std::size_t>(stride_)] : 1.0;
  grid_tare_gain_ = 1.0 - std::pow(1.0 - tare_gain_, stride_);
  fresh_ = true;
}

}  // namespace millwatch::monitor
