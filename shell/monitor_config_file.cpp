#include "shell/monitor_config_file.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <stdexcept>

#include "core/config/json_reader.hpp"
#include "core/model/model_config.hpp"
#include "shell/json_file.hpp"
#include "shell/material_preset.hpp"
#include "shell/recording_source.hpp"

namespace millwatch::shell {

namespace fs = std::filesystem;

ConfigFile read_config_file(const std::string& path) {
  ConfigFile c;
  if (path.empty()) {
    return c;
  }
  if (!fs::exists(path)) {
    throw std::runtime_error(path + ": configuration not found (--config)");
  }
  nlohmann::json j = read_json_file(path);
  // A recording's sidecar (millwatch simulate's, a CSV's) given where a configuration goes: its
  // "columns" list the CSV's header, which a configuration's column map is not.
  if (j.is_object() && j.contains("force_sign_convention") && j.contains("sample_rate_hz")) {
    throw std::runtime_error(path +
                             ": a recording's sidecar, not a monitor configuration: give it with "
                             "--sidecar (--config takes a configuration, e.g. config/*.json)");
  }
  resolve_material_presets(j, path);  // "model": {"material": "preset.json"}
  auto take_columns = [&](nlohmann::json& object, const std::string& where) {
    if (object.is_object() && object.contains("columns")) {
      try {
        c.columns = column_map_from_json(object["columns"], where);
      } catch (const std::invalid_argument& e) {
        throw std::runtime_error(path + ": " + e.what());
      }
      object.erase("columns");
    }
  };
  take_columns(j, "columns");
  if (j.is_object() && j.contains("monitor")) {
    j = nlohmann::json(j["monitor"]);
    take_columns(j, "monitor.columns");
  }
  c.monitor = j;
  return c;
}

double LoadedMonitorConfig::config_rate_hz() const {
  return json.is_object() && json.contains("sample_rate_hz") && json["sample_rate_hz"].is_number()
             ? json["sample_rate_hz"].get<double>()
             : 0.0;
}

void LoadedMonitorConfig::warn_model_note(const std::filesystem::path& input) const {
  if (!model_note.empty()) {
    spdlog::warn("{}: {}", input.string(), model_note);
  }
}

LoadedMonitorConfig load_monitor_config(const MonitorConfigSources& sources,
                                        const ConfigFile& file) {
  LoadedMonitorConfig out;
  const std::string where = sources.where.empty() ? "" : " (" + sources.where + ")";
  out.columns = file.columns.value_or(ColumnMap{});
  if (!sources.columns.empty()) {
    try {
      out.columns = parse_column_map(sources.columns);  // the command line beats the file
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(std::string("--") + e.what());
    }
  }
  out.name = sources.config.empty() ? "(defaults)" : sources.config;
  fs::path sidecar = sources.sidecar;
  if (sidecar.empty() && detect_recording_format(sources.input) != RecordingFormat::kLcmLog) {
    sidecar = sources.input;
    sidecar.replace_extension(".json");
    // `replay cut.csv --json > cut.json`: the shell empties the default sidecar before replay
    // reads it.
    const bool emptied = fs::is_regular_file(sidecar) && fs::file_size(sidecar) == 0;
    if (!fs::exists(sidecar) && !sources.config.empty()) {
      sidecar.clear();  // no sidecar beside the recording: --config describes the cut alone
    } else if (emptied && !sources.config.empty()) {
      spdlog::warn("{}: empty, left out (--config describes the cut)", sidecar.string());
      sidecar.clear();
    } else if (emptied) {
      throw std::runtime_error(sidecar.string() + ": empty, and read as " +
                               sources.input.filename().string() +
                               "'s sidecar (the default, beside it); was it the target of a "
                               "--json redirection? Write the summary with --summary FILE, or "
                               "describe the cut with --sidecar or --config");
    }
  }
  out.json = file.monitor;
  if (sidecar.empty()) {
    // Nothing describes the cut: the built-in model stands in for it, which the commands that
    // measure say (model_note): a cut of another tool or speed is then searched for at the
    // built-in speed and missed. (publish hands the samples on and needs no model.)
    if (!out.json.is_object() || !out.json.contains("model")) {
      const model::ModelConfig assumed;
      const bool log = detect_recording_format(sources.input) == RecordingFormat::kLcmLog;
      out.model_note = fmt::format(
          "nothing describes the cut ({}; {}): the built-in model is assumed, a {:g} mm "
          "{}-flute tool at {:g} rpm; give the cut's \"model\" (tool, process) in --config "
          "(config/*.json) or its sidecar with --sidecar",
          log ? "an LCM log holds the samples alone" : "no sidecar beside the recording",
          sources.config.empty() ? "no --config" : sources.config + " has no \"model\"",
          assumed.tool.diameter_mm, assumed.tool.flutes, assumed.process.spindle_rpm);
    }
    return out;
  }
  if (!fs::exists(sidecar)) {
    throw std::runtime_error(sidecar.string() + ": sidecar not found" + where +
                             " (describe the cut with --sidecar or --config)");
  }
  const nlohmann::json side = read_json_file(sidecar);
  try {
    out.json = monitor::monitor_json_from_sidecar(side, file.monitor);
    const nlohmann::json own = monitor::monitor_json_from_sidecar(side);
    const auto p = own.contains("model") && own["model"].is_object()
                       ? own["model"].value("process", nlohmann::json::object())
                       : nlohmann::json::object();
    if (p.is_object() && p.contains("feed_per_tooth_um") && p["feed_per_tooth_um"].is_number()) {
      out.sidecar_feed_per_tooth_um = p["feed_per_tooth_um"].get<double>();
    }
  } catch (const config::ConfigError& e) {
    throw std::runtime_error(sidecar.string() + ": " + e.what());
  }
  out.sidecar = sidecar;
  out.name = sidecar.string() + (sources.config.empty() ? "" : " + " + sources.config);
  return out;
}

void take_recording_rate(LoadedMonitorConfig& config, const RecordingSource& source,
                         const std::string& input) {
  const double source_hz = source.sample_rate_hz();
  const double config_hz = config.config_rate_hz();
  if (!(source_hz > 0.0) || !config.json.is_object()) {
    return;
  }
  if (config.json.contains("sample_rate_hz") && !(config_hz > 0.0)) {
    return;  // not a rate: parse_monitor_config() names what is wrong with it
  }
  if (config_hz > 0.0 && source.rate_stated() &&
      std::fabs(source_hz - config_hz) > 1e-3 * config_hz) {
    config.rate_note = fmt::format(
        "the recording's rate is {:.6g} Hz (stated, or its time column's steps), {} says "
        "{:.6g} Hz; using the recording's",
        source_hz, config.name, config_hz);
    spdlog::warn("{}: {}", input, config.rate_note);
  }
  if (config_hz <= 0.0 || source.rate_stated()) {
    // Named as the recording's: the configuration's reader would name the configuration.
    if (source_hz < monitor::kMinSampleRateHz || source_hz > monitor::kMaxSampleRateHz) {
      throw std::runtime_error(fmt::format(
          "{}: the recording's rate is {:.6g} Hz (stated, or its time column's steps): outside "
          "the {:g} Hz – {:g} MHz the monitor takes (a time column in other units: scale it, "
          "e.g. --columns t=time_ms*0.001,...)",
          input, source_hz, monitor::kMinSampleRateHz, monitor::kMaxSampleRateHz / 1e6));
    }
    config.json["sample_rate_hz"] = source_hz;
  }
}

double configured_rate_hz(const LoadedMonitorConfig& config) {
  const double rate_hz = config.config_rate_hz();
  if (config.json.is_object() && config.json.contains("sample_rate_hz") && !(rate_hz > 0.0)) {
    (void)parse_monitor_config(config);  // names the field and its value
  }
  return rate_hz;
}

void take_option_feed(LoadedMonitorConfig& config, double feed_um, const std::string& cut) {
  config.json["model"]["process"]["feed_per_tooth_um"] = feed_um;
  const std::string field = "model.process.feed_per_tooth_um";
  try {
    (void)model::model_config_from_json(config.json["model"], "model");
  } catch (const config::ConfigError& e) {
    if (e.path() == field) {
      // "model.process.feed_per_tooth_um: value ..." said of the option.
      throw std::runtime_error("--feeds-um: " + cut + ": " +
                               std::string(e.what()).substr(field.size() + 2) +
                               " of the cut's tool");
    }
  }
}

monitor::MonitorConfig parse_monitor_config(const LoadedMonitorConfig& config) {
  try {
    // "columns" was taken by read_config_file() (the recording's column map).
    monitor::MonitorConfig c = monitor::monitor_config_from_json(config.json, "", {"columns"});
    if (!c.filter_cutoff_note.empty()) {
      spdlog::info("{}: {}", config.name, c.filter_cutoff_note);
    }
    return c;
  } catch (const config::ConfigError& e) {
    throw std::runtime_error(config.name + ": " + e.what());
  }
}

}  // namespace millwatch::shell
