#include "core/monitor/monitor_config.hpp"

#include <algorithm>
#include <cmath>

#include "core/config/json_reader.hpp"
#include "core/model/parameter_map.hpp"
#include "core/monitor/revolution_record.hpp"

namespace millwatch::monitor {
namespace {

using config::ObjectReader;

std::string join(const std::string& path, const char* key) {
  return path.empty() ? std::string(key) : path + "." + key;
}

}  // namespace

MonitorConfig monitor_config_from_json(const nlohmann::json& j, const std::string& path,
                                       std::initializer_list<std::string_view> caller_keys) {
  ObjectReader r(j, path);
  MonitorConfig c;
  (void)r.string("name", "");  // for the reader of the file
  (void)r.string("description", "");
  c.model = model::model_config_from_json(r.raw("model"), join(path, "model"));
  c.sample_rate_hz = r.number("sample_rate_hz", c.sample_rate_hz,
                              config::closed(kMinSampleRateHz, kMaxSampleRateHz, "Hz"));
  c.axis_map = signal::axis_map_from_json(r.raw("axis_map"), join(path, "axis_map"));
  {
    const std::vector<double> fallback(c.saturation_N.begin(), c.saturation_N.end());
    const auto v =
        r.numbers("saturation_N", {1e300, 1e300, 1e300}, config::positive(1e300, "N"), 3, 3);
    for (std::size_t a = 0; a < 3; ++a) {
      c.saturation_N[a] = v[a] >= 1e300 ? fallback[a] : v[a];
    }
  }
  {
    auto f = r.object("filter");
    c.filter_cutoff_hz = f.number("cutoff_hz", c.filter_cutoff_hz, config::positive(1e6, "Hz"));
    c.filter_order = f.integer("order", c.filter_order, 1, 8);
    c.filter_zero_phase = f.choice("mode", c.filter_zero_phase ? "zero_phase" : "causal",
                                   {"causal", "zero_phase"}) == "zero_phase";
    f.finish();
  }
  c.spindle = signal::spindle_tracker_config_from_json(r.raw("spindle"), join(path, "spindle"));
  {
    auto t = r.object("tooth_periods");
    c.alpha_window_revolutions =
        t.integer("window_revolutions", c.alpha_window_revolutions, 1, 10000);
    c.search_fraction_of_pitch = t.number("search_fraction_of_pitch", c.search_fraction_of_pitch,
                                          {0.0, 0.5, true, true, ""});
    t.finish();
  }
  {
    auto s = r.object("sync_average");
    c.sync_bins = s.integer("bins", c.sync_bins, 32, 4096);
    c.sync_window_revolutions =
        s.integer("window_revolutions", c.sync_window_revolutions, 2, 10000);
    c.template_revolutions = s.integer("template_revolutions", c.template_revolutions, 1, 10000);
    s.finish();
  }
  {
    auto l = r.object("lockstep");
    c.lockstep = l.boolean("enabled", c.lockstep);
    c.residual_sectors = l.integer("sectors", c.residual_sectors, 1, kMaxSectors);
    l.finish();
  }
  {
    auto id = r.object("identification");
    auto& o = c.identification;
    o.enabled = id.boolean("enabled", o.enabled);
    const nlohmann::json& extra = id.raw("extra_parameters");
    const std::string field = join(path, "identification.extra_parameters");
    if (!extra.is_null()) {
      if (!extra.is_array()) {
        config::fail(field,
                     "expected an array of parameter names, got " + config::describe_json(extra));
      }
      for (const auto& e : extra) {
        if (!e.is_string()) {
          config::fail(field, "expected parameter names, got " + config::describe_json(e));
        }
        o.extra_parameters.push_back(e.get<std::string>());
      }
    }
    o.max_unexplained = id.number("max_unexplained", o.max_unexplained, config::positive(1.0));
    o.runout_prior_um =
        id.number("runout_prior_um", o.runout_prior_um, config::non_negative(1000.0, "um"));
    o.cpu_budget = id.number("cpu_budget", o.cpu_budget, config::positive(1.0));
    id.finish();
    model::ParameterMap map;
    try {
      map = model::make_parameter_map(c.model, o.extra_parameters);
    } catch (const std::invalid_argument& e) {
      config::fail(field, e.what());
    }
    for (const auto& p : map.parameters) {
      if (p.effect != "force_law" && !model::effect_enabled(c.model, p.effect)) {
        config::fail(field, p.name + " belongs to effects." + p.effect +
                                ", which is off in the model: nothing to fit");
      }
    }
  }
  c.alerts = alert_config_from_json(r.raw("alerts"), join(path, "alerts"));
  for (const std::string_view key : caller_keys) {
    (void)r.raw(key);  // the caller's: allowed, and listed as allowed
  }
  r.finish();
  const nlohmann::json* filter = j.is_object() && j.contains("filter") ? &j["filter"] : nullptr;
  c.filter_cutoff_given = filter != nullptr && filter->is_object() && filter->contains("cutoff_hz");
  choose_cutoff_for_cut(c);
  validate(c, path);
  return c;
}

double zero_phase_design_cutoff_hz(double cutoff_hz, int order) {
  return cutoff_hz * std::pow(std::sqrt(2.0) - 1.0, -1.0 / (2.0 * order));
}

double cutoff_for_cut_hz(double default_hz, double sample_rate_hz, double tooth_hz, int order) {
  const double low_hz = 1.5 * tooth_hz;
  const double high_hz = 0.45 * sample_rate_hz;
  if (default_hz >= low_hz && default_hz < high_hz) {
    return default_hz;
  }
  // 0.4× the rate, and its zero-phase design below 0.45× too (order 4 raises it by 1.117×, to
  // 0.447×; orders 1–3 further).
  const double top_hz = std::min(0.4 * sample_rate_hz,
                                 0.449 * sample_rate_hz / zero_phase_design_cutoff_hz(1.0, order));
  if (top_hz < low_hz) {
    return default_hz;  // no cut-off can serve: validate() says why
  }
  return std::clamp(default_hz, std::min(4.0 * tooth_hz, top_hz), top_hz);
}

void choose_cutoff_for_cut(MonitorConfig& c) {
  using config::format_number;
  if (c.filter_cutoff_given) {
    return;
  }
  const double default_hz = MonitorConfig{}.filter_cutoff_hz;
  const double tooth_hz = model::tooth_passing_hz(c.model);
  const double chosen_hz =
      cutoff_for_cut_hz(default_hz, c.sample_rate_hz, tooth_hz, c.filter_order);
  c.filter_cutoff_hz = chosen_hz;
  c.filter_cutoff_note.clear();
  if (chosen_hz == default_hz) {
    return;
  }
  const std::string why =
      default_hz < 1.5 * tooth_hz
          ? "not pass 1.5 x the tooth-passing frequency (" + format_number(tooth_hz) +
                " Hz: model.process.spindle_rpm " + format_number(c.model.process.spindle_rpm) +
                ", " + std::to_string(c.model.tool.flutes) + " flutes)"
          : "not stay below 0.45 x the sample rate (" + format_number(c.sample_rate_hz) + " Hz)";
  const std::string taken = chosen_hz == 4.0 * tooth_hz
                                ? "4 x the tooth-passing frequency"
                                : "the most the sample rate allows (" +
                                      format_number(chosen_hz / c.sample_rate_hz) + " x it)";
  c.filter_cutoff_note = "filter.cutoff_hz not given: the default " + format_number(default_hz) +
                         " Hz would " + why + "; taking " + format_number(chosen_hz) + " Hz, " +
                         taken + " (set filter.cutoff_hz to choose)";
}

void validate(const MonitorConfig& c, const std::string& path) {
  using config::format_number;
  // Said with where a value that is not in the file comes from: a default that the file's
  // sample rate or speed does not suit is not the user's typing.
  const auto set_or_default = [](double value, double fallback) {
    return value == fallback ? " (the default)" : "";
  };
  const MonitorConfig defaults;
  if (c.filter_cutoff_hz >= 0.45 * c.sample_rate_hz) {
    config::fail(join(path, "filter.cutoff_hz"),
                 "value " + format_number(c.filter_cutoff_hz) + " Hz" +
                     set_or_default(c.filter_cutoff_hz, defaults.filter_cutoff_hz) +
                     " must stay below 0.45 x the sample rate (" +
                     format_number(0.45 * c.sample_rate_hz) + " Hz)");
  }
  const double tooth_hz = model::tooth_passing_hz(c.model);
  if (c.filter_cutoff_hz < 1.5 * tooth_hz) {
    config::fail(join(path, "filter.cutoff_hz"),
                 "value " + format_number(c.filter_cutoff_hz) + " Hz" +
                     set_or_default(c.filter_cutoff_hz, defaults.filter_cutoff_hz) +
                     " must pass at least 1.5 x the tooth-passing frequency (" +
                     format_number(1.5 * tooth_hz) + " Hz at model.process.spindle_rpm " +
                     format_number(c.model.process.spindle_rpm) + ")");
  }
  // The spindle tracker's window as the pipeline sets it up (signal::validate() checks it
  // there too, naming the tracker's own fields).
  signal::SpindleTrackerConfig tracker = c.spindle;
  tracker.commanded_rpm = c.model.process.spindle_rpm;
  if (const std::string problem = signal::window_problem(tracker, "model.process.spindle_rpm");
      !problem.empty()) {
    config::fail(join(path, "spindle.window_s"), problem);
  }
  if (c.model.tool.flutes > kMaxFlutes) {
    config::fail(join(path, "model.tool.flutes"), "at most " + std::to_string(kMaxFlutes));
  }
}

nlohmann::json monitor_json_from_sidecar(const nlohmann::json& sidecar,
                                         const nlohmann::json& overrides) {
  if (!sidecar.is_object()) {
    config::fail("(sidecar)", "expected an object, got " + config::describe_json(sidecar));
  }
  nlohmann::json out = nlohmann::json::object();
  if (sidecar.contains("model")) {
    out["model"] = sidecar["model"];
  } else {
    for (const char* key : {"tool", "process", "material"}) {
      if (!sidecar.contains(key)) {
        config::fail(key, "missing in the sidecar (needed to model the cut)");
      }
      out["model"][key] = sidecar[key];
    }
  }
  if (!sidecar.contains("sample_rate_hz")) {
    config::fail("sample_rate_hz", "missing in the sidecar");
  }
  out["sample_rate_hz"] = sidecar["sample_rate_hz"];
  if (sidecar.contains("force_sign_convention") && sidecar["force_sign_convention"].is_object() &&
      sidecar["force_sign_convention"].contains("axis_map")) {
    out["axis_map"] = sidecar["force_sign_convention"]["axis_map"];
  }
  out.merge_patch(overrides);
  return out;
}

nlohmann::json to_json(const MonitorConfig& c) {
  nlohmann::json sat = nlohmann::json::array();
  for (double s : c.saturation_N) {
    sat.push_back(std::isfinite(s) ? s : 1e300);
  }
  return {{"model", model::to_json(c.model)},
          {"sample_rate_hz", c.sample_rate_hz},
          {"axis_map", signal::to_json(c.axis_map)},
          {"saturation_N", sat},
          {"filter",
           {{"cutoff_hz", c.filter_cutoff_hz},
            {"order", c.filter_order},
            {"mode", c.filter_zero_phase ? "zero_phase" : "causal"}}},
          {"spindle", signal::to_json(c.spindle)},
          {"tooth_periods",
           {{"window_revolutions", c.alpha_window_revolutions},
            {"search_fraction_of_pitch", c.search_fraction_of_pitch}}},
          {"sync_average",
           {{"bins", c.sync_bins},
            {"window_revolutions", c.sync_window_revolutions},
            {"template_revolutions", c.template_revolutions}}},
          {"lockstep", {{"enabled", c.lockstep}, {"sectors", c.residual_sectors}}},
          {"identification",
           {{"enabled", c.identification.enabled},
            {"extra_parameters", c.identification.extra_parameters},
            {"max_unexplained", c.identification.max_unexplained},
            {"runout_prior_um", c.identification.runout_prior_um},
            {"cpu_budget", c.identification.cpu_budget}}},
          {"alerts", to_json(c.alerts)}};
}

}  // namespace millwatch::monitor
