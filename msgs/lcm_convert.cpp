#include "msgs/lcm_convert.hpp"

#include <cmath>
#include <limits>
#include <string>

namespace millwatch::messaging {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

template <typename Array>
std::vector<double> first(const Array& a, int n) {
  return std::vector<double>(a.begin(), a.begin() + n);
}

}  // namespace

force_block_t to_message(const monitor::SampleBlock& b) {
  force_block_t m;
  m.utime = b.utime_us;
  m.seq = b.seq;
  m.sample_rate_hz = b.sample_rate_hz;
  m.fx_N.assign(b.fx_N.begin(), b.fx_N.end());
  m.fy_N.assign(b.fy_N.begin(), b.fy_N.end());
  m.fz_N.assign(b.fz_N.begin(), b.fz_N.end());
  m.num_samples = static_cast<std::int32_t>(m.fx_N.size());
  return m;
}

monitor::SampleBlock to_block(const force_block_t& m) {
  // The length field is not trusted: a channel shorter than num_samples makes a malformed
  // block, which the pipeline rejects and counts.
  return {m.utime, m.seq, m.sample_rate_hz, m.fx_N, m.fy_N, m.fz_N};
}

tooth_periods_t tooth_periods(const monitor::RevolutionRecord& r) {
  const auto& m = r.measured;
  tooth_periods_t t;
  t.utime = r.utime_us;
  t.revolution = r.revolution;
  t.period_s = m.period_s;
  t.flute_period_s = first(m.flute_period_s, m.flutes);
  t.num_flutes = static_cast<std::int32_t>(t.flute_period_s.size());
  t.alpha_deg = m.alpha_deg;
  t.alpha_mean_deg = r.alpha_mean_deg;
  t.alpha_std_deg = r.alpha_std_deg;
  t.window_revolutions = r.window_revolutions;
  t.model_alpha_deg = r.model_valid ? r.model.alpha_deg : kNaN;
  return t;
}

flute_peaks_t flute_peaks(const monitor::RevolutionRecord& r) {
  const auto& m = r.measured;
  flute_peaks_t p;
  p.utime = r.utime_us;
  p.revolution = r.revolution;
  for (int j = 0; j < m.flutes; ++j) {
    const auto uj = static_cast<std::size_t>(j);
    p.peak_fx_N.push_back(m.peak_N[uj][0]);
    p.peak_fy_N.push_back(m.peak_N[uj][1]);
    p.peak_fz_N.push_back(m.peak_N[uj][2]);
    p.peak_resultant_N.push_back(m.peak_resultant_N[uj]);
    p.model_peak_resultant_N.push_back(r.model_valid ? r.model.peak_resultant_N[uj] : kNaN);
  }
  p.num_flutes = static_cast<std::int32_t>(p.peak_fx_N.size());
  p.delta_fy_N = m.delta_fy_N;
  p.delta_fy_mean_N = r.delta_fy_mean_N;
  p.model_delta_fy_N = r.model_valid ? r.model.delta_fy_N : kNaN;
  return p;
}

model_residual_t model_residual(const monitor::RevolutionRecord& r) {
  model_residual_t m;
  m.utime = r.utime_us;
  m.revolution = r.revolution;
  m.rms_fx_N = r.residual_rms_N[0];
  m.rms_fy_N = r.residual_rms_N[1];
  m.rms_fz_N = r.residual_rms_N[2];
  m.measured_rms_N = r.measured_rms_N;
  m.rms_flute_N = first(r.residual_flute_rms_N, r.measured.flutes);
  m.num_flutes = static_cast<std::int32_t>(m.rms_flute_N.size());
  m.rms_sector_N = first(r.residual_sector_rms_N, r.sectors);
  m.num_sectors = static_cast<std::int32_t>(m.rms_sector_N.size());
  m.model_offset_rad = r.model_offset_rad;
  return m;
}

spindle_state_t spindle_state(const monitor::SpindleUpdate& u) {
  spindle_state_t s;
  s.utime = u.utime_us;
  s.seq = u.seq;
  s.revolution = u.revolution;
  s.spindle_rpm_measured = u.estimate.valid ? u.estimate.spindle_rpm : kNaN;
  s.spindle_rpm_commanded = u.commanded_rpm;
  s.spindle_rpm_uncertainty = u.estimate.uncertainty_rpm;
  s.angle_rad = u.estimate.angle_rad;
  s.harmonic_snr_db = u.estimate.snr_db;
  s.valid = u.estimate.valid;
  s.cutting = u.estimate.cutting;
  return s;
}

tool_alert_t tool_alert(const monitor::Alert& a, std::int64_t seq) {
  tool_alert_t t;
  t.utime = a.utime_us;
  t.seq = seq;
  t.kind = static_cast<std::int8_t>(a.kind);
  t.severity = static_cast<std::int8_t>(a.severity);
  t.active = a.active;
  t.revolution = a.revolution;
  t.value = a.value;
  t.threshold = a.threshold;
  t.quantity = std::string(a.quantity);
  t.message = std::string(a.message.data());
  return t;
}

pipeline_status_t pipeline_status(const monitor::PipelineStatus& s, std::int64_t seq,
                                  std::int64_t published, std::int64_t dropped) {
  pipeline_status_t p;
  p.utime = s.utime_us;
  p.seq = seq;
  p.samples_in = s.input.samples_in;
  p.samples_processed = s.input.samples_accepted;
  p.samples_dropped = s.input.samples_dropped;
  p.samples_flagged = s.input.samples_flagged;
  p.nonfinite_samples = s.input.nonfinite_samples;
  p.saturated_samples = s.input.saturated_samples;
  p.gaps = s.input.gaps;
  p.out_of_order_blocks = s.input.out_of_order_blocks;
  p.blocks_rejected = s.input.blocks_rejected;
  p.revolutions = s.valid_revolutions;
  p.messages_published = published;
  p.messages_dropped = dropped;
  p.spindle_rpm = s.spindle_rpm;
  p.cutting = s.cutting;
  p.state = std::string(s.state);
  return p;
}

sync_average_t sync_average(const monitor::SyncAverage& measured, const monitor::Lockstep* model,
                            std::int64_t revolution, std::int64_t utime_us) {
  sync_average_t s;
  s.utime = utime_us;
  s.revolution = revolution;
  s.window_revolutions = measured.revolutions();
  measured.average(0, s.fx_N);
  measured.average(1, s.fy_N);
  measured.average(2, s.fz_N);
  s.num_bins = static_cast<std::int32_t>(s.fx_N.size());
  if (model != nullptr) {
    model->filtered_on_tracker_grid(0, s.num_bins, s.model_fx_N);
    model->filtered_on_tracker_grid(1, s.num_bins, s.model_fy_N);
    model->filtered_on_tracker_grid(2, s.num_bins, s.model_fz_N);
  } else {
    s.model_fx_N.assign(static_cast<std::size_t>(s.num_bins), 0.0);
    s.model_fy_N.assign(static_cast<std::size_t>(s.num_bins), 0.0);
    s.model_fz_N.assign(static_cast<std::size_t>(s.num_bins), 0.0);
  }
  return s;
}

}  // namespace millwatch::messaging
