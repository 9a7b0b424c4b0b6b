#pragma once
// A recorded cut in any of the formats the replay reads, recognised by its content (never its
// name), as one stream of sample blocks:
//
//   LCM log          lcm-logger's event log (sync word 0xEDA1DA01): the raw channel's blocks
//   MATLAB .mat      v5 ("MATLAB 5.0 MAT-file" header) and v7.3 (HDF5 with that header in its
//                    user block); a binary file named .mat is taken for one (and a v4 file,
//                    which has no header, is refused with a word on how to save it)
//   millwatch CSV, DynoWare export, delimited text with a column map (text_layout.hpp)
//
// The sample rate a recording states (DynoWare's preamble, a .mat's fs variable) is its rate;
// otherwise the configuration's, else what its time (column, vector, LCM blocks) shows.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "core/monitor/sample_block.hpp"
#include "shell/column_map.hpp"

namespace millwatch::shell {

enum class RecordingFormat { kMillwatchCsv, kDynoWare, kDelimited, kMat, kLcmLog };

/// The format of the file at `path` from its first bytes. @throws std::runtime_error if it
/// cannot be read.
RecordingFormat detect_recording_format(const std::filesystem::path& path);

/// What a format's bad records are, for `count` of them: "lines", "events" (LCM log) or
/// "samples" (.mat); "line", "event", "sample" for one.
[[nodiscard]] const char* record_unit(RecordingFormat format, std::int64_t count = 0);

struct RecordingOptions {
  ColumnMap columns;            ///< which columns or variables (empty: the format's own)
  double config_rate_hz = 0.0;  ///< the rate the configuration states (0: it does not)
  std::string lcm_channel = "MILLWATCH_FORCE_RAW";
  /// A bad row, event or sample: where (line, event or sample number) and what is wrong.
  std::function<void(std::int64_t where, const std::string& problem)> on_bad;
};

class RecordingSource {
 public:
  virtual ~RecordingSource() = default;
  /// The next block of at most `max_samples` samples (LCM logs: as recorded); nothing at the
  /// end. Views stay valid until the next call.
  virtual std::optional<monitor::SampleBlock> next(std::size_t max_samples) = 0;
  /// Bad rows, events or samples skipped so far.
  [[nodiscard]] virtual std::int64_t bad_records() const = 0;
  /// Fraction of the recording read so far, [0, 1].
  [[nodiscard]] virtual double progress() const = 0;
  /// What the recording held, for a user told that it gave no sample: "no rows after its
  /// header", "no event on channel X; the log holds A (12 events)". Asked once next() has
  /// said the recording ended.
  [[nodiscard]] virtual std::string what_it_held() const = 0;
  /// What a user should hear about how the recording ended (empty: nothing), e.g. a text whose
  /// last line has no end-of-line, as a file cut short mid-number has. Asked at its end too.
  [[nodiscard]] virtual std::string end_note() const { return {}; }

  [[nodiscard]] RecordingFormat format() const { return format_; }
  /// "DynoWare export (Time, Fx, Fy, Fz; 10000 Hz stated)", for the log.
  [[nodiscard]] const std::string& description() const { return description_; }
  /// What bad_records() counts: "lines", "events" or "samples".
  [[nodiscard]] const char* record_unit() const { return shell::record_unit(format_); }
  /// The rate the recording is read at: the one it states, else the configuration's, else what
  /// its time shows (LCM logs: the first block's); a stated or configured rate that its time
  /// column belies (beyond 0.1 %) gives way to the time column's.
  [[nodiscard]] double sample_rate_hz() const { return rate_hz_; }
  /// The rate is the file's (stated, or its time column's against a configuration it belies),
  /// and beats the configuration's.
  [[nodiscard]] bool rate_stated() const { return rate_stated_; }

 protected:
  RecordingFormat format_ = RecordingFormat::kMillwatchCsv;
  std::string description_;
  double rate_hz_ = 0.0;
  bool rate_stated_ = false;
};

/// Opens the recording at `path`. @throws std::runtime_error "PATH[:LINE]: ..." if it cannot be
/// read as its format, or a text without a time column has no rate in the configuration.
std::unique_ptr<RecordingSource> open_recording(const std::filesystem::path& path,
                                                const RecordingOptions& options);

}  // namespace millwatch::shell
