// millwatch — the offline shell: simulate recorded cuts, replay them through the monitor,
// diagnose model/measurement gaps. This file is the command line (every subcommand's options);
// replay/<name>_command.cpp runs them. CLI11 is header-only and costs every file that includes it
// about 8 s of compile time (18 s sanitized): one file, not six.

#include <fmt/format.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <exception>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <utility>

#include "replay/calibrate_command.hpp"
#include "replay/diagnose_command.hpp"
#include "replay/publish_command.hpp"
#include "replay/record_command.hpp"
#include "replay/replay_command.hpp"
#include "replay/simulate_command.hpp"
#include "shell/text_layout.hpp"

namespace millwatch::shell {
namespace {

// How a subcommand ends: an exception is logged as an error and the program exits with code 2;
// a non-zero return exits with that code (CLI11 turns CLI::RuntimeError into the exit code).
/// A number at least `lowest` (exclusive when `open`) and at most `highest`, said plainly:
/// CLI11's PositiveNumber and NonNegativeNumber print their range to DBL_MAX, 309 digits, and
/// its Range lets NaN through.
CLI::Validator number_from(double lowest, bool open,
                           double highest = std::numeric_limits<double>::max()) {
  return CLI::Validator(
      [lowest, open, highest](std::string& text) -> std::string {
        double v = 0.0;
        std::size_t used = 0;
        try {
          v = std::stod(text, &used);
        } catch (const std::exception&) {
          used = 0;
        }
        if (used == 0 || used != text.size() || !std::isfinite(v)) {
          return "\"" + text + "\" is not a number";
        }
        if (open ? !(v > lowest) : !(v >= lowest)) {
          return text + " is not a " + (open ? "positive" : "non-negative") + " number";
        }
        if (v > highest) {
          return fmt::format("{} is beyond {:g}", text, highest);
        }
        return {};
      },
      open ? "POSITIVE" : "NON-NEGATIVE");
}
/// A whole number in [lowest, highest], said plainly: CLI11's Range called "abc" and 1.5 "not in
/// range" of an integer option.
CLI::Validator whole_number_in(long long lowest, long long highest) {
  return CLI::Validator(
      [lowest, highest](std::string& text) -> std::string {
        long long v = 0;
        const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
        if (ec != std::errc() || end != text.data() + text.size()) {
          return "\"" + text + "\" is not a whole number";
        }
        if (v < lowest || v > highest) {
          return highest == std::numeric_limits<long long>::max()
                     ? (lowest == 0 ? text + " is not a non-negative whole number"
                                    : fmt::format("{} is below {}", text, lowest))
                     : fmt::format("{} is not in [{}, {}]", text, lowest, highest);
        }
        return {};
      },
      fmt::format("INT in [{} - {}]", lowest, highest));
}
const CLI::Validator kPositive = number_from(0.0, true);
/// A feed per tooth (um) as a cut's model takes it (model.process.feed_per_tooth_um: (0, 1000]):
/// checked here, or the model's reader would blame the configuration for the option's value.
const CLI::Validator kFeedPerTooth = number_from(0.0, true, 1000.0);
const CLI::Validator kNonNegative = number_from(0.0, false);

template <class Body>
void run_subcommand(Body&& body) {
  int rc = 0;
  try {
    rc = body();
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    rc = 2;
  }
  if (rc != 0) {
    throw CLI::RuntimeError(rc);
  }
}

void add_simulate_command(CLI::App& app) {
  auto options = std::make_shared<SimulateOptions>();
  CLI::App* cmd = app.add_subcommand(
      "simulate",
      "Simulate a dynamometer recording of a cut with known truth (CSV + JSON sidecar)");
  cmd->add_option("scenario", options->scenario_path, "Scenario JSON (see config/presets)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", options->output_csv,
                  "Output CSV; the sidecar is written beside it")
      ->required();
  cmd->add_option("--duration", options->duration_s, "Override the recording's duration (s)")
      ->check(kPositive);
  cmd->add_option("--seed", options->seed, "Override the noise seed")
      ->check(whole_number_in(0, std::numeric_limits<long long>::max()));
  cmd->add_option("--truth-json", options->truth_json,
                  "Where the truth (per revolution: speed, chip load, runout, wear) goes "
                  "(default: beside the CSV, CUT.truth.json)");
  cmd->callback([options] { run_subcommand([&options] { return run_simulate(*options); }); });
}

void add_replay_command(CLI::App& app) {
  auto o = std::make_shared<ReplayOptions>();
  CLI::App* cmd = app.add_subcommand(
      "replay",
      "Replay recorded cuts (millwatch CSV, DynoWare export, delimited text, MATLAB .mat, LCM "
      "log) through the monitor");
  cmd->add_option("input", o->inputs,
                  "Recorded cut(s): the format is found from the content (a CUT.json sidecar "
                  "beside a file describes its cut)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--sidecar", o->sidecar, "JSON describing the cut (default: beside the file)");
  cmd->add_option(
      "--config", o->config,
      "Monitor configuration JSON (or a daemon configuration), merged over the sidecar");
  cmd->add_option("--columns", o->columns,
                  "Which columns (or .mat variables) hold time and forces: "
                  "t=Time,fx=Fx,fy=Fy,fz=Fz (names or 1-based indices, optional *scale; .mat: "
                  "fx=F(:,1), fs=rate variable)");
  cmd->add_option("--summary", o->summary,
                  "Write the summary JSON to this file (several cuts: a folder, one per cut)");
  cmd->add_option("--error-file", o->error_file,
                  "Write why the replay failed to this file (a campaign's own replays)")
      ->group("");  // not in --help: the campaign passes it
  cmd->add_flag("--json", o->json, "Print the summary JSON instead of the readable summary");
  cmd->add_option("--revolutions", o->revolutions,
                  "Write one row per revolution to this file: CSV, or JSON Lines for .jsonl "
                  "(several cuts: a folder, one CSV per cut)");
  cmd->add_option(
      "--plot", o->plot,
      "Draw PNG plots with gnuplot into this folder (several cuts: one folder per cut)");
  cmd->add_option("--table", o->table, "Several cuts: write one row per cut to this CSV file");
  cmd->add_option("-j,--jobs", o->jobs, "Several cuts: replay this many at once (0: one per core)")
      ->check(whole_number_in(0, 256));
  cmd->add_flag("!--no-progress", o->progress, "No progress line on a terminal");
  cmd->add_flag("!--no-identify", o->identify,
                "No identification of runout and coefficients (the model in lockstep keeps the "
                "configured parameters; faster)");
  cmd->add_option("--speed", o->speed, "Pace: k times real time (default: as fast as possible)")
      ->check(kNonNegative);
  cmd->add_flag("--realtime", o->realtime, "Pace at real time (--speed 1)")->excludes("--speed");
  cmd->add_option("--publish", o->publish_url,
                  "Publish the results on LCM at this URL (e.g. udpm://239.255.76.67:7667?ttl=0)");
  cmd->add_flag("--publish-raw", o->publish_raw, "Also publish the raw sample blocks");
  cmd->add_flag("--zero-phase", o->zero_phase,
                "Filter forwards and backwards (no phase, no delay; same -3 dB cut-off) instead "
                "of causally (= \"filter\": {\"mode\": \"zero_phase\"} in --config)");
  cmd->add_option("--channel", o->raw_channel, "LCM channel of the raw samples in a log");
  cmd->add_option("--block", o->block_samples, "Samples per block (text and .mat files)")
      ->check(whole_number_in(1, 65536));
  cmd->callback([o] { run_subcommand([&o] { return run_replay(*o); }); });
}

void add_publish_command(CLI::App& app) {
  auto o = std::make_shared<PublishOptions>();
  CLI::App* cmd = app.add_subcommand(
      "publish",
      "Publish raw sample blocks on LCM like a DAQ bridge (from a recording or a scenario)");
  cmd->add_option("input", o->input,
                  "A recording as replay reads it (CSV, DynoWare, text, .mat, LCM log) or a "
                  "scenario .json to simulate")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--sidecar", o->sidecar, "JSON describing the cut (default: beside the file)");
  cmd->add_option("--config", o->config,
                  "Monitor configuration JSON, merged over the sidecar (e.g. the rate of a text "
                  "without a time column)");
  cmd->add_option("--columns", o->columns,
                  "Which columns hold time and forces, as for replay (t=Time,fx=Fx,...)");
  cmd->add_option("--url", o->url, "LCM URL");
  cmd->add_option("--channel", o->channel, "Channel of the raw blocks")->capture_default_str();
  cmd->add_option("--speed", o->speed, "Pace: k times real time, 0 as fast as possible")
      ->check(kNonNegative)
      ->capture_default_str();
  cmd->add_option("--block", o->block_samples,
                  "Samples per message (at most 2000 keeps it under 64 KiB)")
      ->check(whole_number_in(1, 2000))
      ->capture_default_str();
  cmd->add_option("--duration", o->duration_s, "Simulated duration (scenario input)")
      ->check(kPositive);
  // At most 4e9 s (the year 2096): the input check takes utimes below 2⁵³ µs (9.007e9 s), and
  // the recording's own times come on top.
  cmd->add_option("--start-utime", o->start_utime_s,
                  "Add this many seconds to every utime (e.g. seconds since the epoch)")
      ->check(number_from(0.0, false, 4e9));
  cmd->callback([o] { run_subcommand([&o] { return run_publish(*o); }); });
}

void add_record_command(CLI::App& app) {
  auto o = std::make_shared<RecordOptions>();
  CLI::App* cmd = app.add_subcommand(
      "record",
      "Record LCM traffic into an LCM log (lcm-logger's format, without its queue limit) until "
      "Ctrl-C or SIGTERM");
  cmd->add_option("log", o->output, "The LCM log to write")->required();
  cmd->add_option("--url", o->url, "LCM URL");
  cmd->add_option("--channels", o->channels,
                  "Channels to record: a POSIX extended regular expression matching the whole "
                  "name (default: every channel)");
  cmd->add_flag("--invert", o->invert, "Record every channel --channels does not match");
  cmd->add_flag("-f,--force", o->force, "Replace the log if it exists");
  cmd->add_option("--duration", o->duration_s, "Stop after this many seconds")->check(kPositive);
  cmd->callback([o] { run_subcommand([&o] { return run_record(*o); }); });
}

void add_calibrate_command(CLI::App& app) {
  auto o = std::make_shared<CalibrateOptions>();
  CLI::App* cmd = app.add_subcommand(
      "calibrate",
      "Fit one set of force-law coefficients and one runout across recorded cuts of a feed "
      "sweep (one tool, one clamping); write a material preset");
  cmd->add_option("cuts", o->inputs,
                  "Recorded cuts (any format the replay reads; a CUT.json sidecar beside a file "
                  "describes its cut)")
      ->required();
  cmd->add_option("--config", o->config,
                  "Monitor configuration JSON (or a daemon configuration), merged over each "
                  "cut's sidecar");
  cmd->add_option("--feeds-um", o->feeds_um,
                  "Feed per tooth of each cut (um), in the order of the cuts (default: each "
                  "cut's sidecar)")
      ->delimiter(',')
      ->check(kFeedPerTooth);
  cmd->add_option("-o,--output", o->output, "Write the material preset to this JSON file");
  cmd->add_option("--name", o->name, "The preset's material name");
  cmd->add_flag("--tared", o->tared,
                "The channels were tared before each cut: fit the mean force too");
  cmd->add_option("--columns", o->columns,
                  "Which columns hold time and forces, as for replay (t=Time,fx=Fx,...)");
  cmd->add_flag("--json", o->json, "Print the calibration as JSON");
  cmd->add_flag("!--no-progress", o->progress, "No progress line on a terminal");
  cmd->callback([o] { run_subcommand([&o] { return run_calibrate(*o); }); });
}

void add_diagnose_command(CLI::App& app) {
  auto o = std::make_shared<DiagnoseCliOptions>();
  CLI::App* cmd = app.add_subcommand(
      "diagnose",
      "Where model and measurement disagree: name the missing effect, add it, show the gap "
      "shrink (several cuts: also across their feeds)");
  cmd->add_option("cuts", o->inputs,
                  "Recorded cut(s) (any format the replay reads); several: one tool and material "
                  "at different feeds")
      ->required();
  cmd->add_option("--config", o->config,
                  "Monitor configuration JSON (the cut as commanded), merged over each sidecar");
  cmd->add_option("--sidecar", o->sidecar,
                  "The recording's sidecar (one cut; default: CUT.json if there)");
  cmd->add_option("--feeds-um", o->feeds_um,
                  "Feed per tooth of each cut (um), in the order of the cuts (default: each "
                  "cut's sidecar)")
      ->delimiter(',')
      ->check(kFeedPerTooth);
  cmd->add_option("--report", o->report,
                  "Folder for report.md, report.html, report.json, plots (several cuts: one "
                  "folder per cut inside, and the comparison across feeds)")
      ->required();
  cmd->add_option("--start", o->start,
                  "Starting model: 'plain' (no effects, default) or 'configured'");
  cmd->add_option("--band", o->band_hz,
                  "Upper end of the compared band, Hz (default: 0.4·fs or 10 kHz, the lower)")
      ->check(kPositive);
  cmd->add_option("--from-s", o->from_s,
                  "Diagnose from this time on (s from the record's first sample; skip the entry)")
      ->check(kNonNegative);
  cmd->add_option("--to-s", o->to_s, "Diagnose up to this time (s)")->check(kPositive);
  cmd->add_option("--candidates", o->candidates, "Comma-separated candidates (default: all)");
  cmd->add_option("--max-steps", o->max_steps, "Effects added at most (default 10)");
  cmd->add_option("--exchanges", o->exchanges,
                  "Exchanges of an effect named for another where the search stops above the "
                  "noise floor (default 3; 0: the greedy search alone, faster)");
  cmd->add_option("-j,--jobs", o->jobs,
                  "Candidates fitted at once, a thread each (default 0: one per core; the same "
                  "result for any number)")
      ->check(whole_number_in(0, 256));
  cmd->add_flag("!--no-plots", o->plots, "Do not draw the plots");
  cmd->add_flag("!--no-progress", o->progress, "No progress line on a terminal");
  cmd->callback([o]() { run_subcommand([&]() { return run_diagnose(*o); }); });
}
}  // namespace
}  // namespace millwatch::shell

