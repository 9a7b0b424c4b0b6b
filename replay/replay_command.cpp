#include "replay/replay_command.hpp"

#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <utility>

#include "core/config/json_reader.hpp"
#include "core/monitor/monitor_config.hpp"
#include "msgs/lcm_convert.hpp"
#include "replay/command_exit.hpp"
#include "shell/csv_cut_reader.hpp"
#include "shell/json_file.hpp"
#include "shell/lcm_log_reader.hpp"
#include "shell/monitor_run.hpp"
#include "shell/output_file.hpp"

namespace millwatch::shell {
namespace {

namespace fs = std::filesystem;

std::atomic<bool> g_stop{false};
extern "C" void on_stop(int /*signal*/) {
  g_stop = true;
}

struct ReplayOptions {
  std::string input;
  std::string sidecar;
  std::string config;
  std::string summary;
  std::string publish_url;
  std::string raw_channel = "MILLWATCH_FORCE_RAW";
  double speed = 0.0;  // 0: as fast as possible
  bool realtime = false;
  bool publish_raw = false;
  bool zero_phase = false;
  int block_samples = 1000;
};

bool is_lcm_log(const fs::path& p) {
  const std::string ext = p.extension().string();
  return ext == ".lcmlog" || ext == ".log" || ext == ".lcm";
}

/// The monitor configuration: the sidecar's cut under --config's overrides; a daemon config's
/// "monitor" section is accepted as --config too.
monitor::MonitorConfig build_config(const ReplayOptions& o, const fs::path& input,
                                    double log_sample_rate_hz) {
  nlohmann::json overrides = nlohmann::json::object();
  std::string config_name = "(defaults)";
  if (!o.config.empty()) {
    overrides = read_json_file(o.config);
    if (overrides.is_object() && overrides.contains("monitor")) {
      overrides = overrides["monitor"];
    }
    config_name = o.config;
  }
  fs::path sidecar = o.sidecar;
  if (sidecar.empty() && !is_lcm_log(input)) {
    sidecar = input;
    sidecar.replace_extension(".json");
    if (!fs::exists(sidecar) && !o.config.empty()) {
      sidecar.clear();  // no sidecar beside the CSV: --config describes the cut alone
    }
  }
  nlohmann::json base;
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
  } else {
    base = overrides;
    if (!base.contains("sample_rate_hz") && log_sample_rate_hz > 0.0) {
      base["sample_rate_hz"] = log_sample_rate_hz;
    }
  }
  try {
    return monitor::monitor_config_from_json(base);
  } catch (const config::ConfigError& e) {
    throw std::runtime_error(config_name + ": " + e.what());
  }
}

int run_replay(const ReplayOptions& o) {
  const fs::path input = o.input;
  const bool lcm_log = is_lcm_log(input);
  std::int64_t bad_lines = 0;
  auto warn_line = [&](std::int64_t where, const std::string& problem) {
    ++bad_lines;
    if (bad_lines <= 20) {
      spdlog::warn("{}:{}: {}; skipped", input.string(), where, problem);
    } else if (bad_lines == 21) {
      spdlog::warn("{}: more bad {} follow; counted in the summary", input.string(),
                   lcm_log ? "events" : "lines");
    }
  };

  std::unique_ptr<LcmLogReader> log;
  std::optional<monitor::SampleBlock> first_block;  // read to learn the log's sample rate
  double log_rate = 0.0;
  if (lcm_log) {
    log = std::make_unique<LcmLogReader>(input, o.raw_channel, warn_line);
    first_block = log->next();
    log_rate = log->first_sample_rate_hz();
  }
  monitor::MonitorConfig config = build_config(o, input, log_rate);
  if (o.zero_phase) {
    config.filter_zero_phase = true;
  }
  std::unique_ptr<CsvCutReader> csv;
  if (!lcm_log) {
    csv = std::make_unique<CsvCutReader>(input, config.sample_rate_hz, warn_line);
  }

  std::unique_ptr<lcm::LCM> lcm;
  if (!o.publish_url.empty()) {
    lcm = std::make_unique<lcm::LCM>(o.publish_url);
    if (!lcm->good()) {
      throw std::runtime_error("cannot open LCM at " + o.publish_url);
    }
  }
  MonitorRun::Options run_options;
  run_options.source_name = input.string();
  run_options.lcm = lcm.get();  // none: the summary and the log only
  MonitorRun run(config, run_options);

  const double speed = o.realtime ? 1.0 : o.speed;
  const auto start = std::chrono::steady_clock::now();
  std::int64_t first_utime = 0;
  bool have_first = false;
  g_stop = false;
  std::signal(SIGINT, on_stop);
  std::signal(SIGTERM, on_stop);
  auto next_block = [&]() -> std::optional<monitor::SampleBlock> {
    if (first_block) {
      return std::exchange(first_block, std::nullopt);
    }
    if (lcm_log) {
      return log->next();
    }
    const monitor::SampleBlock b = csv->next(static_cast<std::size_t>(o.block_samples));
    return b.fx_N.empty() ? std::nullopt : std::optional(b);
  };
  while (!g_stop) {
    const std::optional<monitor::SampleBlock> next = next_block();
    if (!next) {
      break;
    }
    const monitor::SampleBlock& block = *next;
    if (!have_first) {
      first_utime = block.utime_us;
      have_first = true;
    }
    if (speed > 0.0) {  // pace by the blocks' own time
      const auto due = start + std::chrono::microseconds(static_cast<std::int64_t>(
                                   static_cast<double>(block.utime_us - first_utime) / speed));
      std::this_thread::sleep_until(due);
    }
    if (o.publish_raw && lcm) {
      const force_block_t raw = messaging::to_message(block);
      lcm->publish(o.raw_channel, &raw);
    }
    run.process(block);
  }
  run.finish();
  if (g_stop) {
    spdlog::warn("interrupted: the summary covers the samples replayed so far");
  }
  run.drain();
  nlohmann::json j = run.summary();
  j["input"] = input.string();
  j["filter"] = config.filter_zero_phase ? "zero_phase" : "causal";
  j["bad_lines"] = lcm_log ? log->bad_events() : csv->bad_lines();
  if (!o.summary.empty()) {
    write_text_file(o.summary, j.dump(2) + "\n");
  }
  std::printf("%s\n", j.dump(2).c_str());
  return 0;
}

}  // namespace

