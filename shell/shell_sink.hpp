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

  void on_revolution(const monitor::RevolutionRecord& r) override { summary_.add(r); }
  void on_spindle(const monitor::SpindleUpdate& u) override { summary_.add(u); }
  void on_alert(const monitor::Alert& a) override;
  void on_event(const monitor::PipelineEvent& e) override;

 private:
  monitor::RunSummary& summary_;
  std::string source_;
  std::array<std::int64_t, 16> logged_{};  // per event kind
};

}  // namespace millwatch::shell
