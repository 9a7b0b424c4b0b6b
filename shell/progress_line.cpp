#include "shell/progress_line.hpp"

#include <unistd.h>

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

}  // namespace millwatch::shell
