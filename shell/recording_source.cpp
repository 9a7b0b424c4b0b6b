#include "shell/recording_source.hpp"

#include <spdlog/spdlog.h>

#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <utility>
#include <vector>

#include "shell/csv_cut_reader.hpp"
#include "shell/lcm_log_reader.hpp"
#include "shell/mat_cut_reader.hpp"
#include "shell/text_layout.hpp"

namespace millwatch::shell {
namespace {

namespace fs = std::filesystem;

std::string hz(double rate_hz) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g Hz", rate_hz);
  return text;
}

class TextSource : public RecordingSource {
 public:
  TextSource(const fs::path& path, const RecordingOptions& o) : in_(path, std::ios::binary) {
    if (!in_) {
      throw std::runtime_error(path.string() + ": cannot read: " + std::strerror(errno));
    }
    in_.seekg(0, std::ios::end);
    size_bytes_ = static_cast<double>(in_.tellg());
    in_.seekg(0);
    const TextLayout layout = read_text_layout(in_, path.string(), o.columns);
    format_ = layout.format == TextFormat::kMillwatch  ? RecordingFormat::kMillwatchCsv
              : layout.format == TextFormat::kDynoWare ? RecordingFormat::kDynoWare
                                                       : RecordingFormat::kDelimited;
    rate_stated_ = layout.rate_stated;
    double rate = layout.sample_rate_hz;
    // A rate stated or configured that the time column belies (one that puts a row of its
    // leading run more than half a sample off) would drop or misplace samples all through the
    // file: the time column's steps are the samples' own.
    const auto belied = [&](double rate_hz) { return misplaces_rows(layout, rate_hz); };
    if (rate_stated_ && belied(rate)) {
      spdlog::warn(
          "{}: the file states {}, but its time column steps at {}; read at the time "
          "column's",
          path.string(), hz(rate), hz(layout.time_rate_hz));
      rate = layout.time_rate_hz;
    } else if (!rate_stated_ && o.config_rate_hz > 0.0) {
      if (belied(o.config_rate_hz)) {
        rate = layout.time_rate_hz;
        rate_stated_ = true;  // the time column's rate beats the configuration's (said there)
      } else {
        rate = o.config_rate_hz;  // exact, where the printed times are rounded
      }
    }
    if (!(rate > 0.0)) {
      throw std::runtime_error(path.string() + ": " +
                               (layout.column[0] < 0 ? "no time column" : "no usable time column") +
                               " and no sample rate: state sample_rate_hz in --config (or in "
                               "the sidecar)");
    }
    rate_hz_ = rate;
    description_ = std::string(to_string(layout.format));
    if (layout.format != TextFormat::kMillwatch) {
      description_ +=
          " (t " + (layout.column[0] >= 0 ? layout.label[0] : std::string("from the row number")) +
          ", fx " + layout.label[1] + ", fy " + layout.label[2] + ", fz " + layout.label[3] + ")";
    }
    if (layout.rate_stated) {
      description_ += ", " + hz(layout.sample_rate_hz) + " stated";
    }
    reader_ = std::make_unique<CsvCutReader>(in_, layout, rate, o.on_bad);
  }
  std::optional<monitor::SampleBlock> next(std::size_t max_samples) override {
    const monitor::SampleBlock b = reader_->next(max_samples);
    rows_ += static_cast<std::int64_t>(b.fx_N.size());
    return b.fx_N.empty() ? std::nullopt : std::optional(b);
  }
  [[nodiscard]] std::int64_t bad_records() const override { return reader_->bad_lines(); }
  [[nodiscard]] std::string what_it_held() const override {
    if (rows_ + bad_records() == 0) {
      return "no rows after its header";
    }
    return std::to_string(rows_) + " rows read, " + std::to_string(bad_records()) + " bad";
  }
  [[nodiscard]] std::string end_note() const override {
    if (!reader_->last_line_unterminated()) {
      return {};
    }
    return "line " + std::to_string(reader_->lines()) +
           ", the last, has no end-of-line: if the file was cut short there, its last number may "
           "be too (the row was read as it stands, unless named bad above)";
  }
  [[nodiscard]] double progress() const override {
    const auto at = in_.tellg();
    return at < 0 || size_bytes_ <= 0 ? 1.0 : static_cast<double>(at) / size_bytes_;
  }

