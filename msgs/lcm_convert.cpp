#include "msgs/lcm_convert.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace millwatch::messaging {
namespace {

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

tooth_periods2_t tooth_periods(const monitor::RevolutionRecord& r) {
  const auto& m = r.measured;
  tooth_periods2_t t;
  t.utime = r.utime_us;
  t.revolution = r.revolution;
  t.event_kind = r.event_kind == monitor::ToothEventKind::kCentroid
                     ? tooth_periods2_t::EVENT_PULSE_CENTROID
                     : tooth_periods2_t::EVENT_VALLEY;
  t.valid = m.valid;
  t.spindle_rpm = r.spindle_rpm;
  // What was not measured is 0 with its flag down: the revolution's period needs its bounds
  // (both CE1 events), each flute's period and α every event.
  t.period_s = m.bounded ? m.period_s : 0.0;
  t.flute_period_s = first(m.flute_period_s, m.flutes);
  if (!m.valid) {
    std::fill(t.flute_period_s.begin(), t.flute_period_s.end(), 0.0);
  }
  t.num_flutes = static_cast<std::int32_t>(t.flute_period_s.size());
  t.alpha_deg = m.valid ? m.alpha_deg : 0.0;
  t.alpha_mean_deg = r.alpha_mean_deg;
  t.alpha_std_deg = r.alpha_std_deg;
  t.window_revolutions = r.window_revolutions;
  t.model_valid = r.model_valid && r.model.valid;
  t.model_alpha_deg = t.model_valid ? r.model.alpha_deg : 0.0;
  return t;
}

flute_peaks2_t flute_peaks(const monitor::RevolutionRecord& r) {
  const auto& m = r.measured;
  flute_peaks2_t p;
  p.utime = r.utime_us;
  p.revolution = r.revolution;
  p.valid = m.valid;
  p.model_valid = r.model_valid && r.model.valid;
  for (int j = 0; j < m.flutes; ++j) {
    const auto uj = static_cast<std::size_t>(j);
    p.peak_fx_N.push_back(m.peak_N[uj][0]);
    p.peak_fy_N.push_back(m.peak_N[uj][1]);
    p.peak_fz_N.push_back(m.peak_N[uj][2]);
    p.peak_resultant_N.push_back(m.peak_resultant_N[uj]);
    p.range_fx_N.push_back(m.range_N[uj][0]);
    p.range_fy_N.push_back(m.range_N[uj][1]);
    p.model_peak_resultant_N.push_back(p.model_valid ? r.model.peak_resultant_N[uj] : 0.0);
  }
  p.num_flutes = static_cast<std::int32_t>(p.peak_fx_N.size());
  p.delta_fy_N = m.valid ? m.delta_fy_N : 0.0;  // CE2's peak needs its event
  p.delta_fy_mean_N = r.delta_fy_mean_N;
  p.model_delta_fy_N = p.model_valid ? r.model.delta_fy_N : 0.0;
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

spindle_state2_t spindle_state(const monitor::SpindleUpdate& u) {
  const auto& e = u.estimate;
  spindle_state2_t s;
  s.utime = u.utime_us;
  s.seq = u.seq;
  s.revolution = e.valid ? u.revolution : 0;
  s.valid = e.valid;
  s.cutting = e.cutting;
  s.consistent = e.consistent;
  s.spindle_rpm_measured = e.valid ? e.spindle_rpm : 0.0;
  s.spindle_rpm_commanded = u.commanded_rpm;
  s.spindle_rpm_uncertainty = e.valid ? e.uncertainty_rpm : 0.0;
  s.harmonic_snr_db = e.snr_db;
  s.speed_agreement = e.agreement;
  s.phase_error_rad = e.phase_error_rad;
  s.angle_rad = e.angle_rad;
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

pipeline_status5_t pipeline_status(const monitor::PipelineStatus& s, std::int64_t seq,
                                   std::int64_t published, std::int64_t dropped) {
  pipeline_status5_t p;
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
  p.revolutions = s.revolutions;
  p.valid_revolutions = s.valid_revolutions;
  p.idle_revolutions = s.idle_revolutions;
  p.cutting_revolutions = s.cutting_revolutions;
  p.model_builds = s.model_builds;
  p.identifications_taken = s.identifications_taken;
  p.identifications_rejected = s.identifications_rejected;
  p.identifications_superseded = s.identifications_superseded;
  p.alert_held_revolutions = s.alert_held_revolutions;
  p.alerts_holding = s.alerts_holding;
  p.flutes_relabelled = s.flutes_relabelled;
  p.relabelled_from_revolution = s.relabelled_from_revolution;
  p.messages_published = published;
  p.messages_dropped = dropped;
  p.spindle_rpm = s.spindle_rpm;
  p.cutting = s.cutting;
  p.state = std::string(s.state);
  p.tooth_event = std::string(s.event_kind);
  return p;
}

runout_estimate_t runout_estimate(const identify::IdentifiedWindow& w) {
  runout_estimate_t m{};
  m.utime = w.utime_us;
  m.revolution = w.revolution;
  m.window_revolutions = w.window_revolutions;
  m.method = "window fit (flute 0 = CE1, the flute with the largest cut)";
  const identify::FitResult& f = w.fit;
  m.valid = f.ok && std::isfinite(f.rho_um.value) && std::isfinite(f.rho_um.sigma);
  if (!m.valid) {
    m.method = "window fit failed: " + f.message;
    return m;
  }
  if (f.runout_at_contact_edge) {
    m.method +=
        "; at a flute's contact edge: offset_um is a lower bound (a flute cuts nothing "
        "beyond it)";
    if (f.edge_flute == 1 && f.config.tool.flutes == 2) {
      m.method += ", and so is r_CE1 − r_CE2";
    } else if (f.edge_flute >= 0) {
      m.method += "; CE" + std::to_string(f.edge_flute + 1) +
                  " cuts nothing: its radius lies at least a chip below the flute's before it";
    }
  }
  m.offset_um = f.rho_um.value;
  m.angle_rad = f.gamma_rad.value;
  m.offset_sigma_um = f.rho_um.sigma;
  m.angle_sigma_rad = f.gamma_rad.sigma;
  m.r_ce1_um = f.cutting_radius_um.empty() ? 0.0 : f.cutting_radius_um[0].value;
  m.r_ce2_um = f.cutting_radius_um.size() < 2 ? 0.0 : f.cutting_radius_um[1].value;
  m.alpha_deg = f.alpha_deg.value;  // the geometric α (0 for one flute: none)
  return m;
}

force_coefficients_t force_coefficients(const identify::IdentifiedWindow& w) {
  force_coefficients_t m{};
  m.utime = w.utime_us;
  m.revolution = w.revolution;
  m.window_revolutions = w.window_revolutions;
  m.valid = w.fit.ok;
  if (!m.valid) {
    return m;
  }
  for (const identify::Estimate& e : w.fit.coefficients) {
    // A coefficient the window does not pin has no σ to send (0 would claim it exact): left out,
    // as the summary's "determined": false says.
    if (!std::isfinite(e.value) || !std::isfinite(e.sigma) || !e.determined) {
      continue;
    }
    m.name.push_back(e.name);
    m.value.push_back(e.value);
    m.sigma.push_back(e.sigma);
  }
  m.num_coefficients = static_cast<std::int32_t>(m.name.size());
  m.residual_rms_N = std::hypot(w.fit.residual_rms_N[0], w.fit.residual_rms_N[1]);
  return m;
}

}  // namespace millwatch::messaging
