#pragma once
// What the commands that read a recording (replay, diagnose, calibrate, publish) say of its bad
// rows, events or samples, in one wording: the first kNamed each by place as they are met
// ("cut.csv:12: …; skipped", an LCM log's event number in the same place, a .mat's
// "cut.mat: sample 12: …"), then that more follow; at the recording's end how it ended
// (RecordingSource::end_note()) and how many were skipped. And why a recording gave no sample
// at all, for the command's error.

#include <cstdint>
#include <functional>
#include <string>

#include "shell/recording_source.hpp"

namespace millwatch::shell {

class BadRecordLog {
 public:
  /// How many bad records are named one by one.
  static constexpr std::int64_t kNamed = 20;
  /// Where the warnings go (spdlog::warn unless a test collects them).
  using Say = std::function<void(const std::string&)>;

  /// @param source_name the recording as the user named it
  /// @param format its format (detect_recording_format()): how places are written
  BadRecordLog(std::string source_name, RecordingFormat format, Say say = {});

  /// RecordingOptions::on_bad for the reader: this log must outlive it.
  [[nodiscard]] std::function<void(std::int64_t, const std::string&)> handler();
  /// A bad record at `where` (line, event or sample number).
  void add(std::int64_t where, const std::string& problem);
  [[nodiscard]] std::int64_t count() const { return count_; }

  /// At the recording's end (not after an interruption): its end note, then the total skipped.
  void finish(const RecordingSource& source) const;

 private:
  std::string name_;
  RecordingFormat format_;
  Say say_;
  std::int64_t count_ = 0;
};

/// Why `source` (read to its end) gave no sample: "all 12 lines were bad (named above)" (beyond
/// BadRecordLog::kNamed: "(the first named above)"), or what it held ("no rows after its
/// header").
[[nodiscard]] std::string why_no_samples(const RecordingSource& source);

}  // namespace millwatch::shell
