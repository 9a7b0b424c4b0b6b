// What the shells log of the pipeline's events and alerts says what happened with the figures
// that belong to it: a missing tooth-event template is logged with the lock's speed (it has no
// sample count), the alerts held and armed with the speeds, and a sensor alert before the first
// revolution says so.

#include "shell/shell_sink.hpp"

#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <memory>
#include <sstream>
#include <string>

#include "core/monitor/run_summary.hpp"

namespace millwatch::shell {
namespace {

/// Captures what spdlog's default logger writes while it lives.
class LogCapture {
 public:
  LogCapture()
      : previous_(spdlog::default_logger()),
        logger_(std::make_shared<spdlog::logger>(
            "capture", std::make_shared<spdlog::sinks::ostream_sink_st>(text_))) {
    logger_->set_pattern("%v");
    spdlog::set_default_logger(logger_);
  }
  ~LogCapture() { spdlog::set_default_logger(previous_); }
  LogCapture(const LogCapture&) = delete;
  LogCapture& operator=(const LogCapture&) = delete;
  [[nodiscard]] std::string text() const { return text_.str(); }

 private:
  std::ostringstream text_;
  std::shared_ptr<spdlog::logger> previous_;
  std::shared_ptr<spdlog::logger> logger_;
};

TEST(ShellSink, ToothEventsNotFoundIsLoggedWithTheLockNotASampleCount) {
  monitor::MonitorConfig config;
  config.sample_rate_hz = 50000.0;
  monitor::RunSummary summary(config);
  ShellSink sink(summary, "cut.csv");
  LogCapture log;
  monitor::PipelineEvent e;
  e.kind = monitor::PipelineEventKind::kNoTemplate;
  e.utime_us = 1250000;
  e.sample = 62500;
  e.value = 25252.0;
  e.detail = "the synchronous average shows no distinct tooth events";
  sink.on_event(e);
  EXPECT_EQ(log.text(),
            "cut.csv: tooth events not found at t = 1.250 s (sample 62500, locked at 25252.0 "
            "rpm): the synchronous average shows no distinct tooth events\n");
}

// The alerts' flute-force detectors held (the speed off their baseline's) and armed again are
// logged with both speeds, and are no warning of the summary (the held revolutions are counted
// in the status instead).
TEST(ShellSink, AlertsHeldAndArmedAreLoggedWithTheSpeeds) {
  monitor::MonitorConfig config;
  monitor::RunSummary summary(config);
  ShellSink sink(summary, "daq");
  LogCapture log;
  monitor::PipelineEvent held;
  held.kind = monitor::PipelineEventKind::kAlertsHeld;
  held.utime_us = 854000;
  held.value = 39299.9;
  held.count = 39700;
  held.detail = "runout change and wear drift hold";
  sink.on_event(held);
  monitor::PipelineEvent armed;
  armed.kind = monitor::PipelineEventKind::kAlertsArmed;
  armed.utime_us = 2100000;
  armed.value = 36000.0;
  armed.detail = "a new flute-force baseline at this speed";
  sink.on_event(armed);
  EXPECT_EQ(log.text(),
            "daq: alerts: the speed, 39299.9 rpm, is off the flute-force baseline's 39700 rpm "
            "(t = 0.854 s): runout change and wear drift hold\n"
            "daq: alerts: a new flute-force baseline at this speed (36000.0 rpm, t = 2.100 s): "
            "runout change and wear drift compare with it\n");
  const nlohmann::json json = summary.to_json();  // kept: a range over a temporary's member dangles
  for (const auto& w : json["warnings"]) {
    EXPECT_NE(w["kind"], "alerts held") << w.dump();
    EXPECT_NE(w["kind"], "alerts armed") << w.dump();
  }
}

TEST(ShellSink, ASensorAlertBeforeTheFirstRevolutionSaysSo) {
  monitor::MonitorConfig config;
  monitor::RunSummary summary(config);
  ShellSink sink(summary, "daq");
  LogCapture log;
  monitor::Alert a;
  a.kind = monitor::AlertKind::kSensor;
  a.revolution = -1;
  std::snprintf(a.message.data(), a.message.size(), "sensor trouble: x");
  sink.on_alert(a);
  a.revolution = 7;
  sink.on_alert(a);
  EXPECT_EQ(log.text(),
            "daq: ALERT sensor before the first revolution: sensor trouble: x\n"
            "daq: ALERT sensor at revolution 7: sensor trouble: x\n");
}

}  // namespace
}  // namespace millwatch::shell
