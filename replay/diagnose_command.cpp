#include "replay/diagnose_command.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/config/json_reader.hpp"
#include "core/diagnose/diagnosis.hpp"
#include "core/monitor/monitor_config.hpp"
#include "replay/command_exit.hpp"
#include "shell/column_map.hpp"
#include "shell/diagnosis_report.hpp"
#include "shell/json_file.hpp"
#include "shell/recording_source.hpp"

namespace millwatch::shell {
namespace {

namespace fs = std::filesystem;

struct DiagnoseCliOptions {
  std::string input;
  std::string config;
  std::string sidecar;
  std::string report;
  std::string start = "plain";
  std::string candidates;
  double band_hz = 0.0;
  double from_s = 0.0;
  double to_s = 0.0;
  int max_steps = 5;
  bool plots = true;
  bool progress = true;
};

/// The progress line on stderr when it is a terminal: the step, the candidate, the time.
class ProgressLine {
 public:
  explicit ProgressLine(bool enabled)
      : enabled_(enabled && isatty(STDERR_FILENO) != 0), start_(std::chrono::steady_clock::now()) {}
  void show(std::string_view what) {
    if (!enabled_) {
      return;
    }
    const double s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    std::fprintf(stderr, "\r  diagnose: %.*s  (%.1f s)\033[K", static_cast<int>(what.size()),
                 what.data(), s);
    std::fflush(stderr);
    shown_ = true;
  }
  void done() {
    if (shown_) {
      std::fprintf(stderr, "\r\033[K");
      std::fflush(stderr);
    }
  }

 private:
  bool enabled_;
  bool shown_ = false;
  std::chrono::steady_clock::time_point start_;
};

std::vector<std::string> split_names(const std::string& list) {
  std::vector<std::string> out;
  std::stringstream ss(list);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (!item.empty()) {
      out.push_back(item);
    }
  }
  return out;
}

int diagnose_one(const DiagnoseCliOptions& o) {
  const fs::path input = o.input;
  if (!fs::exists(input)) {
    throw std::runtime_error(input.string() + ": no such recording");
  }
  const RecordingFormat format = detect_recording_format(input);
  // --config: a monitor configuration (or {"monitor": ...}), optionally with "columns".
  nlohmann::json overrides = nlohmann::json::object();
  ColumnMap columns;
  if (!o.config.empty()) {
    overrides = read_json_file(o.config);
    auto take_columns = [&](nlohmann::json& object, const std::string& where) {
      if (object.is_object() && object.contains("columns")) {
        try {
          columns = column_map_from_json(object["columns"], where);
        } catch (const std::invalid_argument& e) {
          throw std::runtime_error(o.config + ": " + e.what());
        }
        object.erase("columns");
      }
    };
    take_columns(overrides, "columns");
    if (overrides.is_object() && overrides.contains("monitor")) {
      overrides = nlohmann::json(overrides["monitor"]);
      take_columns(overrides, "monitor.columns");
    }
  }
  fs::path sidecar = o.sidecar;
  if (sidecar.empty() && format != RecordingFormat::kLcmLog) {
    sidecar = input;
    sidecar.replace_extension(".json");
    if (!fs::exists(sidecar) && !o.config.empty()) {
      sidecar.clear();
    }
  }
  nlohmann::json base = overrides;
  std::string config_name = o.config.empty() ? "(defaults)" : o.config;
  if (!sidecar.empty()) {
    if (!fs::exists(sidecar)) {
      throw std::runtime_error(sidecar.string() +
                               ": sidecar not found (describe the cut with --sidecar or --config)");
    }
    try {
      base = monitor::monitor_json_from_sidecar(read_json_file(sidecar), overrides);
    } catch (const config::ConfigError& e) {
      throw std::runtime_error(sidecar.string() + ": " + e.what());
    }
    config_name = sidecar.string() + (o.config.empty() ? "" : " + " + o.config);
  }
  const double config_rate_hz =
      base.is_object() && base.contains("sample_rate_hz") && base["sample_rate_hz"].is_number()
          ? base["sample_rate_hz"].get<double>()
          : 0.0;
  RecordingOptions ro;
  ro.columns = columns;
  ro.config_rate_hz = config_rate_hz;
  std::int64_t bad = 0;
  ro.on_bad = [&](std::int64_t where, const std::string& problem) {
    if (++bad <= 20) {
      spdlog::warn("{}: {}: {}; skipped", input.string(), where, problem);
    }
  };
  auto source = open_recording(input, ro);
  spdlog::info("{}: {}", input.string(), source->description());
  if (source->sample_rate_hz() > 0.0 && (config_rate_hz <= 0.0 || source->rate_stated())) {
    base["sample_rate_hz"] = source->sample_rate_hz();
  }
  // The monitor's low-pass plays no part here (the diagnosis compares its own band): unless
  // configured, it is set where the monitor's checks against the tooth-passing frequency pass.
  const double rate_hz =
      base.is_object() && base.contains("sample_rate_hz") && base["sample_rate_hz"].is_number()
          ? base["sample_rate_hz"].get<double>()
          : 0.0;
  if (rate_hz > 0.0 && base.is_object() &&
      !(base.contains("filter") && base["filter"].is_object() &&
        base["filter"].contains("cutoff_hz"))) {
    base["filter"]["cutoff_hz"] = 0.4 * rate_hz;
  }
  monitor::MonitorConfig config;
  try {
    config = monitor::monitor_config_from_json(base);
  } catch (const config::ConfigError& e) {
    throw std::runtime_error(config_name + ": " + e.what());
  }

  // The record in the model frame, trimmed to [--from-s, --to-s).
  diagnose::CutRecord record;
  double rate = 0.0;
  std::int64_t index = 0;
  while (auto block = source->next(65536)) {
    if (rate <= 0.0) {
      rate = block->sample_rate_hz;
    }
    for (std::size_t i = 0; i < block->fx_N.size(); ++i, ++index) {
      const double t = static_cast<double>(index) / rate;
      if (t < o.from_s || (o.to_s > 0.0 && t >= o.to_s)) {
        continue;
      }
      const auto f = config.axis_map.to_model({block->fx_N[i], block->fy_N[i], block->fz_N[i]});
      record.force_N[0].push_back(f[0]);
      record.force_N[1].push_back(f[1]);
    }
  }
  if (rate <= 0.0 || record.force_N[0].empty()) {
    throw std::runtime_error(input.string() + ": no samples to diagnose" +
                             (o.from_s > 0.0 || o.to_s > 0.0 ? " within --from-s/--to-s" : ""));
  }
  record.sample_rate_hz = rate;
  if (bad > 0) {
    spdlog::warn("{}: {} bad {} skipped", input.string(), bad, source->record_unit());
  }

  model::ModelConfig start = config.model;
  if (o.start == "plain") {
    start = diagnose::plain_model(start);
  } else if (o.start != "configured") {
    throw std::runtime_error("--start: '" + o.start + "' is neither 'plain' nor 'configured'");
  }
  diagnose::DiagnoseOptions options;
  options.band_hz = o.band_hz;
  options.max_steps = o.max_steps;
  options.candidates = split_names(o.candidates);
  ProgressLine progress(o.progress);
  options.progress = [&](std::string_view line) { progress.show(line); };
  diagnose::Diagnosis d;
  try {
    d = diagnose::diagnose(record, start, options);
  } catch (const config::ConfigError& e) {
    progress.done();
    throw std::runtime_error(config_name + ": " + e.what());
  } catch (const std::invalid_argument& e) {
    progress.done();
    throw std::runtime_error(input.string() + ": " + e.what());
  }
  progress.done();
  if (!d.ok) {
    throw std::runtime_error(input.string() + ": " + d.message);
  }
  const ReportFiles files = write_diagnosis_report(d, o.report, input.filename().string(), o.plots);
  if (!files.plot_problem.empty() && o.plots) {
    spdlog::warn("plots left out: {}", files.plot_problem);
  }
  std::printf("%s\n", d.verdict.c_str());
  std::printf("  start: residual %.4f, %.4f N (noise floor %.4f, %.4f N)\n",
              d.initial.residual_rms_N[0], d.initial.residual_rms_N[1], d.noise_floor_N[0],
              d.noise_floor_N[1]);
  for (const auto& s : d.steps) {
    std::printf("  + %-22s residual %.4f, %.4f N  ΔBIC %.1f (over %s by %.1f)\n", s.added.c_str(),
                s.residual_rms_N[0], s.residual_rms_N[1], s.gain,
                s.runner_up.empty() ? "-" : s.runner_up.c_str(), s.margin_over_runner_up);
  }
  std::printf("  report: %s\n", (fs::path(o.report) / "report.md").string().c_str());
  return 0;
}

}  // namespace

