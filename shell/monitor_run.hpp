#pragma once
// One monitoring run, the part both shells share: a source's blocks through the pipeline, the
// run summary and the operator's log (ShellSink), and optionally every output on LCM with a
// status message every status period.
//
//   MonitorRun run(config, {.source_name = "cut.csv"});
//   while (<a block from the source>) run.process(block);
//   run.finish();       // the sample thread's last call
//   run.drain();        // every queued LCM message published
//   nlohmann::json summary = run.summary();
//
// The replay drives it from a file, the daemon from its sample thread, where a reload swaps the
// pipeline between two blocks (replace_pipeline) and the source's own losses (undecodable
// messages, a full queue) are added to the status (Options::source_losses).

#include <chrono>
#include <cstdint>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "core/identify/identifier.hpp"
#include "core/identify/window_scatter.hpp"
#include "core/monitor/monitor_config.hpp"
#include "core/monitor/pipeline.hpp"
#include "core/monitor/run_summary.hpp"
#include "msgs/lcm_output.hpp"
#include "shell/shell_sink.hpp"

namespace millwatch::shell {

class MonitorRun {
 public:
  struct Options {
    std::string source_name = "millwatch";  ///< prefix of the log lines
    /// Publish every output and the status on this LCM instance (not owned); none if null.
    lcm::LCM* lcm = nullptr;
    messaging::ChannelNames channels;
    /// Status message every this many seconds of sample time (and of wall-clock time when idle).
    double status_period_s = 1.0;
    /// Adds what the source lost before the pipeline saw it to a status (called from the thread
    /// that calls process(), finish() and status()).
    std::function<void(monitor::PipelineStatus&)> source_losses;
    /// Identify runout and force coefficients on every synchronous-average window, in a worker
    /// thread (published on LCM when the run publishes; the last one in the summary).
    bool identify = true;
    /// When an identified result is due but still being fitted: wait (replay, deterministic) or
    /// not (live; counted as late).
    identify::HandOver hand_over = identify::HandOver::kWhenReady;
    /// Also receives every output of the pipeline (not owned; null: none), in the thread that
    /// calls process(): the replay's RunRecorder.
    monitor::PipelineSink* observer = nullptr;
  };

  /// Builds the pipeline. @throws config::ConfigError or std::invalid_argument for a
  /// configuration the pipeline's stages refuse.
  MonitorRun(const monitor::MonitorConfig& config, Options options);
  ~MonitorRun();
  MonitorRun(const MonitorRun&) = delete;
  MonitorRun& operator=(const MonitorRun&) = delete;

  /// The sink this run's pipelines report to: for a pipeline built elsewhere (a reload).
  [[nodiscard]] monitor::PipelineSink& sink();
  /// One block through the pipeline; a status goes out when a status period of sample time has
  /// passed since the last one.
  /// Whether the pipeline took the block (false: rejected, and counted).
  bool process(const monitor::SampleBlock& block);
  /// No block came: a status goes out when a status period of wall-clock time has passed.
  void idle();
  /// Between two blocks: finishes the running pipeline, keeps its counts and hands it back (to
  /// be destroyed off the sample thread; FFTW plans may be destroyed in any thread, see
  /// signal/fftw_planner.hpp).
  std::unique_ptr<monitor::Pipeline> replace_pipeline(std::unique_ptr<monitor::Pipeline> next);
  void set_status_period(double status_period_s) { options_.status_period_s = status_period_s; }

  /// The running pipeline's status with the counts of the pipelines it replaced and what the
  /// source lost.
  [[nodiscard]] monitor::PipelineStatus status() const;
  /// Samples that went into the pipelines replaced so far.
  [[nodiscard]] std::int64_t carried_samples_in() const { return carried_.input.samples_in; }
  /// End of the run: the pipeline's held samples are measured, the final status published and
  /// given to the summary.
  void finish();
  /// Waits until every queued LCM message is published (nothing to do without LCM).
  void drain();
  [[nodiscard]] nlohmann::json summary() const { return summary_.to_json(); }
  /// A warning of the shell's for the summary (monitor::RunSummary::note).
  void note(std::string kind, std::string detail, std::int64_t utime_us) {
    summary_.note(std::move(kind), std::move(detail), utime_us);
  }
  /// The LCM output, if the run publishes.
  [[nodiscard]] const messaging::LcmOutput* output() const { return output_.get(); }
  /// Whether the pipeline knows when its next sample is due, so that it would count samples
  /// missing before the next block it takes as a gap (false until it takes its first block,
  /// unless it goes on from its predecessor's time after a reload).
  [[nodiscard]] bool input_timed() const { return pipeline_->next_input_utime_us().has_value(); }

 private:
  void publish_status();
  void on_identified(const identify::IdentifiedWindow& w);
  /// An identifier for `config`'s model, attached to the running pipeline.
  void start_identifier(const monitor::MonitorConfig& config);

  Options options_;
  monitor::RunSummary summary_;
  ShellSink shell_sink_;
  std::unique_ptr<messaging::LcmOutput> output_;
  std::unique_ptr<monitor::Pipeline> pipeline_;
  monitor::PipelineStatus carried_;    // counts of the pipelines replaced
  std::int64_t carried_utime_us_ = 0;  // the last replaced pipeline's newest sample time
  bool status_due_ = true;             // the first block always gives a status
  std::int64_t next_status_utime_us_ = 0;
  std::chrono::steady_clock::time_point last_status_wall_;
  std::mutex publish_mutex_;         // the identifier's thread publishes too
  std::mutex scatter_mutex_;         // ... and records its windows here
  identify::WindowScatter scatter_;  // the windows' agreement, for the summary's runout σ
  std::unique_ptr<identify::Identifier> identifier_;  // last: its thread uses the members above
};

}  // namespace millwatch::shell
