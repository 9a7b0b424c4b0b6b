// millwatchd — the live monitor beside the machine.
//
// Threads: an LCM receiver (or the Comedi reader) fills a bounded queue of sample blocks; the
// sample thread runs the pipeline on them (never publishing, never waiting on LCM); the
// publisher thread (messaging::LcmOutput) publishes every output. The main thread waits for
// signals: SIGTERM/SIGINT stop cleanly (the queue is drained, a final status and summary are
// published and logged), SIGHUP reloads the configuration between two blocks (a bad file is
// reported and the running configuration kept).

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <csignal>
#include <memory>
#include <mutex>
#include <thread>

#include "core/config/json_reader.hpp"
#include "core/monitor/pipeline.hpp"
#include "core/monitor/run_summary.hpp"
#include "daemon/block_queue.hpp"
#include "daemon/comedi_source.hpp"
#include "daemon/daemon_config.hpp"
#include "daemon/lcm_source.hpp"
#include "msgs/lcm_output.hpp"
#include "replay/json_file.hpp"
#include "replay/output_file.hpp"
#include "replay/shell_sink.hpp"

namespace {

using namespace millwatch;

daemon::DaemonConfig load(const std::string& path, const std::string& url_override) {
  try {
    daemon::DaemonConfig c = daemon::daemon_config_from_json(shell::read_json_file(path));
    if (!url_override.empty()) {
      c.lcm_url = url_override;
    }
    return c;
  } catch (const config::ConfigError& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
}

/// The pipeline's status with what was lost before it (in the source, in replaced pipelines).
monitor::PipelineStatus merged_status(const monitor::Pipeline& p,
                                      const monitor::InputCounters& carried,
                                      const daemon::SourceCounters& source) {
  monitor::PipelineStatus s = p.status();
  auto& in = s.input;
  in.samples_in += carried.samples_in;
  in.samples_accepted += carried.samples_accepted;
  in.samples_dropped += carried.samples_dropped + source.samples_dropped.load();
  in.samples_flagged += carried.samples_flagged;
  in.nonfinite_samples += carried.nonfinite_samples;
  in.saturated_samples += carried.saturated_samples;
  in.gaps += carried.gaps;
  in.out_of_order_blocks += carried.out_of_order_blocks;
  in.blocks_rejected +=
      carried.blocks_rejected + source.undecodable.load() + source.oversized.load();
  return s;
}

void carry(monitor::InputCounters& total, const monitor::InputCounters& c) {
  total.samples_in += c.samples_in;
  total.samples_accepted += c.samples_accepted;
  total.samples_dropped += c.samples_dropped;
  total.samples_flagged += c.samples_flagged;
  total.nonfinite_samples += c.nonfinite_samples;
  total.saturated_samples += c.saturated_samples;
  total.gaps += c.gaps;
  total.out_of_order_blocks += c.out_of_order_blocks;
  total.blocks_rejected += c.blocks_rejected;
}

int run(const std::string& config_path, const std::string& url_override,
        const std::string& summary_path) {
  daemon::DaemonConfig config = load(config_path, url_override);
  spdlog::set_level(spdlog::level::from_str(config.log_level));

  // Signals are taken by the main thread only (sigwait); every thread inherits the mask.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGHUP);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  lcm::LCM lcm_out(config.lcm_url);
  lcm::LCM lcm_in(config.lcm_url);
  if (!lcm_out.good() || !lcm_in.good()) {
    throw std::runtime_error(
        "cannot open LCM at " + config.lcm_url +
        " (udpm:// needs a multicast route, e.g. `ip route add 239.0.0.0/8 dev lo`)");
  }

  monitor::RunSummary summary(config.monitor);
  shell::ShellSink shell_sink(summary, "millwatchd");
  messaging::LcmOutput output(lcm_out, config.channels, &shell_sink);
  daemon::BlockQueue queue;
  daemon::SourceCounters source_counters;
  std::atomic<bool> stop{false};

  std::unique_ptr<daemon::LcmSource> lcm_source;
  std::unique_ptr<daemon::ComediSource> comedi_source;
  std::thread receiver;
  if (config.source.kind == daemon::SourceConfig::Kind::kLcm) {
    lcm_source =
        std::make_unique<daemon::LcmSource>(lcm_in, config.source.channel, queue, source_counters);
    receiver = std::thread([&] {
      while (!stop.load()) {
        lcm_in.handleTimeout(50);
      }
    });
  } else {
    comedi_source = std::make_unique<daemon::ComediSource>(
        config.source, config.monitor.sample_rate_hz, queue, source_counters);
  }

  // Reload hand-over: the main thread parks a new configuration, the sample thread takes it
  // between two blocks.
  std::mutex reload_mutex;
  std::unique_ptr<daemon::DaemonConfig> pending;
  std::atomic<bool> reload{false};
  monitor::InputCounters carried;

  std::thread sample_thread([&] {
    auto pipeline = std::make_unique<monitor::Pipeline>(config.monitor, output);
    auto slot = std::make_unique<daemon::BlockSlot>();
    std::int64_t next_status_utime = 0;
    auto last_status_wall = std::chrono::steady_clock::now();
    const auto period = std::chrono::duration<double>(config.status_period_s);
    while (true) {
      if (reload.load()) {
        std::lock_guard<std::mutex> lock(reload_mutex);
        if (pending) {
          pipeline->finish();  // samples held for zero-phase filtering are measured first
          carry(carried, pipeline->status().input);
          pipeline = std::make_unique<monitor::Pipeline>(pending->monitor, output);
          spdlog::info("configuration reloaded; the pipeline restarts on the next block");
          pending.reset();
        }
        reload.store(false);
      }
      if (queue.try_pop(*slot)) {
        const monitor::SampleBlock block = slot->view();
        pipeline->process(block);
        if (block.utime_us >= next_status_utime) {
          output.publish_status(merged_status(*pipeline, carried, source_counters));
          next_status_utime =
              block.utime_us + static_cast<std::int64_t>(config.status_period_s * 1e6);
          last_status_wall = std::chrono::steady_clock::now();
        }
        continue;
      }
      if (stop.load()) {
        break;  // the queue is drained
      }
      // Idle: no samples. Still say so every status period.
      if (std::chrono::steady_clock::now() - last_status_wall > period) {
        output.publish_status(merged_status(*pipeline, carried, source_counters));
        last_status_wall = std::chrono::steady_clock::now();
      }
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    pipeline->finish();
    const monitor::PipelineStatus final_status = merged_status(*pipeline, carried, source_counters);
    output.publish_status(final_status);
    summary.finish(final_status);
  });

  spdlog::info("millwatchd running: source {}, LCM {}",
               config.source.kind == daemon::SourceConfig::Kind::kLcm
                   ? "lcm:" + config.source.channel
                   : "comedi:" + config.source.device,
               config.lcm_url);
  while (true) {
    int signal = 0;
    sigwait(&signals, &signal);
    if (signal == SIGHUP) {
      try {
        auto next = std::make_unique<daemon::DaemonConfig>(load(config_path, url_override));
        std::lock_guard<std::mutex> lock(reload_mutex);
        pending = std::move(next);
        reload.store(true);
        spdlog::info("SIGHUP: {} read; applying it", config_path);
      } catch (const std::exception& e) {
        spdlog::error("SIGHUP: {}; keeping the running configuration", e.what());
      }
      continue;
    }
    spdlog::info("{}: stopping", signal == SIGTERM ? "SIGTERM" : "SIGINT");
    break;
  }
  // Stop the source first, then let the sample thread drain what was queued.
  stop.store(true);
  if (receiver.joinable()) {
    receiver.join();
  }
  comedi_source.reset();
  sample_thread.join();
  output.drain();
  lcm_source.reset();

  const nlohmann::json j = summary.to_json();
  spdlog::info("final summary: {}", j.dump());
  spdlog::info(
      "published {} messages, dropped {}; source: {} messages, {} undecodable, {} queue full",
      output.published(), output.dropped(), source_counters.messages.load(),
      source_counters.undecodable.load(), source_counters.queue_full.load());
  if (!summary_path.empty()) {
    shell::OutputFile out(summary_path);
    out.write(j.dump(2) + "\n");
    out.commit();
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  spdlog::set_default_logger(spdlog::stderr_color_mt("millwatchd"));
  CLI::App app{"millwatchd: live micro-milling process monitor"};
  std::string config_path;
  std::string url;
  std::string summary_path;
  bool check = false;
  app.add_option("-c,--config", config_path, "Daemon configuration JSON")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--lcm-url", url, "Override the configuration's LCM URL");
  app.add_option("--summary", summary_path, "Write the final summary JSON here on exit");
  app.add_flag("--check", check, "Validate the configuration and exit");
  CLI11_PARSE(app, argc, argv);
  try {
    if (check) {
      load(config_path, url);
      std::printf("%s: configuration is valid\n", config_path.c_str());
      return 0;
    }
    return run(config_path, url, summary_path);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
}
