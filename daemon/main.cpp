// millwatchd — the live monitor beside the machine.
//
// Threads: the sample thread runs the pipeline on the blocks of a bounded queue, in place, and
// never publishes. An LCM source's blocks are dispatched in the sample thread itself: on a udpm://
// URL it reads the group's socket itself, a round's datagrams in one call (source.receive
// "batched", daemon/udpm_receiver.hpp); otherwise asleep on LCM's notification pipe (LCM's own
// receive thread reads the socket). It decodes a block into the queue's free slot and runs the
// pipeline on it — a thread between the two (it was) cost a second wake-up per block, 2–2.5 % of
// a core at 1,000 blocks a second. It takes the blocks in rounds
// about source.wake_period_s apart (5 ms): woken for every block, it spent more on the wake-ups
// into cold caches than on the blocks. A Comedi source's reader thread
// fills the queue, and the sample thread sleeps on the queue. The publisher thread
// (messaging::LcmOutput) publishes every output, on lcm.output_url. The main thread waits for
// signals: SIGTERM/SIGINT stop cleanly (the queue is drained, a final status and summary are
// published and logged), SIGHUP reloads the configuration between two blocks (a bad file is
// reported and the running configuration kept). A reload applies the monitor section,
// status_period_s and log_level; the source and the LCM set-up take a restart (said so). Under
// systemd (Type=notify): READY=1 once the source is open, WATCHDOG=1 from the sample loop,
// RELOADING=1/READY=1 around a reload, STOPPING=1 (daemon/service_notifier.hpp).

#include <fmt/format.h>
#include <pthread.h>
#include <signal.h>  // kill
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <unistd.h>  // getpid

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <csignal>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <tuple>
#include <utility>
#include <vector>

#include "core/config/json_reader.hpp"
#include "core/monitor/pipeline.hpp"
#include "daemon/block_queue.hpp"
#include "daemon/comedi_source.hpp"
#include "daemon/daemon_config.hpp"
#include "daemon/drop_ledger.hpp"
#include "daemon/lcm_source.hpp"
#include "daemon/service_notifier.hpp"
#include "shell/json_file.hpp"
#include "shell/material_preset.hpp"
#include "shell/monitor_run.hpp"
#include "shell/output_file.hpp"

