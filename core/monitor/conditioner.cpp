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
  for (auto& channel : checked_) {
    channel.assign(kCheckedBlock, 0.0);
  }
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

bool Conditioner::filter_checked(std::int64_t first, std::span<const double> fx,
                                 std::span<const double> fy, std::span<const double> fz,
                                 const std::array<double, 3>& limit) {
  const std::size_t count = fx.size();
  const std::array<int, 3>& s = axis_map_.source;
  const bool permutation = s[0] != s[1] && s[0] != s[2] && s[1] != s[2];
  if (zero_phase_on_ || count == 0 || count > checked_[0].size() || fy.size() != count ||
      fz.size() != count || !permutation) {
    return false;
  }
  const std::array<const double*, 3> in = {fx.data(), fy.data(), fz.data()};
  std::array<const double*, 3> source{};
  std::array<double, 3> source_limit{};
  for (std::size_t a = 0; a < 3; ++a) {
    const auto from = static_cast<std::size_t>(s[a]);
    source[a] = in[from];
    source_limit[a] = limit[from];
  }
  // A fresh stretch settles on its first sample (push_block()'s first chunk does): a failed
  // check leaves it fresh, to settle again on what the input check makes of that sample.
  const bool was_fresh = fresh_;
  if (fresh_) {
    if (on_grid_) {
      grid_.settle(first, {source[0][0], source[1][0], source[2][0]});
    } else {
      settle_lowpass(axis_map_.to_model({fx[0], fy[0], fz[0]}));
    }
    fresh_ = false;
  }
  // One pass over the block: its filtered values do not depend on how it is cut (the causal
  // filters run sample by sample; GridLowPass likewise), so push_block()'s chunks are handed on
  // from it as they were filtered one by one.
  const std::array<double*, 3> out = {checked_[0].data(), checked_[1].data(), checked_[2].data()};
  const bool within = on_grid_ ? grid_.process_checked(source, out, count, source_limit)
                               : signal::LowPassFilter::process_three_checked(
                                     lowpass_, source, axis_map_.sign, out, count, source_limit);
  if (!within) {
    fresh_ = was_fresh;
    return false;
  }
  checked_first_ = first;
  checked_count_ = count;
  return true;
}

}  // namespace millwatch::monitor
