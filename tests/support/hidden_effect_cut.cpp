#include "tests/support/hidden_effect_cut.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

#include "core/sim/cut_simulator.hpp"
#include "tests/support/realistic_cut.hpp"

namespace millwatch::test {

sim::Scenario hidden_effect_scenario(const std::vector<std::string>& hidden, double duration_s,
                                     double sample_rate_hz, unsigned seed) {
  sim::Scenario s;
  s.sample_rate_hz = sample_rate_hz;
  s.duration_s = duration_s;
  s.seed = seed;
  s.axis_map = signal::identity_axis_map();
  auto& m = s.model;
  m = model::without_effects(m);
  m.process.feed_per_tooth_um = 4.0;
  measure_like_a_real_cut(s);  // noise, quantisation, a truth finer than the fitted model
  // The dynamometer's nominal resonance, as configured (the truth's differs when hidden).
  m.effects.dynamometer.natural_hz = {2145.0, 2192.0, 3000.0};
  for (const auto& h : hidden) {
    if (h == "runout") {
      model::set_effect(m, "runout", true);
      m.effects.runout.offset_um = 1.0;
      m.effects.runout.angle_rad = 0.6;
    } else if (h == "min_chip_thickness") {
      model::set_effect(m, "min_chip", true);
      m.effects.min_chip.h_min_um = 1.0;
    } else if (h == "accumulation_like_runout") {
      // Chips between h_min/2 and h_min over most of the engagement: every other pass removes
      // nothing and its chip goes to the next, so one flute cuts double and the other ploughs — a
      // once-per-revolution pattern like runout's; the thin chips near entry and exit skip
      // passes in longer cycles (sub-harmonics of the tooth-passing frequency).
      model::set_effect(m, "min_chip", true);
      model::set_effect(m, "accumulation", true);
      model::set_effect(m, "multi_pass", true);
      m.effects.min_chip.h_min_um = 1.3;
      m.process.feed_per_tooth_um = 1.0;
    } else if (h == "chip_accumulation") {
      model::set_effect(m, "min_chip", true);
      model::set_effect(m, "accumulation", true);
      model::set_effect(m, "multi_pass", true);
      m.effects.min_chip.h_min_um = 1.2;
      m.process.feed_per_tooth_um = 2.0;
    } else if (h == "ploughing_area") {
      // [001]'s law (the AlSi10Mg preset's assumed coefficients): the shear force and, in place
      // of an edge force, K_p times the area ploughed while the chip is below h_min = 1.5 µm, at
      // 3 µm a tooth (the chip below it over a third of the slot: θ < 30° and θ > 150°).
      m.material.law = model::ForceLawKind::kLinearEdge;
      auto& le = m.material.linear_edge;
      le = {};
      le.k_tc_N_per_mm2 = 1000.0;
      le.k_nc_N_per_mm2 = 420.0;
      le.k_ac_N_per_mm2 = 60.0;
      le.k_te_N_per_mm = le.k_ne_N_per_mm = le.k_ae_N_per_mm = 0.0;
      le.k_tp_N_per_mm3 = 4000.0;
      le.k_np_N_per_mm3 = 6000.0;
      le.k_ap_N_per_mm3 = 500.0;
      model::set_effect(m, "ploughing_area", true);
      model::set_effect(m, "min_chip", true);
      m.effects.min_chip.h_min_um = 1.5;
      m.process.feed_per_tooth_um = 3.0;
      m.process.axial_depth_mm = 0.2;
    } else if (h == "tool_deflection") {
      model::set_effect(m, "deflection", true);
      m.effects.deflection.stiffness_N_per_um = 0.15;
    } else if (h == "helix_lag") {
      model::set_effect(m, "helix_lag", true);
      m.process.axial_depth_mm = 0.1;
    } else if (h == "trochoidal_path") {
      // The exact path departs from f_t·sin θ by ~f_t/(2R) of the chip: 2.5 % at 10 µm a tooth
      // on the 0.2 mm radius.
      model::set_effect(m, "trochoidal", true);
      m.process.feed_per_tooth_um = 10.0;
    } else if (h == "dynamometer_dynamics") {
      model::set_effect(m, "dynamometer", true);
      m.effects.dynamometer.natural_hz = {2300.0, 2360.0, 3000.0};
      m.effects.dynamometer.damping_ratio = {0.04, 0.06, 0.05};
    } else if (h == "spindle_speed_error") {
      s.spindle.actual_rpm = 0.99 * m.process.spindle_rpm;
    } else if (h == "amplifier_drift") {
      s.drift.enabled = true;
      s.drift.rate_N_per_s = {0.06, -0.05, 0.0};
    } else if (h == "runout_change") {
      // The tool re-clamped half-way: the runout jumps (from whatever the cut had).
      s.runout_change.enabled = true;
      s.runout_change.time_s = 0.5 * duration_s;
      s.runout_change.offset_um = 2.0;
      s.runout_change.angle_rad = 1.2;
      model::set_effect(m, "runout", true);
    } else if (h == "tool_wear") {
      s.wear.enabled = true;
      s.wear.start_um = {1.0};
      s.wear.end_um = {9.0};
    } else if (h == "mains_hum") {
      s.hum.enabled = true;
      s.hum.frequency_hz = 50.0;
      s.hum.amplitude_N = {0.02, 0.015, 0.0};
    } else {
      throw std::invalid_argument("hidden_effect_scenario: no recipe for '" + h + "'");
    }
  }
  return s;
}

const diagnose::Parameter* find_parameter(const std::vector<diagnose::Parameter>& ps,
                                          const std::string& name) {
  const auto it = std::find_if(ps.begin(), ps.end(),
                               [&](const diagnose::Parameter& p) { return p.name == name; });
  return it == ps.end() ? nullptr : &*it;
}

diagnose::CutRecord record_in_model_frame(const sim::Scenario& s) {
  // A data acquisition samples behind an anti-aliasing filter; the simulator samples the force
  // as it is (its harmonics above Nyquist would fold onto the spindle harmonics and look like a
  // model error). So the cut is simulated clean at 8× the rate, low-passed by a Kaiser-windowed
  // sinc (flat to 0.4·fs, −80 dB from 0.5·fs), decimated, and only then are the noise and the
  // quantisation added at the recorder's rate.
  constexpr int kOver = 8;
  sim::Scenario fine = s;
  fine.sample_rate_hz = kOver * s.sample_rate_hz;
  fine.noise.enabled = false;
  fine.quantisation.enabled = false;
  sim::CutSimulator sim(fine);
  const auto n_in = static_cast<std::size_t>(sim.total_samples());
  std::vector<double> t(n_in), fx(n_in), fy(n_in), fz(n_in);
  sim.next_block(t, fx, fy, fz);
  const double pi = std::numbers::pi;
  const double cutoff = 0.45 / kOver;     // cycles per input sample
  const double transition = 0.1 / kOver;  // 0.4·fs to 0.5·fs of the output rate
  const double attenuation_db = 80.0;
  const int taps =
      static_cast<int>(std::ceil((attenuation_db - 8.0) / (2.285 * 2.0 * pi * transition))) | 1;
  const double beta = 0.1102 * (attenuation_db - 8.7);
  auto bessel_i0 = [](double x) {
    double sum = 1.0, term = 1.0;
    for (int k = 1; k < 50; ++k) {
      term *= (x / (2.0 * k)) * (x / (2.0 * k));
      sum += term;
    }
    return sum;
  };
  std::vector<double> h(static_cast<std::size_t>(taps));
  const int half = taps / 2;
  double gain = 0.0;
  for (int i = 0; i < taps; ++i) {
    const double m = i - half;
    const double sinc = m == 0 ? 2.0 * cutoff : std::sin(2.0 * pi * cutoff * m) / (pi * m);
    const double r = m / half;
    h[static_cast<std::size_t>(i)] =
        sinc * bessel_i0(beta * std::sqrt(1.0 - r * r)) / bessel_i0(beta);
    gain += h[static_cast<std::size_t>(i)];
  }
  for (auto& v : h) {
    v /= gain;
  }
  // Output sample j at input sample j·kOver; the record starts and ends where the filter's
  // whole support is inside the simulated cut.
  const std::size_t first = static_cast<std::size_t>(half + kOver - 1) / kOver;
  const std::size_t n_out = (n_in - static_cast<std::size_t>(half)) / kOver - first;
  std::mt19937_64 rng(s.seed * 7919U + 17U);
  std::normal_distribution<double> gauss(0.0, 1.0);
  diagnose::CutRecord r;
  r.sample_rate_hz = s.sample_rate_hz;
  std::array<const std::vector<double>*, 3> in = {&fx, &fy, &fz};
  std::array<std::vector<double>, 3> out;
  for (std::size_t a = 0; a < 3; ++a) {
    out[a].resize(n_out);
    for (std::size_t j = 0; j < n_out; ++j) {
      const std::size_t centre = (first + j) * kOver;
      double acc = 0.0;
      for (int i = 0; i < taps; ++i) {
        acc += h[static_cast<std::size_t>(i)] *
               (*in[a])[centre + static_cast<std::size_t>(i) - static_cast<std::size_t>(half)];
      }
      if (s.noise.enabled) {
        acc += s.noise.sigma_N[a] * gauss(rng);
      }
      if (s.quantisation.enabled) {
        const double q = 2.0 * s.quantisation.range_N[a] / std::pow(2.0, s.quantisation.bits);
        acc = std::clamp(q * std::round(acc / q), -s.quantisation.range_N[a],
                         s.quantisation.range_N[a]);
      }
      out[a][j] = acc;
    }
  }
  r.force_N[0].resize(n_out);
  r.force_N[1].resize(n_out);
  for (std::size_t j = 0; j < n_out; ++j) {
    const auto f = s.axis_map.to_model({out[0][j], out[1][j], out[2][j]});
    r.force_N[0][j] = f[0];
    r.force_N[1][j] = f[1];
  }
  return r;
}

namespace {

HiddenEffectCut make_cut(const std::vector<std::string>& hidden,
                         const std::vector<std::string>& known, double duration_s,
                         double sample_rate_hz, unsigned seed, double feed_per_tooth_um) {
  HiddenEffectCut c;
  std::vector<std::string> all = hidden;
  all.insert(all.end(), known.begin(), known.end());
  c.scenario = hidden_effect_scenario(all, duration_s, sample_rate_hz, seed);
  if (feed_per_tooth_um > 0.0) {
    c.scenario.model.process.feed_per_tooth_um = feed_per_tooth_um;
  }
  c.record = record_in_model_frame(c.scenario);
  // What the diagnosis knows: the plain model of the cut as commanded, at the fitter's
  // resolution, the coefficients off by tens of percent (they are fitted).
  model::ModelConfig m = diagnose::plain_model(c.scenario.model);
  m.resolution.steps_per_rev = 720;
  m.effects.helix_lag.discs = 5;
  m.effects.dynamometer.natural_hz = {2145.0, 2192.0, 3000.0};
  m.effects.dynamometer.damping_ratio = {0.05, 0.05, 0.05};
  m.effects.min_chip.h_min_um = 0.5;
  m.effects.deflection.stiffness_N_per_um = 0.47;
  m.material.power_law.k_tc_Nmm *= 0.8;
  m.material.power_law.k_nc_Nmm *= 1.3;
  // The known effects are in the starting model (their parameters are fitted from there).
  for (const auto& k : known) {
    if (k == "runout") {
      model::set_effect(m, "runout", true);
      m.effects.runout.offset_um = 0.5;
      m.effects.runout.angle_rad = 0.0;
    } else {
      throw std::invalid_argument("hidden_effect_cut: no starting recipe for known '" + k + "'");
    }
  }
  c.start = m;
  return c;
}

}  // namespace

HiddenEffectCut hidden_effect_cut(const std::vector<std::string>& hidden,
                                  const std::vector<std::string>& known, double duration_s,
                                  double sample_rate_hz, unsigned seed) {
  return make_cut(hidden, known, duration_s, sample_rate_hz, seed, 0.0);
}

HiddenEffectCut hidden_effect_cut_at_feed(const std::vector<std::string>& hidden,
                                          double feed_per_tooth_um, double duration_s,
                                          double sample_rate_hz, unsigned seed) {
  return make_cut(hidden, {}, duration_s, sample_rate_hz, seed, feed_per_tooth_um);
}

}  // namespace millwatch::test
