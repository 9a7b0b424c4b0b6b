#pragma once
// A recorded cut's monitor configuration as the offline commands (replay, calibrate, diagnose)
// build it: the cut's sidecar (CUT.json beside the recording, or --sidecar) under --config's
// overrides, or --config alone; --config may be a daemon configuration (its "monitor" is
// taken), its material presets are resolved (shell/material_preset.hpp) and its column map
// ("columns" or "monitor.columns", beaten by --columns) is the shell's, kept apart. The
// recording's own rate then beats the configuration's (said so when they differ).

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "core/monitor/monitor_config.hpp"
#include "shell/column_map.hpp"

namespace millwatch::shell {

class RecordingSource;

/// --config's file: its monitor configuration (presets resolved, without "columns") and its
/// column map.
struct ConfigFile {
  nlohmann::json monitor = nlohmann::json::object();
  std::optional<ColumnMap> columns;
};

/// Reads --config ("" gives an empty one).
/// @throws std::runtime_error "PATH: ..." for a file that is missing or cannot be read
ConfigFile read_config_file(const std::string& path);

/// Where a cut's configuration comes from.
struct MonitorConfigSources {
  std::filesystem::path input;    ///< the recording
  std::string config;             ///< --config ("": none)
  std::filesystem::path sidecar;  ///< --sidecar ("": CUT.json beside the recording, if there)
  std::string columns;            ///< --columns ("": the configuration's, else the default)
  std::string where;              ///< e.g. "cut 2 of 3", added to the messages ("": none)
};

/// A cut's configuration before the recording is opened.
struct LoadedMonitorConfig {
  nlohmann::json json = nlohmann::json::object();  ///< the sidecar under the overrides
  ColumnMap columns;
  std::string name;               ///< for messages: "SIDECAR + CONFIG", "CONFIG" or "(defaults)"
  std::filesystem::path sidecar;  ///< the sidecar read ("": none)
  std::optional<double> sidecar_feed_per_tooth_um;  ///< the feed the sidecar itself states
  /// take_recording_rate()'s word when the recording's rate overrode the one configured ("":
  /// none), for the summary as well as the log.
  std::string rate_note;
  /// Where neither a sidecar nor the configuration describes the cut (no "model"): that the
  /// built-in model is assumed, and which ("": the cut is described), for the commands that
  /// measure to say (replay: the log and the summary).
  std::string model_note;
  /// sample_rate_hz in json (0: none).
  [[nodiscard]] double config_rate_hz() const;
  /// Warns model_note in the log, naming `input`, where there is one.
  void warn_model_note(const std::filesystem::path& input) const;
};

/// The rate the configuration states (0: none). @throws std::runtime_error naming the file,
/// the field and its value when it states one that is no rate ("fifty", 0, null): a text
/// without a time column would otherwise be said to have "no sample rate".
double configured_rate_hz(const LoadedMonitorConfig& config);

/// Loads a cut's configuration. `file` is --config already read (read_config_file), so that
/// several cuts read it once.
/// @throws std::runtime_error naming the file and the problem (a sidecar that is missing,
///         unreadable or invalid, a bad column map)
LoadedMonitorConfig load_monitor_config(const MonitorConfigSources& sources,
                                        const ConfigFile& file);

/// The recording's rate into the configuration: a rate the recording states beats the
/// configuration's (a warning when they differ); a rate it assumes fills a gap.
/// @throws std::runtime_error naming the recording when the rate it gives is outside what the
///         monitor takes (a time column in other units)
void take_recording_rate(LoadedMonitorConfig& config, const RecordingSource& source,
                         const std::string& input);

/// A feed per tooth given on the command line (--feeds-um) into the configuration, checked
/// against the cut's tool there: a feed the model cannot take is the option's error (the
/// model's reader would blame the configuration file). `cut` names the cut ("cu.csv (cut 1 of
/// 2)"). Other problems of the configuration are left to parse_monitor_config().
/// @throws std::runtime_error "--feeds-um: CUT: ..."
void take_option_feed(LoadedMonitorConfig& config, double feed_um, const std::string& cut);

/// The monitor configuration. @throws std::runtime_error "NAME: ..." naming the field
monitor::MonitorConfig parse_monitor_config(const LoadedMonitorConfig& config);

}  // namespace millwatch::shell
