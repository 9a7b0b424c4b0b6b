#pragma once
// One line of progress on stderr, rewritten in place ("\r…\033[K"), when stderr is a terminal:
// the replay's share done and speed, the diagnosis's step and candidate, the time so far. Cleared
// by done() (or on destruction) so that what follows starts on a clean line.

#include <chrono>
#include <string>
#include <string_view>

namespace millwatch::shell {

class ProgressLine {
 public:
  /// @param enabled false (--no-progress) or stderr not a terminal: shows nothing
  /// @param delay_s shows nothing before this much time has passed (a short run stays quiet)
  /// @param interval_s at most one redraw per interval (0: every call)
  explicit ProgressLine(bool enabled, double delay_s = 0.0, double interval_s = 0.0);
  ~ProgressLine();
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;

  /// Seconds since construction.
  [[nodiscard]] double elapsed_s() const;
  /// Whether a call to show() now would draw (enabled, past the delay and the interval).
  [[nodiscard]] bool due() const;
  /// Draws `text` (when due).
  void show(std::string_view text);
  /// Clears the line if one was drawn.
  void done();

 private:
  bool enabled_;
  bool shown_ = false;
  std::chrono::steady_clock::time_point start_, next_;
  std::chrono::steady_clock::duration interval_;
};

/// A speed as a multiple of real time: "35", "2.1", "0.02" (two significant digits below 10:
/// a replay slowed by identification's fits is not "0×").
std::string times_real_time(double ratio);

/// The replay's progress: "42.0 %  4.2 s of recording in 2.1 s (2.0× real time), 3 s left".
/// Once the recording is read (`fraction` ≥ 0.999) it says "finishing" (with `identifying`:
/// the last identification windows' fits, which can take seconds) instead of "0 s left".
std::string replay_progress_text(double fraction, double sample_time_s, double wall_s,
                                 bool identifying);

}  // namespace millwatch::shell
