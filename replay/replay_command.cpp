#include "replay/replay_command.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <spawn.h>
#include <spdlog/spdlog.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <span>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "core/config/json_reader.hpp"
#include "core/monitor/in_plane_force.hpp"
#include "core/monitor/monitor_config.hpp"
#include "msgs/lcm_convert.hpp"
#include "replay/stop_signal.hpp"
#include "shell/bad_records.hpp"
#include "shell/column_map.hpp"
#include "shell/cut_table.hpp"
#include "shell/json_file.hpp"
#include "shell/monitor_config_file.hpp"
#include "shell/monitor_run.hpp"
#include "shell/output_file.hpp"
#include "shell/progress_line.hpp"
#include "shell/read_ahead_source.hpp"
#include "shell/recording_source.hpp"
#include "shell/run_plots.hpp"
#include "shell/run_recorder.hpp"
#include "shell/summary_text.hpp"

extern char** environ;

namespace millwatch::shell {
namespace {

namespace fs = std::filesystem;

int replay_one(const ReplayOptions& o) {
  const fs::path input = o.inputs.front();
  // The outputs are written last: a path that cannot take them must not cost the whole replay.
  for (const auto& [option, path] :
       {std::pair{"--summary", &o.summary}, std::pair{"--revolutions", &o.revolutions}}) {
    if (!path->empty()) {
      check_output_file(option, *path, "a folder; one cut writes a file");
    }
  }
  if (!o.plot.empty()) {
    check_output_folder("--plot", o.plot, "the plots");
  }
  const RecordingFormat format = detect_recording_format(input);
  const bool lcm_log = format == RecordingFormat::kLcmLog;
  // The configuration: the sidecar's cut under --config's overrides.
  LoadedMonitorConfig loaded =
      load_monitor_config({input, o.config, o.sidecar, o.columns, ""}, read_config_file(o.config));
  loaded.warn_model_note(input);
  const double config_rate_hz = configured_rate_hz(loaded);

  BadRecordLog bad(input.string(), format);
  RecordingOptions ro;
  ro.columns = loaded.columns;
  ro.config_rate_hz = config_rate_hz;
  ro.lcm_channel = o.raw_channel;
  ro.on_bad = bad.handler();
  // Read on a second thread, a few blocks ahead: parsing overlaps the pipeline.
  const auto block_samples = static_cast<std::size_t>(o.block_samples);
  std::unique_ptr<RecordingSource> source = open_recording_read_ahead(input, ro, block_samples);
  spdlog::info("{}: {}", input.string(), source->description());
  take_recording_rate(loaded, *source, input.string());
  monitor::MonitorConfig config = parse_monitor_config(loaded);
  if (o.zero_phase) {
    config.filter_zero_phase = true;
  }

  std::unique_ptr<lcm::LCM> lcm;
  if (!o.publish_url.empty()) {
    lcm = std::make_unique<lcm::LCM>(o.publish_url);
    if (!lcm->good()) {
      throw std::runtime_error("cannot open LCM at " + o.publish_url);
    }
  }
  std::unique_ptr<RunRecorder> recorder;
  if (!o.revolutions.empty() || !o.plot.empty()) {
    recorder =
        std::make_unique<RunRecorder>(config.model.tool.flutes, o.revolutions, !o.plot.empty());
  }
  MonitorRun::Options run_options;
  run_options.source_name = input.string();
  run_options.lcm = lcm.get();  // none: the summary and the log only
  run_options.observer = recorder.get();
  run_options.identify = o.identify;
  // Offline, each identified result is taken at its due revolution even when the fit is slower
  // than the replay: the results do not depend on the machine's speed.
  run_options.hand_over = identify::HandOver::kWait;
  MonitorRun run(config, run_options);

  const double speed = o.realtime ? 1.0 : o.speed;
  const auto start = std::chrono::steady_clock::now();
  std::int64_t first_utime = 0;
  std::int64_t last_utime = 0;
  bool have_first = false;
  install_stop_signals();
  ProgressLine progress(o.progress, 2.0, 0.25);
  // The record's in-plane force, in the model's frame and before any filter.
  monitor::InPlaneForce in_plane;
  std::int64_t samples_read = 0;
  std::int64_t raw_published = 0;  // --publish-raw's blocks, LCM's answer to each
  std::int64_t raw_failed = 0;
  while (!stop_requested()) {
    const std::optional<monitor::SampleBlock> next = source->next(block_samples);
    if (!next) {
      break;
    }
    const monitor::SampleBlock& block = *next;
    samples_read += static_cast<std::int64_t>(block.fx_N.size());
    if (!have_first) {
      first_utime = block.utime_us;
      have_first = true;
    }
    // The block's end: where the replay stood when it was stopped.
    last_utime = block.utime_us +
                 std::llround(static_cast<double>(block.fx_N.size()) / block.sample_rate_hz * 1e6);
    if (speed > 0.0) {  // pace by the blocks' own time
      const auto due = start + std::chrono::microseconds(static_cast<std::int64_t>(
                                   static_cast<double>(block.utime_us - first_utime) / speed));
      std::this_thread::sleep_until(due);
    }
    if (o.publish_raw && lcm) {
      const force_block_t raw = messaging::to_message(block);
      (lcm->publish(o.raw_channel, &raw) == 0 ? raw_published : raw_failed) += 1;
    }
    if (recorder) {
      recorder->add_samples(block);
    }
    {
      // The model's x and y are ± two of the channels: the signs do not change the squares.
      const std::array<std::span<const double>, 3> channel = {block.fx_N, block.fy_N, block.fz_N};
      const std::span<const double> x =
          channel[static_cast<std::size_t>(config.axis_map.source[0])];
      const std::span<const double> y =
          channel[static_cast<std::size_t>(config.axis_map.source[1])];
      in_plane.add(x, y);
    }
    run.process(block);
    if (progress.due()) {
      progress.show(replay_progress_text(source->progress(),
                                         static_cast<double>(block.utime_us - first_utime) * 1e-6,
                                         progress.elapsed_s(), o.identify));
    }
  }
  progress.done();
  if (!stop_requested()) {
    bad.finish(*source);
  }
  run.finish();
  if (stop_requested()) {
    spdlog::warn("interrupted: the summary covers the samples replayed so far");
  }
  run.drain();
  if (const messaging::LcmOutput* out = run.output(); out != nullptr) {
    spdlog::log(out->dropped() + raw_failed > 0 ? spdlog::level::warn : spdlog::level::info,
                "--publish {}: {} messages published, {} dropped{}", o.publish_url,
                out->published(), out->dropped(),
                o.publish_raw ? fmt::format("; raw blocks on {}: {} published, {} failed",
                                            o.raw_channel, raw_published, raw_failed)
                              : std::string());
  }
  if (stop_requested()) {  // the summary says so too: a reader of it alone could not tell
    run.note("interrupted",
             fmt::format("the replay was stopped by {} after {:.3f} s of the record ({} samples "
                         "read): this summary covers them alone",
                         stop_signal() == SIGTERM ? "SIGTERM" : "SIGINT",
                         static_cast<double>(last_utime - first_utime) * 1e-6, samples_read),
             last_utime);
  }
  if (!loaded.rate_note.empty()) {  // the summary alone says so too
    run.note("rate overridden", loaded.rate_note, first_utime);
  }
  if (!loaded.model_note.empty()) {  // said in the log at the start
    run.note("cut not described", loaded.model_note, first_utime);
  }
  nlohmann::json j = run.summary();
  j["input"] = input.string();
  j["input_format"] = source->description();
  j["filter"] = config.filter_zero_phase ? "zero_phase" : "causal";
  j["filter_cutoff_hz"] = config.filter_cutoff_hz;
  j["bad_lines"] = source->bad_records();
  j["record_in_plane_force_N"] =
      in_plane.samples() > 0
          ? nlohmann::json{{"rms", *in_plane.rms_N()}, {"max", *in_plane.max_N()}}
          : nlohmann::json{{"rms", nullptr}, {"max", nullptr}};
  // A record with nothing measurable is a failed replay, said before any summary, revolutions
  // or plots are written (a summary of 0 samples would look like a replay that worked).
  if (samples_read == 0 && (source->bad_records() > 0 || !stop_requested())) {
    // Neither a cut without cutting nor an interrupted one: nothing to measure at all (a header
    // alone, a log without the raw channel, a file this reader could not read a row of).
    throw std::runtime_error(fmt::format(
        "{}: no samples to replay{}: {}{}", input.string(),
        stop_requested() ? " (interrupted)" : "", why_no_samples(*source),
        lcm_log && source->bad_records() == 0 ? " (--channel names the log's raw channel)" : ""));
  }
  if (recorder) {
    recorder->commit();
    if (!o.revolutions.empty()) {
      spdlog::info("{}: {} revolutions written", o.revolutions, recorder->rows_written());
    }
    if (!o.plot.empty()) {
      const auto pngs = write_plots(*recorder, j, o.plot, input.filename().string());
      spdlog::info("{}: {} plot{} drawn ({})", o.plot, pngs.size(), pngs.size() == 1 ? "" : "s",
                   (fs::path(o.plot) / "plots.txt").string());
    }
  }
  if (!o.summary.empty()) {
    write_text_file(o.summary, j.dump(2) + "\n");
  }
  if (o.json) {
    std::printf("%s\n", j.dump(2).c_str());
  } else {
    std::printf("%s", summary_text(j).c_str());
  }
  std::fflush(stdout);
  return stop_requested() ? interrupted_exit_status() : 0;
}

/// Runs `argv` with stdout to /dev/null; returns its pid.
pid_t spawn(const std::vector<std::string>& args) {
  std::vector<char*> argv;
  for (const auto& a : args) {
    argv.push_back(const_cast<char*>(a.c_str()));
  }
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, args[0].c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) {
    throw std::runtime_error("cannot run " + args[0] + ": " + std::strerror(rc));
  }
  return pid;
}

int replay_many(const ReplayOptions& o) {
  if (!o.publish_url.empty() || o.realtime || o.speed > 0.0) {
    throw std::runtime_error(
        "--publish, --realtime and --speed take one recording at a time (several are replayed "
        "as fast as possible, side by side)");
  }
  const std::size_t n = o.inputs.size();
  const int jobs =
      o.jobs > 0 ? o.jobs : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const std::vector<std::string> stems = shell::unique_stems(o.inputs);
  if (!o.table.empty()) {  // written last: a path that cannot take it must not cost the campaign
    check_output_file("--table", o.table);
  }
  for (const auto& [option, dir] :
       {std::pair{"--summary", &o.summary}, std::pair{"--revolutions", &o.revolutions},
        std::pair{"--plot", &o.plot}}) {
    std::error_code ec;
    if (!dir->empty()) {
      fs::create_directories(*dir, ec);
    }
    if (ec) {
      throw std::runtime_error(fmt::format("{} {}: cannot make the folder for the cuts ({})",
                                           option, *dir, ec.message()));
    }
  }
  // Each cut's summary goes to a scratch folder (or --summary DIR) and is read back.
  const fs::path scratch =
      fs::temp_directory_path() / fmt::format("millwatch-replay-{}", static_cast<long>(getpid()));
  fs::create_directories(scratch);
  const std::string self = fs::read_symlink("/proc/self/exe").string();
  std::vector<fs::path> summaries(n);
  std::vector<fs::path> errors(n);  // why a cut's replay failed, in its own words
  std::vector<int> exit_codes(n, -1);
  std::vector<bool> interrupted(n, false);
  std::map<pid_t, std::size_t> running;
  std::size_t next = 0;
  std::size_t done = 0;
  install_stop_signals();
  while (done < n) {
    while (!stop_requested() && next < n && static_cast<int>(running.size()) < jobs) {
      const std::size_t k = next++;
      summaries[k] = o.summary.empty() ? scratch / fmt::format("{}.json", k)
                                       : fs::path(o.summary) / (stems[k] + ".json");
      errors[k] = scratch / fmt::format("{}.error", k);
      // An earlier run's summary there must not pass for this one's (a cut killed before it
      // writes one).
      std::error_code stale;
      fs::remove(summaries[k], stale);
      std::vector<std::string> args = {
          self,           "replay",           o.inputs[k],    "--summary", summaries[k].string(),
          "--error-file", errors[k].string(), "--no-progress"};
      auto pass = [&args](const char* flag, const std::string& value) {
        if (!value.empty()) {
          args.push_back(flag);
          args.push_back(value);
        }
      };
      pass("--sidecar", o.sidecar);
      pass("--config", o.config);
      pass("--columns", o.columns);
      pass("--channel", o.raw_channel);
      pass("--block", std::to_string(o.block_samples));
      if (!o.revolutions.empty()) {
        pass("--revolutions", (fs::path(o.revolutions) / (stems[k] + ".csv")).string());
      }
      if (!o.plot.empty()) {
        pass("--plot", (fs::path(o.plot) / stems[k]).string());
      }
      if (o.zero_phase) {
        args.push_back("--zero-phase");
      }
      if (!o.identify) {
        args.push_back("--no-identify");
      }
      running[spawn(args)] = k;
    }
    if (running.empty()) {
      break;  // interrupted before the rest started
    }
    int status = 0;
    const pid_t pid = waitpid(-1, &status, 0);
    if (pid < 0) {
      if (errno == EINTR) {
        continue;
      }
      throw std::runtime_error(std::string("waitpid: ") + std::strerror(errno));
    }
    const auto it = running.find(pid);
    if (it == running.end()) {
      continue;
    }
    const std::size_t k = it->second;
    running.erase(it);
    exit_codes[k] = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    // Stopped with the campaign and exited on its own: its summary covers what it replayed (a
    // cut the signal killed wrote none).
    interrupted[k] = WIFEXITED(status) && is_interrupted_exit_status(exit_codes[k]);
    ++done;
    spdlog::info("[{}/{}] {}: {}", done, n, o.inputs[k],
                 exit_codes[k] == 0 ? "done"
                 : interrupted[k]   ? fmt::format("interrupted (exit {}): partial", exit_codes[k])
                                    : fmt::format("failed (exit {})", exit_codes[k]));
  }
  std::vector<CutResult> results;
  for (std::size_t k = 0; k < n; ++k) {
    CutResult r;
    r.file = o.inputs[k];
    r.exit_code = exit_codes[k];
    // A cut stopped with the campaign wrote a summary of what it replayed (it says so).
    if ((exit_codes[k] == 0 || interrupted[k]) && fs::exists(summaries[k])) {
      r.summary = read_json_file(summaries[k]);
    }
    if (std::ifstream why(errors[k]); exit_codes[k] != 0 && why) {
      std::getline(why, r.error);
    }
    results.push_back(std::move(r));
  }
  fs::remove_all(scratch);
  if (!o.table.empty()) {
    write_text_file(o.table, cut_table_csv(results));
  }
  if (o.json) {
    nlohmann::json all = nlohmann::json::array();
    for (const auto& r : results) {
      all.push_back(
          r.summary.is_null()
              ? nlohmann::json{{"input", r.file}, {"exit_code", r.exit_code}, {"error", r.error}}
              : r.summary);
    }
    std::printf("%s\n", all.dump(2).c_str());
  } else {
    std::printf("%s", cut_table_text(results).c_str());
  }
  const bool failed = std::any_of(results.begin(), results.end(),
                                  [](const CutResult& r) { return r.exit_code != 0; });
  if (stop_requested()) {
    spdlog::warn("interrupted: {} of {} cuts replayed", done, n);
  }
  return failed || stop_requested() ? 1 : 0;
}

}  // namespace

int run_replay(const ReplayOptions& o) {
  if (o.inputs.size() > 1 || !o.table.empty()) {
    return replay_many(o);
  }
  try {
    return replay_one(o);
  } catch (const std::exception& e) {
    if (!o.error_file.empty()) {
      std::string why = e.what();
      std::replace(why.begin(), why.end(), '\n', ' ');  // one line: the campaign's table
      std::ofstream(o.error_file) << why << "\n";
    }
    throw;
  }
}

}  // namespace millwatch::shell