 private:
  mutable std::ifstream in_;  // tellg() is not const
  double size_bytes_ = 0.0;
  std::unique_ptr<CsvCutReader> reader_;
  std::int64_t rows_ = 0;  // samples read
};

class MatSource : public RecordingSource {
 public:
  MatSource(const fs::path& path, const RecordingOptions& o)
      : reader_(path, o.columns, o.config_rate_hz, o.on_bad) {
    format_ = RecordingFormat::kMat;
    rate_hz_ = reader_.sample_rate_hz();
    rate_stated_ = reader_.rate_stated();
    description_ = "MATLAB " + reader_.version() + " .mat (" + reader_.variables() + ")";
    if (rate_stated_) {
      description_ += ", " + hz(rate_hz_) + " stated";
    }
  }
  std::optional<monitor::SampleBlock> next(std::size_t max_samples) override {
    const monitor::SampleBlock b = reader_.next(max_samples);
    return b.fx_N.empty() ? std::nullopt : std::optional(b);
  }
  [[nodiscard]] std::int64_t bad_records() const override { return reader_.bad_samples(); }
  [[nodiscard]] double progress() const override { return reader_.progress(); }
  [[nodiscard]] std::string what_it_held() const override {
    if (reader_.samples() == 0) {
      return "no samples in its variables";
    }
    return std::to_string(reader_.samples()) + " samples, " +
           std::to_string(reader_.bad_samples()) + " bad";
  }

 private:
  MatCutReader reader_;
};

class LogSource : public RecordingSource {
 public:
  LogSource(const fs::path& path, const RecordingOptions& o)
      : reader_(path, o.lcm_channel, o.on_bad), channel_(o.lcm_channel) {
    format_ = RecordingFormat::kLcmLog;
    first_ = reader_.next();  // to learn the rate
    rate_hz_ = reader_.first_sample_rate_hz();
    description_ = "LCM log (channel " + o.lcm_channel + ")";
  }
  std::optional<monitor::SampleBlock> next(std::size_t /*max_samples*/) override {
    if (first_) {
      return std::exchange(first_, std::nullopt);
    }
    return reader_.next();
  }
  [[nodiscard]] std::int64_t bad_records() const override { return reader_.bad_events(); }
  [[nodiscard]] double progress() const override { return reader_.progress(); }
  [[nodiscard]] std::string what_it_held() const override {
    const auto& tally = reader_.channel_events();
    if (tally.empty()) {
      return "the log holds no event";
    }
    if (const auto own = tally.find(channel_); own != tally.end()) {
      return "its " + events(own->second) + " on " + channel_ + " hold no samples";
    }
    std::string held;
    for (const auto& [name, count] : tally) {
      held += (held.empty() ? "" : ", ") + name + " (" + events(count) + ")";
    }
    if (reader_.events_untallied() > 0) {
      held += " and " + events(reader_.events_untallied()) + " on further channels";
    }
    return "no event on channel " + channel_ + "; the log holds " + held;
  }

 private:
  static std::string events(std::int64_t n) {
    return std::to_string(n) + (n == 1 ? " event" : " events");
  }
  LcmLogReader reader_;
  std::string channel_;
  std::optional<monitor::SampleBlock> first_;
};

}  // namespace

const char* record_unit(RecordingFormat format, std::int64_t count) {
  const bool one = count == 1;
  switch (format) {
    case RecordingFormat::kLcmLog:
      return one ? "event" : "events";
    case RecordingFormat::kMat:
      return one ? "sample" : "samples";
    default:
      return one ? "line" : "lines";
  }
}

RecordingFormat detect_recording_format(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw std::runtime_error(path.string() + ": cannot read: " + std::strerror(errno));
  }
  std::array<char, 520> head{};
  in.read(head.data(), head.size());
  const auto n = static_cast<std::size_t>(in.gcount());
  const std::string_view s(head.data(), n);
  if (s.substr(0, 4) == std::string_view("\xED\xA1\xDA\x01", 4)) {
    return RecordingFormat::kLcmLog;
  }
  // v5 and v7.3 open with a 116-byte text header; v7.3 is HDF5 behind a 512-byte user block.
  if (s.substr(0, 6) == "MATLAB" || s.substr(0, 8) == "\x89HDF\r\n\x1A\n" ||
      (n >= 520 && s.substr(512, 8) == "\x89HDF\r\n\x1A\n")) {
    return RecordingFormat::kMat;
  }
  if (path.extension() == ".mat" && s.find('\0') != std::string_view::npos) {
    return RecordingFormat::kMat;  // v4: a binary header, no text
  }
  return RecordingFormat::kDelimited;  // text: which kind, read_text_layout says
}

std::unique_ptr<RecordingSource> open_recording(const fs::path& path,
                                                const RecordingOptions& options) {
  switch (detect_recording_format(path)) {
    case RecordingFormat::kLcmLog:
      return std::make_unique<LogSource>(path, options);
    case RecordingFormat::kMat:
      return std::make_unique<MatSource>(path, options);
    default:
      return std::make_unique<TextSource>(path, options);
  }
}

}  // namespace millwatch::shell
