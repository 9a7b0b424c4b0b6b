#include "shell/csv_cut_reader.hpp"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace millwatch::shell {
namespace {

constexpr const char* kHeader = "t_s,fx_N,fy_N,fz_N";

/// Reads one line without its end-of-line; false at the end of the file.
bool read_line(std::FILE* f, std::string& out) {
  out.clear();
  int c;
  while ((c = std::fgetc(f)) != EOF) {
    if (c == '\n') {
      break;
    }
    out.push_back(static_cast<char>(c));
  }
  if (!out.empty() && out.back() == '\r') {
    out.pop_back();
  }
  return c != EOF || !out.empty();
}

/// Parses "a,b,c,d" into four doubles ("nan" and "inf" are numbers, found later as non-finite).
const char* parse_row(const std::string& s, double* v) {
  const char* p = s.data();
  const char* end = s.data() + s.size();
  for (int i = 0; i < 4; ++i) {
    while (p < end && *p == ' ') {
      ++p;
    }
    const auto r = std::from_chars(p, end, v[i]);
    if (r.ec != std::errc() && r.ec != std::errc::result_out_of_range) {
      return i == 0 ? "t_s is not a number" : "a force is not a number";
    }
    p = r.ptr;
    while (p < end && *p == ' ') {
      ++p;
    }
    if (i < 3) {
      if (p == end || *p != ',') {
        return "fewer than 4 columns";
      }
      ++p;
    }
  }
  return p == end ? nullptr : "more than 4 columns";
}

}  // namespace

CsvCutReader::CsvCutReader(const std::filesystem::path& path, double sample_rate_hz,
                           std::function<void(std::int64_t, const std::string&)> on_bad_line)
    : path_(path), sample_rate_hz_(sample_rate_hz), on_bad_line_(std::move(on_bad_line)) {
  file_ = std::fopen(path.c_str(), "rb");
  if (file_ == nullptr) {
    throw std::runtime_error(path.string() + ": cannot read: " + std::strerror(errno));
  }
  std::string header;
  if (!read_line(file_, header) || header != kHeader) {
    std::fclose(file_);
    file_ = nullptr;
    throw std::runtime_error(path.string() + ":1: header is \"" + header.substr(0, 80) +
                             "\"; expected \"" + kHeader + "\"");
  }
}

CsvCutReader::~CsvCutReader() {
  if (file_ != nullptr) {
    std::fclose(file_);
  }
}

bool CsvCutReader::read_row(double* t, double* fx, double* fy, double* fz) {
  double v[4];
  while (read_line(file_, text_)) {
    ++line_;
    if (text_.empty()) {
      continue;
    }
    if (const char* problem = parse_row(text_, v); problem != nullptr) {
      ++bad_lines_;
      if (on_bad_line_) {
        on_bad_line_(line_, std::string(problem) + " in \"" + text_.substr(0, 60) + "\"");
      }
      continue;
    }
    if (!std::isfinite(v[0])) {
      ++bad_lines_;
      if (on_bad_line_) {
        on_bad_line_(line_, "t_s is not finite");
      }
      continue;
    }
    *t = v[0];
    *fx = v[1];
    *fy = v[2];
    *fz = v[3];
    return true;
  }
  return false;
}

monitor::SampleBlock CsvCutReader::next(std::size_t max_samples) {
  fx_.clear();
  fy_.clear();
  fz_.clear();
  double t0 = 0.0;
  double row[4];
  const double dt = 1.0 / sample_rate_hz_;
  while (fx_.size() < max_samples) {
    if (pending_) {
      std::copy(pending_row_, pending_row_ + 4, row);
      pending_ = false;
    } else if (!read_row(&row[0], &row[1], &row[2], &row[3])) {
      break;
    }
    if (fx_.empty()) {
      t0 = row[0];
    } else if (std::fabs(row[0] - (t0 + static_cast<double>(fx_.size()) * dt)) > 0.5 * dt) {
      std::copy(row, row + 4, pending_row_);  // time jumps: this row opens the next block
      pending_ = true;
      break;
    }
    fx_.push_back(row[1]);
    fy_.push_back(row[2]);
    fz_.push_back(row[3]);
  }
  monitor::SampleBlock b;
  b.utime_us = std::llround(t0 * 1e6);
  b.seq = seq_++;
  b.sample_rate_hz = sample_rate_hz_;
  b.fx_N = fx_;
  b.fy_N = fy_;
  b.fz_N = fz_;
  return b;
}

}  // namespace millwatch::shell