int main(int argc, char** argv) {
  // Logs go to stderr: stdout carries the results (summaries as JSON).
  spdlog::set_default_logger(spdlog::stderr_color_mt("millwatch"));
  CLI::App app{"millwatch: micro-milling process monitor, offline tools"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "millwatch " MILLWATCH_VERSION);
  millwatch::shell::add_simulate_command(app);
  millwatch::shell::add_replay_command(app);
  millwatch::shell::add_publish_command(app);
  millwatch::shell::add_record_command(app);
  millwatch::shell::add_calibrate_command(app);
  millwatch::shell::add_diagnose_command(app);
  // A word that is no command: CLI11 would say only "A subcommand is required".
  if (argc > 1 && argv[1][0] != '-') {
    std::string commands;
    bool known = false;
    const std::function<bool(const CLI::App*)> every = [](const CLI::App*) { return true; };
    for (const CLI::App* sub : std::as_const(app).get_subcommands(every)) {
      commands += (commands.empty() ? "" : ", ") + sub->get_name();
      known = known || sub->get_name() == argv[1];
    }
    if (!known) {  // quoted as errors quote a line: control bytes as \xNN, not to the terminal
      std::fprintf(stderr, "millwatch: no command \"%s\" (commands: %s; millwatch --help)\n",
                   millwatch::shell::excerpt(argv[1], 40).c_str(), commands.c_str());
      return 109;  // CLI11's exit code for an argument it does not expect
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  return 0;
}