namespace {

using namespace millwatch;

/// The command line's URLs: --lcm-url sets the input URL and, without --lcm-output-url, the
/// output URL too (everything on one URL, as a test on memq:// wants).
struct UrlOverrides {
  std::string input;
  std::string output;
};

daemon::DaemonConfig load(const std::string& path, const UrlOverrides& urls) {
  // The command line's URLs are its own, not the file's: said without the file's name.
  for (const auto& [url, option] :
       {std::pair{&urls.input, "--lcm-url"}, std::pair{&urls.output, "--lcm-output-url"}}) {
    if (!url->empty()) {
      try {
        daemon::check_lcm_url(*url, option);
      } catch (const config::ConfigError& e) {
        throw std::runtime_error(e.what());
      }
    }
  }
  try {
    nlohmann::json j = shell::read_json_file(path);
    shell::resolve_material_presets(j, path);  // "model": {"material": "preset.json"}
    daemon::DaemonConfig c = daemon::daemon_config_from_json(j);
    if (!c.monitor.filter_cutoff_note.empty()) {
      spdlog::info("{}: monitor.{}", path, c.monitor.filter_cutoff_note);
    }
    if (!urls.input.empty()) {
      c.lcm_url = urls.input;
      c.lcm_output_url = urls.input;
    }
    if (!urls.output.empty()) {
      c.lcm_output_url = urls.output;
    }
    return c;
  } catch (const config::ConfigError& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
}

/// `build()` of a pipeline (or of a run, which builds one) for a configuration read from
/// `path`. Building it checks what only the stages can (e.g. a spindle window of at least 5
/// revolutions at the commanded speed), so that a bad file is an error here — at --check, at
/// start, on SIGHUP — and never in the sample thread.
template <class Build>
auto build_for(const std::string& path, Build&& build) {
  try {
    return build();
  } catch (const config::ConfigError& e) {
    // The stages name fields relative to the monitor configuration.
    throw std::runtime_error(path + ": monitor." + e.what());
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(path + ": monitor: " + e.what());
  }
}

std::unique_ptr<monitor::Pipeline> make_pipeline(const std::string& path,
                                                 const monitor::MonitorConfig& config,
                                                 monitor::PipelineSink& sink) {
  return build_for(path, [&] { return std::make_unique<monitor::Pipeline>(config, sink); });
}

/// Tests only (hidden options): the sample thread hangs after `stall_after_s`, as a stuck
/// pipeline would, so that the systemd watchdog's pings stop; the source ends after
/// `source_ends_after_s`, as a DAQ whose reads fail would (0: never).
struct TestHooks {
  double stall_after_s = 0.0;
  double source_ends_after_s = 0.0;
};

/// Whether `url` is an LCM log (file://) opened for reading: without mode=w (or a), LCM's file
/// provider reads it, and takes nothing published there.
bool log_read(const std::string& url) {
  return url.rfind("file://", 0) == 0 && url.find("mode=w") == std::string::npos &&
         url.find("mode=a") == std::string::npos;
}

/// Why LCM may have refused a URL, by its provider.
std::string lcm_open_hint(const std::string& url) {
  if (url.rfind("file://", 0) == 0) {
    return log_read(url) ? "the log is not there or cannot be read (a log to write: ?mode=w)"
                         : "the log cannot be written there";
  }
  if (url.rfind("udpm://", 0) == 0 || url.empty()) {
    return "udpm:// needs a multicast route, e.g. `ip route add 239.0.0.0/8 dev lo`";
  }
  if (url.rfind("tcpq://", 0) == 0) {
    return "no LCM TCP queue server answers there";
  }
  return "LCM refused it";
}

/// The LCM source: on a udpm:// URL read by the sample thread in rounds (source.receive
/// "batched"), else through LCM's receive thread (whose name it takes from this thread's).
std::unique_ptr<daemon::LcmSource> open_lcm_source(const daemon::DaemonConfig& config,
                                                   lcm::LCM& lcm_in, daemon::BlockQueue& queue,
                                                   daemon::SourceCounters& counters) {
  const std::optional<daemon::UdpmEndpoint> udpm = daemon::parse_udpm_url(config.lcm_url);
  const bool batched = config.source.receive == daemon::SourceConfig::Receive::kBatched;
  const bool plain = daemon::LcmSource::is_plain_channel(config.source.channel);
  if (!udpm || !batched || !plain) {
    if (udpm && batched) {
      spdlog::info("source.channel {} is a regular expression: LCM's receive thread takes it",
                   config.source.channel);
    }
    pthread_setname_np(pthread_self(), "mw-lcm-receive");  // started by the subscription
    return std::make_unique<daemon::LcmSource>(lcm_in, config.source.channel,
                                               config.source.max_block_samples, queue, counters);
  }
  auto source = std::make_unique<daemon::LcmSource>(
      *udpm, config.source.channel, config.source.max_block_samples, queue, counters);
  const int asked = udpm->recv_buf_size_bytes > 0 ? udpm->recv_buf_size_bytes
                                                  : daemon::UdpmReceiver::kDefaultBufferBytes;
  const int got = source->receive_buffer_bytes();
  spdlog::info(
      "source: the udpm group read in rounds by the sample thread (source.receive), its buffer "
      "{} bytes",
      got);
  // The kernel doubles what it is asked for, within net.core.rmem_max (LCM warns alike).
  if (got < asked) {
    spdlog::warn(
        "the udpm receive buffer is {} bytes, less than the {} asked (the URL's recv_buf_size, "
        "or millwatchd's default): raise net.core.rmem_max, or blocks that come while the "
        "sample thread is busy may be lost (counted as gaps)",
        got, asked);
  }
  return source;
}

int run(const std::string& config_path, const UrlOverrides& urls, const std::string& summary_path,
        TestHooks hooks) {
  daemon::ServiceNotifier notifier;
  daemon::DaemonConfig config = load(config_path, urls);
  spdlog::set_level(spdlog::level::from_str(config.log_level));

  // Signals are taken by the main thread only (sigwait); every thread inherits the mask.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGHUP);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  // Two instances: the output one never subscribes, so LCM gives it no receive socket or thread.
  lcm::LCM lcm_out(config.lcm_output_url);
  lcm::LCM lcm_in(config.lcm_url);
  for (const auto& [lcm, url, key, option] :
       {std::tuple{&lcm_in, &config.lcm_url, "lcm.url", "--lcm-url"},
        std::tuple{&lcm_out, &config.lcm_output_url, "lcm.output_url", "--lcm-output-url"}}) {
    if (!lcm->good()) {
      throw std::runtime_error("cannot open LCM at " + *url + " (" + key + ", or its option " +
                               option + "): " + lcm_open_hint(*url));
    }
  }
  // A log read (file:// without mode=w) takes no messages: results published there are lost.
  if (log_read(config.lcm_output_url)) {
    spdlog::warn(
        "lcm.output_url {} is a log opened for reading: every result published is "
        "dropped (give --lcm-output-url, e.g. memq:// or udpm://…, or a log with "
        "?mode=w)",
        config.lcm_output_url);
  }

  // Threads take the name of the thread that creates them: the ones LCM and shell::MonitorRun
  // start here are named by naming this thread first (for top -H and scripts/daemon_load.sh).
  const auto name_next_threads = [](const char* name) { pthread_setname_np(pthread_self(), name); };
  daemon::SourceCounters source_counters;
  shell::MonitorRun::Options run_options;
  run_options.source_name = "millwatchd";
  run_options.lcm = &lcm_out;
  run_options.channels = config.channels;
  run_options.status_period_s = config.status_period_s;
  // What the source lost before the pipeline saw it, in every status and the summary: the
  // blocks. Their samples are counted once: as the gap they leave before the next block (a
  // lost block is a hole in the stream's time; counting it here too counted it twice), or here
  // when no such gap shows them (since the last block queued; DropLedger's).
  run_options.source_losses = [&source_counters](monitor::PipelineStatus& s) {
    s.input.blocks_rejected += source_counters.undecodable.load() +
                               source_counters.oversized.load() + source_counters.queue_full.load();
    s.input.samples_dropped += source_counters.samples_dropped_unseen();
  };
  // Built here, so that a configuration the stages refuse stops the daemon with its message.
  name_next_threads("mw-identify");  // the identification worker (the publisher names itself)
  std::unique_ptr<shell::MonitorRun> run = build_for(config_path, [&] {
    return std::make_unique<shell::MonitorRun>(config.monitor, run_options);
  });
  // An LCM source decodes in the sample thread, which runs each block before the next: a few
  // slots, kept in the cache. A Comedi reader thread needs room for a backlog.
  const auto queue_storage = std::make_unique<daemon::BlockQueue>(
      config.source.kind == daemon::SourceConfig::Kind::kLcm ? daemon::LcmSource::kQueueCapacity
                                                             : daemon::BlockQueue::kCapacity);
  daemon::BlockQueue& queue = *queue_storage;
  std::atomic<bool> stop{false};

  std::unique_ptr<daemon::LcmSource> lcm_source;
  std::unique_ptr<daemon::ComediSource> comedi_source;
  if (config.source.kind == daemon::SourceConfig::Kind::kLcm) {
    lcm_source = open_lcm_source(config, lcm_in, queue, source_counters);
  } else {
    name_next_threads("mw-comedi");
    comedi_source = std::make_unique<daemon::ComediSource>(
        config.source, config.monitor.sample_rate_hz, queue, source_counters);
  }
  name_next_threads("millwatchd");

  // Reload hand-over: the main thread reads the new file and builds its pipeline, the sample
  // thread swaps it in between two blocks and hands the old one back to be destroyed here, so
  // that neither the build nor the teardown (FFTW plans, model tables) stalls the samples. The
  // sample thread plans too (the lockstep model at a new speed): FFTW's planner is guarded by
  // signal::fftw_planner_mutex().
  struct Reload {
    daemon::DaemonConfig config;
    std::unique_ptr<monitor::Pipeline> pipeline;
  };
  std::mutex reload_mutex;
  std::unique_ptr<Reload> pending;
  std::vector<std::unique_ptr<monitor::Pipeline>> retired;
  std::atomic<bool> reload{false};

  const std::string running =
      fmt::format("source {}, results on LCM {}",
                  config.source.kind == daemon::SourceConfig::Kind::kLcm
                      ? "lcm:" + config.source.channel + " at " + config.lcm_url
                      : "comedi:" + config.source.device,
                  config.lcm_output_url);
  spdlog::info("millwatchd running: {}", running);
  // READY=1 now that the source is open, before the sample loop's first WATCHDOG=1 (sent from
  // the sample thread, it came first now and then).
  notifier.ready("monitoring: " + running);
  if (notifier.watchdog_interval().count() > 0) {
    spdlog::info("systemd watchdog: {} ms; pinged from the sample loop",
                 notifier.watchdog_interval().count() / 1000);
  }

  const auto started = std::chrono::steady_clock::now();
  const auto wake_period = std::chrono::duration<double>(config.source.wake_period_s);
  std::atomic<bool> source_ended{false};
  daemon::DropLedger ledger(source_counters);  // the sample thread's
  const auto source_has_ended = [&] {
    return source_counters.ended.load() ||
           (hooks.source_ends_after_s > 0.0 &&
            std::chrono::steady_clock::now() - started >
                std::chrono::duration<double>(hooks.source_ends_after_s));
  };
  std::thread sample_thread([&] {
    pthread_setname_np(pthread_self(), "mw-sample");
    bool took_blocks = false;  // in this round (since the last wake period)
    while (true) {
      notifier.watchdog();  // a stalled loop stops the pings: systemd restarts the daemon
      if (hooks.stall_after_s > 0.0 && std::chrono::steady_clock::now() - started >
                                           std::chrono::duration<double>(hooks.stall_after_s)) {
        // Test hook (--test-stall-sample-thread): the sample thread hangs until told to stop.
        spdlog::warn("test: the sample thread stalls");
        while (!stop.load()) {
          std::this_thread::sleep_for(std::chrono::milliseconds(5));
        }
        hooks.stall_after_s = 0.0;
      }
      if (reload.load()) {
        std::unique_ptr<Reload> next;
        {
          std::lock_guard<std::mutex> lock(reload_mutex);
          next = std::move(pending);
          reload.store(false);
        }
        if (next) {
          std::unique_ptr<monitor::Pipeline> old = run->replace_pipeline(std::move(next->pipeline));
          {
            std::lock_guard<std::mutex> lock(reload_mutex);
            retired.push_back(std::move(old));
          }
          run->set_status_period(next->config.status_period_s);
          spdlog::set_level(spdlog::level::from_str(next->config.log_level));
          spdlog::info(
              "configuration reloaded after {} samples; the pipeline restarts on the next block",
              run->carried_samples_in());
        }
      }
      if (const daemon::BlockSlot* block = queue.front()) {
        ledger.before_block(block->dropped_before, run->input_timed());
        const bool accepted = run->process(block->view());  // in the queue's slot: no copy
        ledger.after_block(accepted, run->input_timed());
        queue.pop();
        took_blocks = true;
        continue;
      }
      if (stop.load()) {
        // The queue is drained; so is LCM's (what came before the stop).
        if (lcm_source && lcm_source->take_waiting()) {
          continue;
        }
        break;
      }
      if (!source_ended.load() && source_has_ended()) {
        // Nothing more will come (a DAQ whose reads fail): the daemon stops as on SIGTERM,
        // with its final status and summary, and exits 1, so that a service manager restarts
        // it instead of watching a live process that measures nothing.
        source_ended.store(true);
        spdlog::error("the source has ended: millwatchd stops (exit status 1)");
        kill(getpid(), SIGTERM);
      }
      run->idle();  // no samples: still a status every status period
      // Asleep until the source has a block; woken at least every 20 ms (LCM: 20 ms after a
      // round's wake period) for the status, the watchdog, a reload and the stop.
      if (lcm_source) {
        if (lcm_source->take_waiting()) {
          continue;  // the next block had come already: decoded into the queue by LcmSource
        }
        // None waiting after a round of blocks: the next ones gather for a wake period and come
        // in one round (idle, it just waits for the next block).
        if (std::exchange(took_blocks, false)) {
          std::this_thread::sleep_for(wake_period);
        }
        lcm_source->wait(std::chrono::milliseconds(20));
      } else {
        queue.wait(std::chrono::milliseconds(20));
      }
    }
    ledger.close();  // before the final status
    run->finish();
  });

  while (true) {
    int signal = 0;
    sigwait(&signals, &signal);
    if (signal == SIGHUP) {
      notifier.reloading();
      try {
        {
          std::lock_guard<std::mutex> lock(reload_mutex);
          retired.clear();
        }
        auto next = std::make_unique<Reload>();
        next->config = load(config_path, urls);
        const std::string restart = daemon::fields_needing_restart(config, next->config);
        if (!restart.empty()) {
          spdlog::warn("SIGHUP: {}: {} changed; that takes a restart, the running values stay",
                       config_path, restart);
        }
        next->config = daemon::as_reload_of(config, std::move(next->config));
        next->pipeline = make_pipeline(config_path, next->config.monitor, run->sink());
        std::lock_guard<std::mutex> lock(reload_mutex);
        pending = std::move(next);
        reload.store(true);
        spdlog::info("SIGHUP: {} read; applying it", config_path);
        notifier.ready("monitoring: " + running + "; configuration reloaded");
      } catch (const std::exception& e) {
        spdlog::error("SIGHUP: {}; keeping the running configuration", e.what());
        notifier.ready("monitoring: " + running + "; reload failed, running configuration kept");
      }
      continue;
    }
    spdlog::info("{}: stopping", source_ended.load() ? "the source has ended"
                                 : signal == SIGTERM ? "SIGTERM"
                                                     : "SIGINT");
    break;
  }
  // Stop the source first, then let the sample thread drain what was queued.
  notifier.stopping();
  stop.store(true);
  comedi_source.reset();
  sample_thread.join();
  run->drain();
  lcm_source.reset();

  if (run->status().input.samples_in == 0) {  // the summary's nulls need their reason
    const bool lcm = config.source.kind == daemon::SourceConfig::Kind::kLcm;
    const std::string why =
        lcm ? fmt::format(
                  "no samples came: {} message(s) on channel {} from {} (source.channel, "
                  "lcm.url), none taken: speed, α, peaks and residuals are absent",
                  source_counters.messages.load(), config.source.channel, config.lcm_url)
            : fmt::format(
                  "no samples came: no block was read from {} (source.device): speed, "
                  "α, peaks and residuals are absent",
                  config.source.device);
    spdlog::warn("{}", why);
    run->note("no samples", why, 0);
  }
  const nlohmann::json j = run->summary();
  spdlog::info("final summary: {}", j.dump());
  spdlog::info(
      "published {} messages, dropped {}; source: {} messages, {} undecodable, {} queue full",
      run->output()->published(), run->output()->dropped(), source_counters.messages.load(),
      source_counters.undecodable.load(), source_counters.queue_full.load());
  if (!summary_path.empty()) {
    shell::write_text_file(summary_path, j.dump(2) + "\n");
  }
  return source_ended.load() ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  spdlog::set_default_logger(spdlog::stderr_color_mt("millwatchd"));
  CLI::App app{"millwatchd: live micro-milling process monitor"};
  app.set_version_flag("--version", "millwatchd " MILLWATCH_VERSION);
  std::string config_path;
  UrlOverrides urls;
  std::string summary_path;
  bool check = false;
  TestHooks hooks;
  app.add_option("-c,--config", config_path, "Daemon configuration JSON")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--lcm-url", urls.input,
                 "Override the configuration's LCM URLs (lcm.url; lcm.output_url too unless "
                 "--lcm-output-url)");
  app.add_option("--lcm-output-url", urls.output,
                 "Override the configuration's LCM output URL (lcm.output_url)");
  app.add_option("--summary", summary_path, "Write the final summary JSON here on exit");
  app.add_flag("--check", check, "Validate the configuration and exit");
  // Tests only (hidden): TestHooks.
  app.add_option("--test-stall-sample-thread", hooks.stall_after_s)->group("");
  app.add_option("--test-source-ends-after", hooks.source_ends_after_s)->group("");
  CLI11_PARSE(app, argc, argv);
  try {
    if (!summary_path.empty()) {  // written on exit: a path that cannot take it is said now
      shell::check_output_file("--summary", summary_path);
    }
    if (check) {
      const daemon::DaemonConfig c = load(config_path, urls);
      monitor::PipelineSink ignore;
      make_pipeline(config_path, c.monitor, ignore);
      std::printf("%s: configuration is valid\n", config_path.c_str());
      return 0;
    }
    return run(config_path, urls, summary_path, hooks);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
}
