#pragma once
// Reads a recorded cut from a MATLAB .mat file (v5 — compressed or not — and v7.3/HDF5,
// through Debian's libmatio, after shell/mat_file_check.hpp found its structure sound) into
// sample blocks.
//
// The forces are three vectors or one N×3 (or 3×N) matrix, the time an optional vector and the
// sample rate an optional scalar. A ColumnMap names them (`fx=Fx,fy=Fy,fz=Fz,t=t,fs=fs`;
// `fx=F(:,1)` a matrix column, `fx=data.Fx` a struct field); without one they are found by
// their usual names (case-insensitive): fx/fy/fz (or force_x...), a matrix F/force/forces/data
// with a dimension of 3, t/time/t_s, fs/sample_rate_hz/sampling_rate/rate.
//
// Numeric classes (double, single, integers) are read as doubles times the column's scale.
// With a time vector, samples whose time is not finite, out of range or not after the
// previous sample's are reported by index (`t(1234)`) and skipped, and a jump in time starts
// a new block (a gap for the pipeline). Non-finite forces pass on to the pipeline's input
// check, which flags and counts them.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "core/monitor/sample_block.hpp"
#include "shell/column_map.hpp"

namespace millwatch::shell {

class MatCutReader {
 public:
  /// Called for each skipped sample with its 1-based index and what is wrong.
  using OnBadSample = std::function<void(std::int64_t sample, const std::string& problem)>;
  /// Variables larger than this are refused (a damaged header must not make us allocate).
  static constexpr std::int64_t kDefaultMaxElements = std::int64_t{1} << 28;

  /// Reads the variables. @param config_rate_hz the configuration's rate (0: not stated), used
  /// when the file has no rate variable. @throws std::runtime_error "PATH: ..." naming the
  /// variable that is missing, of the wrong shape or class, or too large.
  MatCutReader(const std::filesystem::path& path, const ColumnMap& columns, double config_rate_hz,
               OnBadSample on_bad_sample, std::int64_t max_elements = kDefaultMaxElements);

  /// The next block of at most `max_samples` (views valid until the next call); empty at the
  /// end.
  monitor::SampleBlock next(std::size_t max_samples);

  [[nodiscard]] double sample_rate_hz() const { return rate_hz_; }
  /// The rate came from a variable of the file (not the time vector or the configuration).
  [[nodiscard]] bool rate_stated() const { return rate_stated_; }
  [[nodiscard]] const std::string& version() const { return version_; }
  /// Which variables were read, e.g. "fx=F(:,1) fy=F(:,2) fz=F(:,3) fs=fs".
  [[nodiscard]] const std::string& variables() const { return variables_; }
  [[nodiscard]] std::int64_t samples() const { return static_cast<std::int64_t>(f_[0].size()); }
  [[nodiscard]] std::int64_t bad_samples() const { return bad_samples_; }
  [[nodiscard]] double progress() const {
    return f_[0].empty() ? 1.0 : static_cast<double>(next_) / static_cast<double>(f_[0].size());
  }

 private:
  bool time_ok(std::size_t k);

  std::string name_;
  OnBadSample on_bad_;
  std::vector<double> f_[3];
  std::vector<double> t_;  // empty: no time vector
  double rate_hz_ = 0.0;
  bool rate_stated_ = false;
  std::string version_;
  std::string variables_;
  std::size_t next_ = 0;
  bool checked_ = false;  // sample next_ passed time_ok() already
  bool have_last_ = false;
  double last_t_ = 0.0;
  std::int64_t last_index_ = 0;
  std::int64_t bad_samples_ = 0;
  std::int64_t seq_ = 0;
  std::vector<double> fx_, fy_, fz_;
};

}  // namespace millwatch::shell
