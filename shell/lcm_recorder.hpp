#pragma once
// Records LCM traffic into an LCM event log (lcm-logger's format, which `millwatch replay`,
// lcm-logplayer and lcm-spy read): every message on the channels a regular expression matches,
// with no limit on the messages waiting in its subscription. lcm-logger 1.3.1 keeps 30 and drops
// the rest when its thread is slow to run; on a busy 2-core machine, at real-time priority, it
// lost runs of 6 to 25 revolutions' results of millwatchd while the kernel dropped nothing.
// A failed write is an error naming the file and the event, never a silent gap. The log is
// flushed to the file at least once a second (flush_if_due), so a recorder killed outright loses
// at most its last second.

#include <lcm/eventlog.h>
#include <lcm/lcm.h>
#include <regex.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>

namespace millwatch::shell {

class LcmRecorder {
 public:
  /// Records from `lcm` (which must outlive the recorder) into a new log at `path` (an existing
  /// file is overwritten: the caller decides) the channels whose whole name matches `channels`, a
  /// POSIX extended regular expression, or with `invert` those it does not match.
  /// @throws std::runtime_error naming the expression or the file when it cannot be used.
  LcmRecorder(lcm_t* lcm, const std::filesystem::path& path, const std::string& channels,
              bool invert = false);
  ~LcmRecorder();
  LcmRecorder(const LcmRecorder&) = delete;
  LcmRecorder& operator=(const LcmRecorder&) = delete;

  /// Records what arrives within `timeout_ms` (0: what is waiting). Returns whether anything was
  /// handled (false too when a signal interrupted the wait). @throws std::runtime_error "PATH:
  /// cannot write event N (…)" on a failed write, or when LCM cannot receive.
  bool handle(int timeout_ms);
  /// The source is a log being read (a file:// URL): LCM's failure to receive past its end is
  /// its end (source_ended()), not an error.
  void set_source_is_a_log(bool is_log) { source_is_log_ = is_log; }
  [[nodiscard]] bool source_is_a_log() const { return source_is_log_; }
  /// A log source has been read to its end (nothing more will arrive).
  [[nodiscard]] bool source_ended() const { return source_ended_; }
  /// Records everything already received, then flushes and closes the log (a second call does
  /// nothing). @throws std::runtime_error on a failed write or close.
  void finish();

  [[nodiscard]] std::int64_t events() const { return events_; }
  [[nodiscard]] std::int64_t bytes() const { return bytes_; }
  /// Events recorded per channel.
  [[nodiscard]] const std::map<std::string, std::int64_t>& per_channel() const {
    return per_channel_;
  }

 private:
  static void on_message(const lcm_recv_buf_t* rbuf, const char* channel, void* self);
  void record(const lcm_recv_buf_t& rbuf, const char* channel);
  void throw_if_failed() const;
  void flush_if_due();

  lcm_t* lcm_;
  std::filesystem::path path_;
  regex_t channels_{};
  bool invert_;
  lcm_eventlog_t* log_ = nullptr;
  lcm_subscription_t* subscription_ = nullptr;
  bool source_is_log_ = false;
  bool source_ended_ = false;
  std::int64_t events_ = 0;
  std::int64_t bytes_ = 0;
  std::map<std::string, std::int64_t> per_channel_;
  std::string failure_;  // the first failed write (the callback cannot throw through LCM's C)
  std::chrono::steady_clock::time_point last_flush_;
};

}  // namespace millwatch::shell
