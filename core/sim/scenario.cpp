#include "core/sim/scenario.hpp"

#include <algorithm>
#include <string>

#include "core/config/json_reader.hpp"

namespace millwatch::sim {
namespace {

using config::closed;
using config::non_negative;
using config::ObjectReader;
using config::positive;

std::array<double, 3> triple(ObjectReader& r, const char* key,
                             const std::array<double, 3>& fallback, const config::Range& range) {
  const auto v = r.numbers(key, {fallback.begin(), fallback.end()}, range, 3, 3);
  return {v[0], v[1], v[2]};
}

std::string profile_name(SpindleProfileKind k) {
  switch (k) {
    case SpindleProfileKind::kRamp:
      return "ramp";
    case SpindleProfileKind::kStopStart:
      return "stop_start";
    case SpindleProfileKind::kSteady:
      break;
  }
  return "steady";
}

SpindleSettings read_spindle(ObjectReader r, double duration_s) {
  SpindleSettings s;
  const std::string profile = r.choice("profile", "steady", {"steady", "ramp", "stop_start"});
  s.profile = profile == "ramp"         ? SpindleProfileKind::kRamp
              : profile == "stop_start" ? SpindleProfileKind::kStopStart
                                        : SpindleProfileKind::kSteady;
  s.actual_rpm = r.number("actual_rpm", s.actual_rpm, non_negative(200000.0, "rpm"));
  s.ramp_end_rpm = r.number("ramp_end_rpm", s.ramp_end_rpm, non_negative(200000.0, "rpm"));
  s.ramp_start_s = r.number("ramp_start_s", s.ramp_start_s, non_negative(duration_s, "s"));
  s.ramp_end_s = r.number("ramp_end_s", s.ramp_end_s, non_negative(duration_s, "s"));
  s.stop_s = r.number("stop_s", s.stop_s, non_negative(duration_s, "s"));
  s.stop_ramp_s = r.number("stop_ramp_s", s.stop_ramp_s, positive(60.0, "s"));
  s.stop_hold_s = r.number("stop_hold_s", s.stop_hold_s, non_negative(3600.0, "s"));
  r.finish();
  if (s.profile == SpindleProfileKind::kRamp) {
    if (s.ramp_end_s <= s.ramp_start_s) {
      config::fail(r.path_of("ramp_end_s"), "value " + std::to_string(s.ramp_end_s) +
                                                " must be after ramp_start_s (" +
                                                std::to_string(s.ramp_start_s) + " s)");
    }
    if (s.ramp_end_rpm <= 0.0) {
      config::fail(r.path_of("ramp_end_rpm"), "a ramp needs a speed > 0 rpm to end at");
    }
  }
  return s;
}

}  // namespace

double actual_rpm(const Scenario& s) {
  return s.spindle.actual_rpm > 0.0 ? s.spindle.actual_rpm : s.model.process.spindle_rpm;
}

Scenario scenario_from_json(const nlohmann::json& j) {
  ObjectReader r(j, "");
  Scenario s;
  s.name = r.string("name", s.name);
  s.description = r.string("description", s.description);
  s.model = model::model_config_from_json(r.raw("model"), "model");
  {
    auto rec = r.object("recording");
    s.sample_rate_hz = rec.number("sample_rate_hz", s.sample_rate_hz, closed(1000.0, 2e6, "Hz"));
    s.duration_s = rec.number("duration_s", s.duration_s, positive(3600.0, "s"));
    s.seed = static_cast<std::uint64_t>(rec.integer64("seed", 1, 0, INT64_MAX));
    rec.finish();
    if (s.duration_s * s.sample_rate_hz < 1.0) {
      config::fail("recording.duration_s", "value " + config::format_number(s.duration_s) +
                                               " s is shorter than one sample at " +
                                               config::format_number(s.sample_rate_hz) + " Hz");
    }
  }
  s.spindle = read_spindle(r.object("spindle"), s.duration_s);
  {
    auto n = r.object("noise");
    s.noise.enabled = n.boolean("enabled", s.noise.enabled);
    s.noise.sigma_N = triple(n, "sigma_N", s.noise.sigma_N, non_negative(100.0, "N"));
    n.finish();
  }
  {
    auto q = r.object("quantisation");
    s.quantisation.enabled = q.boolean("enabled", s.quantisation.enabled);
    s.quantisation.bits = q.integer("bits", s.quantisation.bits, 4, 32);
    s.quantisation.range_N = triple(q, "range_N", s.quantisation.range_N, positive(1e5, "N"));
    q.finish();
  }
  {
    auto d = r.object("drift");
    s.drift.enabled = d.boolean("enabled", s.drift.enabled);
    s.drift.rate_N_per_s =
        triple(d, "rate_N_per_s", s.drift.rate_N_per_s, closed(-100, 100, "N/s"));
    d.finish();
  }
  {
    auto h = r.object("hum");
    s.hum.enabled = h.boolean("enabled", s.hum.enabled);
    s.hum.frequency_hz = h.number("frequency_hz", s.hum.frequency_hz, positive(1000.0, "Hz"));
    s.hum.amplitude_N = triple(h, "amplitude_N", s.hum.amplitude_N, non_negative(100.0, "N"));
    h.finish();
  }
  {
    auto w = r.object("wear");
    const auto flutes = static_cast<std::size_t>(s.model.tool.flutes);
    s.wear.enabled = w.boolean("enabled", s.wear.enabled);
    s.wear.start_um = w.numbers("start_um", s.wear.start_um, non_negative(2000.0, "um"), 1, flutes);
    s.wear.end_um = w.numbers("end_um", s.wear.end_um, non_negative(2000.0, "um"), 1, flutes);
    w.finish();
    if (s.wear.start_um.size() != s.wear.end_um.size()) {
      config::fail("wear.end_um", "needs as many entries as wear.start_um (" +
                                      std::to_string(s.wear.start_um.size()) + ")");
    }
  }
  {
    auto c = r.object("runout_change");
    s.runout_change.enabled = c.boolean("enabled", s.runout_change.enabled);
    // A change the recording ends before would never show: refused when enabled (given or by
    // default). A disabled one's time is kept as it is, whatever the duration (the default
    // 0.25 s outlasts a 0.1 s recording, and to_json() writes it back).
    s.runout_change.time_s = c.number("time_s", s.runout_change.time_s, non_negative(1e6, "s"));
    if (s.runout_change.enabled && s.runout_change.time_s > s.duration_s) {
      config::fail(c.path_of("time_s"),
                   "value " + config::format_number(s.runout_change.time_s) +
                       " s is after the recording's end (recording.duration_s " +
                       config::format_number(s.duration_s) + " s): the change would not show");
    }
    const double radius_um = s.model.tool.diameter_mm * 500.0;
    s.runout_change.offset_um =
        c.number("offset_um", s.runout_change.offset_um, {0.0, 0.2 * radius_um, false, true, "um"});
    s.runout_change.angle_rad =
        c.number("angle_rad", s.runout_change.angle_rad, closed(-6.2832, 6.2832, "rad"));
    c.finish();
  }
  {
    auto d = r.object("coefficient_drift");
    s.coefficient_drift.enabled = d.boolean("enabled", s.coefficient_drift.enabled);
    s.coefficient_drift.end_factor =
        d.number("end_factor", s.coefficient_drift.end_factor, positive(10.0));
    d.finish();
  }
  s.axis_map = signal::axis_map_from_json(r.raw("axis_map"), "axis_map");
  r.finish();

  // The model applies the dynamometer resonance on its spindle-angle grid, whose rate is
  // rpm·steps/60: it must stay well above the natural frequencies.
  const auto& dyn = s.model.effects.dynamometer;
  if (dyn.enabled) {
    double slowest_rpm = actual_rpm(s);
    if (s.spindle.profile == SpindleProfileKind::kRamp) {
      slowest_rpm = std::min(slowest_rpm, s.spindle.ramp_end_rpm);
    }
    const double grid_hz = slowest_rpm * s.model.resolution.steps_per_rev / 60.0;
    for (double fn : dyn.natural_hz) {
      if (fn >= 0.45 * grid_hz) {
        config::fail("model.effects.dynamometer.natural_hz",
                     "value " + std::to_string(fn) +
                         " Hz must stay below 0.45 x the model's step rate (" +
                         std::to_string(0.45 * grid_hz) +
                         " Hz at the slowest spindle speed); raise model.resolution.steps_per_rev");
      }
    }
  }
  return s;
}

nlohmann::json to_json(const Scenario& s) {
  using nlohmann::json;
  return json{
      {"name", s.name},
      {"description", s.description},
      {"model", model::to_json(s.model)},
      {"recording",
       {{"sample_rate_hz", s.sample_rate_hz}, {"duration_s", s.duration_s}, {"seed", s.seed}}},
      {"spindle",
       {{"profile", profile_name(s.spindle.profile)},
        {"actual_rpm", s.spindle.actual_rpm},
        {"ramp_end_rpm", s.spindle.ramp_end_rpm},
        {"ramp_start_s", s.spindle.ramp_start_s},
        {"ramp_end_s", s.spindle.ramp_end_s},
        {"stop_s", s.spindle.stop_s},
        {"stop_ramp_s", s.spindle.stop_ramp_s},
        {"stop_hold_s", s.spindle.stop_hold_s}}},
      {"noise", {{"enabled", s.noise.enabled}, {"sigma_N", s.noise.sigma_N}}},
      {"quantisation",
       {{"enabled", s.quantisation.enabled},
        {"bits", s.quantisation.bits},
        {"range_N", s.quantisation.range_N}}},
      {"drift", {{"enabled", s.drift.enabled}, {"rate_N_per_s", s.drift.rate_N_per_s}}},
      {"hum",
       {{"enabled", s.hum.enabled},
        {"frequency_hz", s.hum.frequency_hz},
        {"amplitude_N", s.hum.amplitude_N}}},
      {"wear",
       {{"enabled", s.wear.enabled}, {"start_um", s.wear.start_um}, {"end_um", s.wear.end_um}}},
      {"runout_change",
       {{"enabled", s.runout_change.enabled},
        {"time_s", s.runout_change.time_s},
        {"offset_um", s.runout_change.offset_um},
        {"angle_rad", s.runout_change.angle_rad}}},
      {"coefficient_drift",
       {{"enabled", s.coefficient_drift.enabled}, {"end_factor", s.coefficient_drift.end_factor}}},
      {"axis_map", signal::to_json(s.axis_map)}};
}

}  // namespace millwatch::sim
