#include "shell/bad_records.hpp"

#include <spdlog/spdlog.h>

#include <utility>

namespace millwatch::shell {

BadRecordLog::BadRecordLog(std::string source_name, RecordingFormat format, Say say)
    : name_(std::move(source_name)), format_(format), say_(std::move(say)) {
  if (!say_) {
    say_ = [](const std::string& text) { spdlog::warn("{}", text); };
  }
}

std::function<void(std::int64_t, const std::string&)> BadRecordLog::handler() {
  return [this](std::int64_t where, const std::string& problem) { add(where, problem); };
}

void BadRecordLog::add(std::int64_t where, const std::string& problem) {
  ++count_;
  if (count_ <= kNamed) {
    // A line or an event number where a compiler puts a line; a .mat's samples are no lines.
    say_(name_ + (format_ == RecordingFormat::kMat ? ": sample " : ":") + std::to_string(where) +
         ": " + problem + "; skipped");
  } else if (count_ == kNamed + 1) {
    say_(name_ + ": more bad " + record_unit(format_) + " follow; their number comes at the end");
  }
}

void BadRecordLog::finish(const RecordingSource& source) const {
  if (const std::string note = source.end_note(); !note.empty()) {
    say_(name_ + ": " + note);
  }
  if (count_ > 0) {
    say_(name_ + ": " + std::to_string(count_) + " bad " + record_unit(format_, count_) +
         " skipped");
  }
}

std::string why_no_samples(const RecordingSource& source) {
  const std::int64_t bad = source.bad_records();
  if (bad == 0) {
    return source.what_it_held();
  }
  const std::string unit = record_unit(source.format(), bad);
  return (bad == 1 ? "its one " + unit + " was"
                   : "all " + std::to_string(bad) + " " + unit + " were") +
         (bad > BadRecordLog::kNamed ? " bad (the first named above)" : " bad (named above)");
}

}  // namespace millwatch::shell
