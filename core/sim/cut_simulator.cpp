#include "core/sim/cut_simulator.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace millwatch::sim {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

model::ModelConfig initial_config(const Scenario& s) {
  model::ModelConfig c = s.model;
  if (s.wear.enabled) {
    c.effects.flank_wear.enabled = true;
    c.effects.flank_wear.wear_um = s.wear.start_um;
  }
  return c;
}

/// `to`'s force coefficients (the law's K's, the flank-wear rubbing ones) = `from`'s × factor.
void scale_coefficients(const model::ModelConfig& from, double factor, model::ModelConfig& to) {
  const auto& pl = from.material.power_law;
  auto& p = to.material.power_law;
  p.k_tc_Nmm = factor * pl.k_tc_Nmm;
  p.k_nc_Nmm = factor * pl.k_nc_Nmm;
  p.k_tp_Nmm = factor * pl.k_tp_Nmm;
  p.k_np_Nmm = factor * pl.k_np_Nmm;
  p.k_ac_Nmm = factor * pl.k_ac_Nmm;
  p.k_ap_Nmm = factor * pl.k_ap_Nmm;
  const auto& le = from.material.linear_edge;
  auto& l = to.material.linear_edge;
  l.k_tc_N_per_mm2 = factor * le.k_tc_N_per_mm2;
  l.k_nc_N_per_mm2 = factor * le.k_nc_N_per_mm2;
  l.k_ac_N_per_mm2 = factor * le.k_ac_N_per_mm2;
  l.k_te_N_per_mm = factor * le.k_te_N_per_mm;
  l.k_ne_N_per_mm = factor * le.k_ne_N_per_mm;
  l.k_ae_N_per_mm = factor * le.k_ae_N_per_mm;
  l.k_tp_N_per_mm3 = factor * le.k_tp_N_per_mm3;
  l.k_np_N_per_mm3 = factor * le.k_np_N_per_mm3;
  l.k_ap_N_per_mm3 = factor * le.k_ap_N_per_mm3;
  l.a_t_Nmm = factor * le.a_t_Nmm;
  l.a_n_Nmm = factor * le.a_n_Nmm;
  l.a_a_Nmm = factor * le.a_a_Nmm;
  to.material.kronenberg.k_s0_N_per_mm2 = factor * from.material.kronenberg.k_s0_N_per_mm2;
  to.effects.flank_wear.k_wt_N_per_mm2 = factor * from.effects.flank_wear.k_wt_N_per_mm2;
  to.effects.flank_wear.k_wn_N_per_mm2 = factor * from.effects.flank_wear.k_wn_N_per_mm2;
}

}  // namespace

CutSimulator::CutSimulator(const Scenario& scenario)
    : scenario_(scenario),
      spindle_(scenario),
      config_(initial_config(scenario)),
      workspace_(config_, config_.resolution.steps_per_rev),
      evaluated_(config_),
      rng_(scenario.seed) {
  scale_result_ = !config_.effects.deflection.enabled;
  feed_rate_um_per_min_ = scenario_.model.process.feed_per_tooth_um * scenario_.model.tool.flutes *
                          scenario_.model.process.spindle_rpm;
  total_samples_ = std::llround(scenario_.duration_s * scenario_.sample_rate_hz);
  for (auto& p : hum_phase_rad_) {
    p = kTwoPi * std::uniform_real_distribution<double>(0.0, 1.0)(rng_);
  }
  const double fastest_rpm = std::max({actual_rpm(scenario_), scenario_.spindle.ramp_end_rpm});
  truth_.reserve(static_cast<std::size_t>(scenario_.duration_s * fastest_rpm / 60.0) + 8);
  const auto steps = static_cast<std::size_t>(config_.resolution.steps_per_rev);
  for (std::size_t a = 0; a < 3; ++a) {
    current_[a].assign(steps, 0.0);
    next_[a].assign(steps, 0.0);
  }
  // Start in the steady cut: the first two revolutions.
  advance_revolution(0.0);
  current_ = next_;
  current_cutting_ = next_cutting_;
  current_revolution_ = 0;
  const double rev_s = 60.0 / std::max(spindle_.rpm_at(0.0), 1.0);
  advance_revolution(rev_s);
}

