#include "shell/shell_sink.hpp"

#include <spdlog/spdlog.h>

namespace millwatch::shell {

void ShellSink::on_revolution(const monitor::RevolutionRecord& r) {
  summary_.add(r);
  if (observer_ != nullptr) {
    observer_->on_revolution(r);
  }
}

void ShellSink::on_alert(const monitor::Alert& a) {
  summary_.add(a);
  if (observer_ != nullptr) {
    observer_->on_alert(a);
  }
  if (a.active) {
    spdlog::warn("{}: ALERT {} {}: {}", source_, monitor::to_string(a.kind),
                 a.revolution < 0 ? std::string("before the first revolution")
                                  : fmt::format("at revolution {}", a.revolution),
                 a.message.data());
  } else {
    spdlog::info("{}: {}", source_, a.message.data());
  }
}

void ShellSink::on_event(const monitor::PipelineEvent& e) {
  summary_.add(e);
  if (observer_ != nullptr) {
    observer_->on_event(e);
  }
  const auto kind = static_cast<std::size_t>(e.kind);
  const std::int64_t n = ++logged_[kind % logged_.size()];
  const double t_s = static_cast<double>(e.utime_us) * 1e-6;
  switch (e.kind) {
    case monitor::PipelineEventKind::kLockAcquired:
      spdlog::info("{}: spindle locked at {:.1f} rpm (t = {:.3f} s)", source_, e.value, t_s);
      return;
    case monitor::PipelineEventKind::kAlertsHeld:
      spdlog::info(
          "{}: alerts: the speed, {:.1f} rpm, is off the flute-force baseline's {} rpm "
          "(t = {:.3f} s): {}",
          source_, e.value, e.count, t_s, e.detail);
      return;
    case monitor::PipelineEventKind::kAlertsArmed:
      spdlog::info(
          "{}: alerts: {} ({:.1f} rpm, t = {:.3f} s): runout change and wear drift compare "
          "with it",
          source_, e.detail, e.value, t_s);
      return;
    case monitor::PipelineEventKind::kModelAligned:
      // The revolutions' time, not the event's: a lock measures back to the start of the cut,
      // so this can read earlier than the lock's line before it.
      spdlog::info(
          "{}: {} ({} in the average, correlation {:.3f}; up to the revolution at t = "
          "{:.3f} s)",
          source_, e.detail, e.count, e.value, t_s);
      return;
    case monitor::PipelineEventKind::kModelUpdated:
      if (n == 1) {  // then every window: the first says it happens
        spdlog::info(
            "{}: the model in lockstep takes the identified parameters (window ending at "
            "revolution {}, {:.1f} % of the force's variance unexplained)",
            source_, e.count, 100.0 * e.value);
      }
      return;
    case monitor::PipelineEventKind::kCuttingResumed:
      spdlog::info("{}: cutting resumed (t = {:.3f} s)", source_, t_s);
      return;
    case monitor::PipelineEventKind::kCuttingStopped:
      spdlog::info("{}: cutting stopped (t = {:.3f} s)", source_, t_s);
      return;
    case monitor::PipelineEventKind::kLockLost:
      if (e.count > 0) {  // the tooth events' speed against the tracker's
        spdlog::info("{}: spindle lock lost (t = {:.3f} s): {}: {:.0f} rpm against {} rpm", source_,
                     t_s, e.detail, e.value, e.count);
      } else {
        spdlog::info("{}: spindle lock lost (t = {:.3f} s): {}", source_, t_s, e.detail);
      }
      return;
    case monitor::PipelineEventKind::kRecordTooShort:
      spdlog::warn("{}: record too short: {:.4f} s of samples, {:.4f} s needed; {}", source_,
                   static_cast<double>(e.count) / summary_.config().sample_rate_hz, e.value,
                   e.detail);
      return;
    case monitor::PipelineEventKind::kNoSteadySignal:
      spdlog::warn("{}: no steady tooth-passing signal, no speed stated: {}", source_, e.detail);
      return;
    case monitor::PipelineEventKind::kSpeedOutOfRange:
      if (n <= 10) {
        spdlog::warn("{}: t = {:.3f} s: {}", source_, t_s,
                     monitor::describe_line_outside_search(e, summary_.config()));
      }
      return;
    case monitor::PipelineEventKind::kFlutesRelabelled:
      spdlog::warn(
          "{}: flutes relabelled (t = {:.3f} s): flute {} held {:.2f} times CE1's force over the "
          "windows since the lock; locking again, its template choosing CE1",
          source_, t_s, e.count, e.value);
      return;
    case monitor::PipelineEventKind::kNoTemplate:  // no sample count: the lock's speed instead
      if (n <= 10) {
        spdlog::warn(
            "{}: tooth events not found at t = {:.3f} s (sample {}, locked at {:.1f} "
            "rpm): {}",
            source_, t_s, e.sample, e.value, e.detail);
      }
      return;
    default:
      break;
  }
  if (n <= 10) {
    spdlog::warn("{}: {} at t = {:.6f} s (block {}, sample {}): {} sample(s); {}", source_,
                 monitor::to_string(e.kind), t_s, e.block_seq, e.sample, e.count, e.detail);
  } else if (n == 11) {
    spdlog::warn("{}: more \"{}\" follow; counted in the status", source_,
                 monitor::to_string(e.kind));
  }
}

}  // namespace millwatch::shell
