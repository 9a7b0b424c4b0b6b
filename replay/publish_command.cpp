#include "replay/publish_command.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <optional>
#include <stdexcept>
#include <thread>
#include <vector>

#include "core/config/json_reader.hpp"
#include "core/sim/cut_simulator.hpp"
#include "msgs/lcm_convert.hpp"
#include "shell/bad_records.hpp"
#include "shell/json_file.hpp"
#include "shell/monitor_config_file.hpp"
#include "shell/recording_source.hpp"

namespace millwatch::shell {

namespace fs = std::filesystem;

int run_publish(const PublishOptions& o) {
  lcm::LCM lcm(o.url);
  if (!lcm.good()) {
    throw std::runtime_error("cannot open LCM at " + o.url);
  }
  const fs::path input = o.input;
  std::unique_ptr<sim::CutSimulator> simulator;
  std::unique_ptr<BadRecordLog> bad;  // declared first: it outlives the reader
  std::unique_ptr<RecordingSource> recording;
  double rate_hz = 0.0;
  std::string extension = input.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  const bool scenario = extension == ".json";
  // What does not apply to the input is refused rather than left unused.
  if (scenario && !(o.sidecar.empty() && o.config.empty() && o.columns.empty())) {
    throw std::runtime_error(input.string() +
                             ": a scenario describes its cut itself: --sidecar, --config and "
                             "--columns are for a recording");
  }
  if (!scenario && o.duration_s > 0.0) {
    throw std::runtime_error(input.string() +
                             ": --duration is for a scenario (a recording is published whole)");
  }
  if (scenario) {  // simulated on the fly
    sim::Scenario s;
    try {
      s = sim::scenario_from_json(read_json_file(input));
    } catch (const config::ConfigError& e) {
      throw std::runtime_error(input.string() + ": " + e.what());
    }
    if (o.duration_s > 0.0) {
      s.duration_s = o.duration_s;
    }
    rate_hz = s.sample_rate_hz;
    simulator = std::make_unique<sim::CutSimulator>(s);
  } else {  // a recording in any format replay reads, described as replay's are
    const LoadedMonitorConfig loaded = load_monitor_config(
        {input, o.config, o.sidecar, o.columns, ""}, read_config_file(o.config));
    bad = std::make_unique<BadRecordLog>(input.string(), detect_recording_format(input));
    RecordingOptions ro;
    ro.columns = loaded.columns;
    ro.config_rate_hz = configured_rate_hz(loaded);
    ro.on_bad = bad->handler();
    recording = open_recording(input, ro);
    spdlog::info("{}: {}", input.string(), recording->description());
  }
  const auto n = static_cast<std::size_t>(o.block_samples);
  std::vector<double> t(n), fx(n), fy(n), fz(n);
  const auto start = std::chrono::steady_clock::now();
  const auto offset_us = static_cast<std::int64_t>(o.start_utime_s * 1e6);
  std::int64_t first_utime = -1;
  std::int64_t seq = 0;
  std::int64_t samples = 0;
  while (true) {
    monitor::SampleBlock b;
    if (simulator) {
      const std::size_t k = simulator->next_block(t, fx, fy, fz);
      if (k == 0) {
        break;
      }
      b = {std::llround(t[0] * 1e6), seq, rate_hz, {fx.data(), k}, {fy.data(), k}, {fz.data(), k}};
    } else {
      const std::optional<monitor::SampleBlock> next = recording->next(n);
      if (!next) {
        break;
      }
      b = *next;
    }
    b.utime_us += offset_us;
    b.seq = seq++;
    if (first_utime < 0) {
      first_utime = b.utime_us;
    }
    if (o.speed > 0.0) {
      std::this_thread::sleep_until(start +
                                    std::chrono::microseconds(static_cast<std::int64_t>(
                                        static_cast<double>(b.utime_us - first_utime) / o.speed)));
    }
    const force_block_t m = messaging::to_message(b);
    lcm.publish(o.channel, &m);
    samples += static_cast<std::int64_t>(b.fx_N.size());
  }
  if (recording) {
    bad->finish(*recording);
    if (samples == 0) {
      spdlog::error("{}: no samples to publish: {}", input.string(), why_no_samples(*recording));
      return 2;
    }
  }
  spdlog::info("published {} blocks, {} samples on {}", seq, samples, o.channel);
  return 0;
}

}  // namespace millwatch::shell