RevolutionTruth CutSimulator::configure_revolution(double start_s) {
  RevolutionTruth t;
  t.start_s = start_s;
  t.spindle_rpm = spindle_.rpm_at(start_s);
  t.cutting = spindle_.cutting_at(start_s) && t.spindle_rpm > 0.0;
  auto& process = config_.process;
  auto& runout = config_.effects.runout;
  if (t.cutting) {
    process.spindle_rpm = t.spindle_rpm;
    process.feed_per_tooth_um = feed_rate_um_per_min_ / (config_.tool.flutes * t.spindle_rpm);
  }
  if (scenario_.runout_change.enabled && start_s >= scenario_.runout_change.time_s) {
    runout.enabled = true;
    runout.offset_um = scenario_.runout_change.offset_um;
    runout.angle_rad = scenario_.runout_change.angle_rad;
  }
  if (scenario_.wear.enabled) {
    const double progress = std::clamp(start_s / scenario_.duration_s, 0.0, 1.0);
    auto& wear = config_.effects.flank_wear.wear_um;
    for (std::size_t j = 0; j < wear.size(); ++j) {
      wear[j] = scenario_.wear.start_um[j] +
                progress * (scenario_.wear.end_um[j] - scenario_.wear.start_um[j]);
    }
  }
  if (scenario_.coefficient_drift.enabled) {
    const double progress = std::clamp(start_s / scenario_.duration_s, 0.0, 1.0);
    factor_ = 1.0 + progress * (scenario_.coefficient_drift.end_factor - 1.0);
    if (!scale_result_) {
      scale_coefficients(scenario_.model, factor_, config_);
    }
  }
  t.coefficient_factor = factor_;
  t.feed_per_tooth_um = process.feed_per_tooth_um;
  t.runout_offset_um = runout.enabled ? runout.offset_um : 0.0;
  t.runout_angle_rad = runout.enabled ? runout.angle_rad : 0.0;
  t.wear_um = config_.effects.flank_wear.enabled ? config_.effects.flank_wear.wear_um
                                                 : std::vector<double>{0.0};
  return t;
}

bool CutSimulator::conditions_changed() const {
  const auto& a = config_;
  const auto& b = evaluated_;
  return !has_result_ || a.process.spindle_rpm != b.process.spindle_rpm ||
         a.process.feed_per_tooth_um != b.process.feed_per_tooth_um ||
         a.effects.runout.enabled != b.effects.runout.enabled ||
         a.effects.runout.offset_um != b.effects.runout.offset_um ||
         a.effects.runout.angle_rad != b.effects.runout.angle_rad ||
         a.effects.flank_wear.wear_um != b.effects.flank_wear.wear_um ||
         (!scale_result_ && factor_ != evaluated_factor_);
}

void CutSimulator::advance_revolution(double start_s) {
  truth_.push_back(configure_revolution(start_s));
  next_cutting_ = truth_.back().cutting;
  if (!next_cutting_) {
    for (auto& axis : next_) {
      std::fill(axis.begin(), axis.end(), 0.0);
    }
    return;
  }
  if (conditions_changed()) {
    const model::SteadyState& st = model::evaluate_steady_state(
        config_, config_.process.spindle_rpm, config_.resolution.steps_per_rev, workspace_,
        model::SteadyStateOutput::kMeanAndCycle);
    ++played_.evaluations;
    played_.cycles_cut += st.cycle_exact ? 0 : 1;
    played_.longest_cycle_revolutions =
        std::max(played_.longest_cycle_revolutions, st.cycle_revolutions);
    if (st.stats.unconverged_slots >= played_.unsettled_slots) {
      played_.unsettled_slots = st.stats.unconverged_slots;
      played_.slots = st.stats.slots;
    }
    evaluated_.process = config_.process;
    evaluated_.effects.runout = config_.effects.runout;
    evaluated_.effects.flank_wear.wear_um = config_.effects.flank_wear.wear_um;  // same size
    evaluated_factor_ = scale_result_ ? 1.0 : factor_;
    has_result_ = true;
  }
  // Revolution n of the record plays revolution n mod L of the cycle.
  const model::SteadyState& state = workspace_.result();
  const auto n = static_cast<long>(truth_.size()) - 1;
  const int m = static_cast<int>(n % state.cycle_revolutions);
  truth_.back().round_again = !state.cycle_exact && n >= state.cycle_revolutions;
  const double scale = factor_ / evaluated_factor_;
  for (int a = 0; a < 3; ++a) {
    const auto revolution = state.revolution(m, a);
    std::transform(revolution.begin(), revolution.end(), next_[static_cast<std::size_t>(a)].begin(),
                   [scale](double f) { return scale * f; });
  }
}