void add_diagnose_command(CLI::App& app) {
  auto o = std::make_shared<DiagnoseCliOptions>();
  CLI::App* cmd = app.add_subcommand(
      "diagnose",
      "Where model and measurement disagree: name the missing effect, add it, show the gap shrink");
  cmd->add_option("cut", o->input, "Recorded cut (any format the replay reads)")->required();
  cmd->add_option("--config", o->config, "Monitor configuration JSON (the cut as commanded)");
  cmd->add_option("--sidecar", o->sidecar, "The recording's sidecar (default: CUT.json if there)");
  cmd->add_option("--report", o->report, "Folder for report.md, report.html, report.json, plots")
      ->required();
  cmd->add_option("--start", o->start,
                  "Starting model: 'plain' (no effects, default) or 'configured'");
  cmd->add_option("--band", o->band_hz, "Upper end of the compared band, Hz (default 0.4·fs)");
  cmd->add_option("--from-s", o->from_s, "Diagnose from this time on (s; skip the entry)");
  cmd->add_option("--to-s", o->to_s, "Diagnose up to this time (s)");
  cmd->add_option("--candidates", o->candidates, "Comma-separated candidates (default: all)");
  cmd->add_option("--max-steps", o->max_steps, "Effects added at most (default 5)");
  cmd->add_flag("!--no-plots", o->plots, "Do not draw the plots");
  cmd->add_flag("!--no-progress", o->progress, "No progress line on a terminal");
  cmd->callback([o]() { run_subcommand([&]() { return diagnose_one(*o); }); });
}

}  // namespace millwatch::shell
