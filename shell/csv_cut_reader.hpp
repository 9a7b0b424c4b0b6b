#pragma once
// Reads a recorded cut in delimited text into sample blocks: millwatch's CSV (header
// `t_s,fx_N,fy_N,fz_N`, a row per sample), a DynoWare export or any delimited text with a
// column map (shell/text_layout.hpp says how each is recognised). A bad row is reported with its
// line number and skipped; a block ends where the sample times stop following each other at the
// sample rate, so that a skipped row or a jump in time reaches the pipeline as a gap (counted
// there), never as silently shifted samples.
//
// Without a time column, row k (counting the bad ones, so that a bad row is a gap) is at
// k / sample rate.
//
// Bad rows: not four numbers (or, with a column map, a mapped column missing or not a number); a
// time that is not finite, or beyond ±kMaxAbsUtime_us (about ±9.0e9 s); a time not after the
// previous good row's (repeated or going back); a time that jumps ahead of both its neighbours (the
// next row is between the previous good row and it: a damaged time, not a gap in the recording,
// which would leave the next row after it).

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <istream>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "core/monitor/sample_block.hpp"
#include "shell/text_layout.hpp"

namespace millwatch::shell {

class CsvCutReader {
 public:
  /// Called for each bad row with its line number (1-based, the header is line 1) and what is
  /// wrong with it.
  using OnBadLine = std::function<void(std::int64_t line, const std::string& problem)>;

  /// Reads the file at `path`.
  /// @throws std::runtime_error "PATH: cannot read" or "PATH:1: header is ...; expected ...".
  CsvCutReader(const std::filesystem::path& path, double sample_rate_hz, OnBadLine on_bad_line);
  /// Bytes read from the input at a time (a line longer than that grows the buffer).
  static constexpr std::size_t kDefaultBufferBytes = std::size_t{1} << 20;

  /// Reads `in` (which must outlive the reader), named `name` in errors.
  /// @param buffer_bytes bytes read at a time (> 0; the result does not depend on it)
  /// @throws std::runtime_error "NAME:1: header is ...; expected ...".
  CsvCutReader(std::istream& in, const std::string& name, double sample_rate_hz,
               OnBadLine on_bad_line, std::size_t buffer_bytes = kDefaultBufferBytes);
  /// Reads `in` laid out as `layout` (read_text_layout() left it at the first sample row).
  /// @param sample_rate_hz the rate (> 0): the layout's, or the configuration's
  CsvCutReader(std::istream& in, const TextLayout& layout, double sample_rate_hz,
               OnBadLine on_bad_line, std::size_t buffer_bytes = kDefaultBufferBytes);
  CsvCutReader(const CsvCutReader&) = delete;
  CsvCutReader& operator=(const CsvCutReader&) = delete;

  /// The next block of at most `max_samples` (views valid until the next call); an empty block
  /// at the end of the file.
  monitor::SampleBlock next(std::size_t max_samples);
  [[nodiscard]] std::int64_t bad_lines() const { return bad_lines_; }
  [[nodiscard]] std::int64_t lines() const { return line_; }
  /// Whether the file's last line had no end-of-line (read as it stands, but a file cut short
  /// mid-number ends that way too).
  [[nodiscard]] bool last_line_unterminated() const { return unterminated_; }
  [[nodiscard]] const TextLayout& layout() const { return layout_; }

 private:
  struct Row {
    double t_s = 0.0;
    double f_N[3] = {};
    std::int64_t line = 0;
  };

  void read_header(const std::string& name);
  /// Makes [next_, lines_end_) hold at least one whole line, each ending in '\n' (a last line
  /// without one is given it); false at the end of the input.
  bool fill();
  /// Takes the line at next_ (without its end-of-line and one '\r' before it); false at the end.
  bool take_line(std::string_view& line);
  /// The next row of four numbers with a finite time in range; false at the end.
  bool parse_next(Row& row);
  /// The next row whose time is in order; false at the end.
  bool next_row(Row& row);
  void bad(std::int64_t line, const std::string& problem);
  /// A row of layout_ (not millwatch's) into t and forces; the problem, or empty.
  std::string parse_mapped(std::string_view line, double* v);

  std::unique_ptr<std::ifstream> file_;  // when reading a path
  std::istream* in_ = nullptr;
  TextLayout layout_;
  std::int64_t data_rows_ = 0;  // non-empty rows after the header (time of a row without t)
  std::vector<std::string_view> fields_;
  double sample_rate_hz_;
  OnBadLine on_bad_line_;
  std::int64_t line_ = 1;
  std::int64_t bad_lines_ = 0;
  std::int64_t seq_ = 0;
  bool have_last_ = false;  // a row was accepted; last_ is it
  Row last_;
  bool have_ahead_ = false;  // a row read ahead to judge a jump in time
  Row ahead_;
  bool pending_ = false;  // an accepted row that starts the next block
  Row pending_row_;
  std::vector<double> fx_, fy_, fz_;
  // Rows are parsed in place in a large buffer refilled by whole reads: bytes [next_, data_end_)
  // are read and not yet taken, [next_, lines_end_) of them whole lines (lines_end_ follows a
  // '\n'). A line cut by the buffer's end is moved to its front before the next read.
  std::size_t read_bytes_;
  std::vector<char> buffer_;
  std::size_t next_ = 0;
  std::size_t lines_end_ = 0;
  std::size_t data_end_ = 0;
  bool at_end_ = false;        // the input has nothing more to read
  bool unterminated_ = false;  // the last line had no '\n' (one was added)
};

}  // namespace millwatch::shell
