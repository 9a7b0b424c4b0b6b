#include "shell/progress_line.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>

namespace millwatch::shell {

namespace {
std::chrono::steady_clock::duration seconds(double s) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(s));
}
}  // namespace

ProgressLine::ProgressLine(bool enabled, double delay_s, double interval_s)
    : enabled_(enabled && isatty(STDERR_FILENO) != 0),
      start_(std::chrono::steady_clock::now()),
      next_(start_ + seconds(delay_s)),
      interval_(seconds(interval_s)) {}

ProgressLine::~ProgressLine() {
  done();
}

double ProgressLine::elapsed_s() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

bool ProgressLine::due() const {
  return enabled_ && std::chrono::steady_clock::now() >= next_;
}

void ProgressLine::show(std::string_view text) {
  if (!due()) {
    return;
  }
  next_ = std::chrono::steady_clock::now() + interval_;
  std::fprintf(stderr, "\r  %.*s\033[K", static_cast<int>(text.size()), text.data());
  std::fflush(stderr);
  shown_ = true;
}

void ProgressLine::done() {
  if (shown_) {
    std::fprintf(stderr, "\r\033[K");
    std::fflush(stderr);
    shown_ = false;
  }
}

std::string times_real_time(double ratio) {
  if (!(ratio >= 0.0) || !std::isfinite(ratio)) {
    return "—";
  }
  if (ratio >= 9.95) {
    return fmt::format("{:.0f}", ratio);
  }
  if (ratio >= 0.995) {
    return fmt::format("{:.1f}", ratio);
  }
  return ratio < 0.001 ? std::string("<0.001") : fmt::format("{:.2g}", ratio);
}

std::string replay_progress_text(double fraction, double sample_time_s, double wall_s,
                                 bool identifying) {
  const std::string done = fmt::format(
      "{:5.1f} %  {:.1f} s of recording in {:.1f} s ({}× real time)", 100.0 * fraction,
      sample_time_s, wall_s, times_real_time(wall_s > 0.0 ? sample_time_s / wall_s : 0.0));
  if (fraction >= 0.999) {
    return done + (identifying ? ", finishing (identification's last fits)" : ", finishing");
  }
  const double left_s = fraction > 0.01 ? wall_s * (1.0 - fraction) / fraction : 0.0;
  return done + (fraction > 0.01 ? fmt::format(", {:.0f} s left", left_s) : "");
}

}  // namespace millwatch::shell
