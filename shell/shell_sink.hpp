#pragma once
// The shells' sink: feeds the run summary and logs what the operator should see (warnings for
// bad input, the lock, alerts) with spdlog. Repeated warnings of one kind are rate-limited.

#include <array>
#include <cstdint>
#include <string>

#include "core/monitor/pipeline.hpp"
#include "core/monitor/run_summary.hpp"

namespace millwatch::shell {

class ShellSink : public monitor::PipelineSink {
 public:
  ShellSink(monitor::RunSummary& summary, std::string source)
      : summary_(summary), source_(std::move(source)) {}

  /// Also hands every output to `observer` (not owned; null: none), e.g. a RunRecorder.
  void set_observer(monitor::PipelineSink* observer) { observer_ = observer; }

  void on_revolution(const monitor::RevolutionRecord& r) override;
  void on_sync_average(const monitor::SyncAverage& measured, const monitor::Lockstep* model,
                       std::int64_t revolution, std::int64_t utime_us) override {
    if (observer_ != nullptr) {
      observer_->on_sync_average(measured, model, revolution, utime_us);
    }
  }
  void on_spindle(const monitor::SpindleUpdate& u) override {
    summary_.add(u);
    if (observer_ != nullptr) {
      observer_->on_spindle(u);
    }
  }
  void on_alert(const monitor::Alert& a) override;
  void on_event(const monitor::PipelineEvent& e) override;

 private:
  monitor::RunSummary& summary_;
  std::string source_;
  monitor::PipelineSink* observer_ = nullptr;
  std::array<std::int64_t, 32> logged_{};  // per event kind
};

}  // namespace millwatch::shell