std::array<double, 3> CutSimulator::clean_force(double revolutions) const {
  const double frac = revolutions - std::floor(revolutions);
  const auto steps = static_cast<std::size_t>(config_.resolution.steps_per_rev);
  const double pos = frac * static_cast<double>(steps);
  auto k0 = static_cast<std::size_t>(pos);
  k0 = std::min(k0, steps - 1);
  const double w = pos - static_cast<double>(k0);
  std::array<double, 3> f{};
  for (std::size_t a = 0; a < 3; ++a) {
    const double v0 = current_[a][k0];
    const double v1 = k0 + 1 < steps ? current_[a][k0 + 1] : next_[a][0];
    f[a] = v0 + w * (v1 - v0);
  }
  return f;
}

std::array<double, 3> CutSimulator::measure(const std::array<double, 3>& force_N, double t) {
  std::array<double, 3> reading = scenario_.axis_map.to_reading(force_N);
  for (std::size_t a = 0; a < 3; ++a) {
    double v = reading[a];
    if (scenario_.drift.enabled) {
      v += scenario_.drift.rate_N_per_s[a] * t;
    }
    if (scenario_.hum.enabled) {
      v += scenario_.hum.amplitude_N[a] *
           std::sin(kTwoPi * scenario_.hum.frequency_hz * t + hum_phase_rad_[a]);
    }
    if (scenario_.noise.enabled) {
      v += scenario_.noise.sigma_N[a] * gauss_(rng_);
    }
    if (scenario_.quantisation.enabled) {
      const double range = scenario_.quantisation.range_N[a];
      const double step = 2.0 * range / std::ldexp(1.0, scenario_.quantisation.bits);
      v = std::clamp(v, -range, range - step);
      v = std::round(v / step) * step;
    }
    reading[a] = v;
  }
  return reading;
}

std::size_t CutSimulator::next_block(std::span<double> time_s, std::span<double> fx_N,
                                     std::span<double> fy_N, std::span<double> fz_N) {
  const std::size_t capacity = std::min({time_s.size(), fx_N.size(), fy_N.size(), fz_N.size()});
  std::size_t n = 0;
  while (n < capacity && next_sample_ < total_samples_) {
    const double t = static_cast<double>(next_sample_) / scenario_.sample_rate_hz;
    const double revs = spindle_.revolutions_at(t);
    const auto revolution = static_cast<long>(std::floor(revs));
    while (revolution > current_revolution_) {
      current_.swap(next_);
      current_cutting_ = next_cutting_;
      ++current_revolution_;
      // The revolution just begun: its parameters were set one revolution ahead.
      truth_[static_cast<std::size_t>(current_revolution_)].start_s = t;
      const double rev_s = 60.0 / std::max(spindle_.rpm_at(t), 1.0);
      advance_revolution(t + rev_s);
    }
    last_clean_ =
        current_cutting_ && spindle_.cutting_at(t) ? clean_force(revs) : std::array<double, 3>{};
    clean_stats_.add(last_clean_);
    const auto reading = measure(last_clean_, t);
    time_s[n] = t;
    fx_N[n] = reading[0];
    fy_N[n] = reading[1];
    fz_N[n] = reading[2];
    ++n;
    ++next_sample_;
  }
  return n;
}

}  // namespace millwatch::sim
