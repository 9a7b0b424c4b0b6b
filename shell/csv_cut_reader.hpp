#pragma once
// Reads a recorded cut's CSV (header `t_s,fx_N,fy_N,fz_N`, a row per sample) into sample
// blocks. A bad row is reported with its line number and skipped; a block ends where the
// sample times stop following each other at the sample rate, so that a skipped row or a jump
// in time reaches the pipeline as a gap (counted there), never as silently shifted samples.

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "core/monitor/sample_block.hpp"

namespace millwatch::shell {

class CsvCutReader {
 public:
  /// @throws std::runtime_error "PATH: cannot read" or "PATH:1: header is ...; expected ...".
  CsvCutReader(const std::filesystem::path& path, double sample_rate_hz,
               std::function<void(std::int64_t line, const std::string& problem)> on_bad_line);
  ~CsvCutReader();
  CsvCutReader(const CsvCutReader&) = delete;
  CsvCutReader& operator=(const CsvCutReader&) = delete;

  /// The next block of at most `max_samples` (views valid until the next call); an empty block
  /// at the end of the file.
  monitor::SampleBlock next(std::size_t max_samples);
  [[nodiscard]] std::int64_t bad_lines() const { return bad_lines_; }
  [[nodiscard]] std::int64_t lines() const { return line_; }

 private:
  bool read_row(double* t, double* fx, double* fy, double* fz);

  std::filesystem::path path_;
  std::FILE* file_ = nullptr;
  double sample_rate_hz_;
  std::function<void(std::int64_t, const std::string&)> on_bad_line_;
  std::int64_t line_ = 1;
  std::int64_t bad_lines_ = 0;
  std::int64_t seq_ = 0;
  bool pending_ = false;  // a row read ahead that starts the next block
  double pending_row_[4] = {};
  std::vector<double> fx_, fy_, fz_;
  std::string text_;
};

}  // namespace millwatch::shell