void add_replay_command(CLI::App& app) {
  auto o = std::make_shared<ReplayOptions>();
  CLI::App* cmd = app.add_subcommand(
      "replay", "Replay a recorded cut (CSV + JSON sidecar, or an LCM log) through the monitor");
  cmd->add_option("input", o->input,
                  "Recorded cut: CUT.csv (sidecar CUT.json beside it) or LOG.lcmlog")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--sidecar", o->sidecar, "JSON describing the cut (default: beside the CSV)");
  cmd->add_option(
      "--config", o->config,
      "Monitor configuration JSON (or a daemon configuration), merged over the sidecar");
  cmd->add_option("--summary", o->summary, "Also write the summary JSON to this file");
  cmd->add_option("--speed", o->speed, "Pace: k times real time (default: as fast as possible)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--realtime", o->realtime, "Pace at real time (--speed 1)");
  cmd->add_option("--publish", o->publish_url,
                  "Publish the results on LCM at this URL (e.g. udpm://239.255.76.67:7667?ttl=0)");
  cmd->add_flag("--publish-raw", o->publish_raw, "Also publish the raw sample blocks");
  cmd->add_flag("--zero-phase", o->zero_phase,
                "Filter forwards and backwards (no phase, no delay; same -3 dB cut-off) instead "
                "of causally (= \"filter\": {\"mode\": \"zero_phase\"} in --config)");
  cmd->add_option("--channel", o->raw_channel, "LCM channel of the raw samples in a log");
  cmd->add_option("--block", o->block_samples, "CSV samples per block")
      ->check(CLI::Range(1, 65536));
  cmd->callback([o] { run_subcommand([&o] { return run_replay(*o); }); });
}

}  // namespace millwatch::shell
