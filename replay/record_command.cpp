#include "replay/record_command.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <filesystem>
#include <lcm/lcm-cpp.hpp>
#include <stdexcept>

#include "replay/stop_signal.hpp"
#include "shell/lcm_recorder.hpp"

namespace millwatch::shell {
int run_record(const RecordOptions& o) {
  namespace fs = std::filesystem;
  if (!o.force && fs::exists(o.output)) {
    throw std::runtime_error(o.output +
                             " exists: record into a new file, or --force to replace it");
  }
  lcm::LCM lcm(o.url);
  if (!lcm.good()) {
    throw std::runtime_error("cannot open LCM at " + o.url);
  }
  LcmRecorder recorder(lcm.getUnderlyingLCM(), o.output, o.channels, o.invert);
  recorder.set_source_is_a_log(o.url.rfind("file://", 0) == 0);
  install_stop_signals(InterruptedCalls::return_at_once);  // the wait ends with the signal
  spdlog::info("recording {}{} from {} into {} until {}", o.invert ? "every channel but " : "",
               o.channels, o.url, o.output,
               o.duration_s > 0.0           ? fmt::format("{} s have passed", o.duration_s)
               : recorder.source_is_a_log() ? std::string("the log's end, SIGINT or SIGTERM")
                                            : std::string("SIGINT or SIGTERM (Ctrl-C)"));
  const auto start = std::chrono::steady_clock::now();
  const auto elapsed_s = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  while (!stop_requested() && !recorder.source_ended() &&
         (o.duration_s <= 0.0 || elapsed_s() < o.duration_s)) {
    recorder.handle(100);
  }
  if (recorder.source_ended()) {
    spdlog::info("{}: read to its end", o.url);
  }
  recorder.finish();  // what arrived before the end and is still queued
  spdlog::info("{} events, {} bytes of messages, in {} over {:.1f} s", recorder.events(),
               recorder.bytes(), o.output, elapsed_s());
  for (const auto& [channel, count] : recorder.per_channel()) {
    spdlog::info("  {}: {}", channel, count);
  }
  if (recorder.events() == 0) {
    spdlog::warn(
        "nothing recorded: nothing was published on {} on a channel {} (a udpm URL also "
        "needs the publisher's ttl to reach this host, and a multicast route)",
        o.url, o.invert ? "outside " + o.channels : "matching " + o.channels);
  }
  return 0;
}

}  // namespace millwatch::shell
