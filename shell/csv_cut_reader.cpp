#include "shell/csv_cut_reader.hpp"

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "core/monitor/input_check.hpp"
#include "shell/decimal_number.hpp"
#include "shell/decimal_row.hpp"
#include "shell/out_of_range_number.hpp"

namespace millwatch::shell {
namespace {

constexpr const char* kHeader = "t_s,fx_N,fy_N,fz_N";

/// Parses the row "a,b,c,d" at `p` in place ("nan" and "inf" are numbers, found later as
/// non-finite); on success leaves `p` at the row's '\n'. A '\n' follows `p` before `end`
/// (CsvCutReader::fill), which is where every scan stops.
const char* parse_row(const char*& p, const char* end, double* v) {
  for (int i = 0; i < 4; ++i) {
    while (*p == ' ') {
      ++p;
    }
    const auto r = read_decimal(p, end, v[i]);
    if (r.ec == std::errc::result_out_of_range) {
      v[i] = out_of_range_value(p, r.ptr);  // from_chars leaves v[i] as it was
    } else if (r.ec != std::errc()) {
      return i == 0 ? "t_s is not a number" : "a force is not a number";
    }
    p = r.ptr;
    while (*p == ' ') {
      ++p;
    }
    const bool row_ends = *p == '\n' || (*p == '\r' && p[1] == '\n');
    if (*p != ',' && !row_ends) {  // the cell goes on after its number: "0x10", "1;2"
      if (*p == '\r') {
        return "a carriage return inside the row";
      }
      return i == 0 ? "t_s is not a number" : "a force is not a number";
    }
    if (i < 3) {
      if (row_ends) {
        return "fewer than 4 columns";
      }
      ++p;
    }
  }
  if (*p == '\r') {
    ++p;  // CRLF
  }
  return *p == '\n' ? nullptr : "more than 4 columns";
}

/// The line [from, eol) without one '\r' at its end.
std::string_view line_text(const char* from, const char* eol) {
  if (eol > from && eol[-1] == '\r') {
    --eol;
  }
  return {from, static_cast<std::size_t>(eol - from)};
}

/// Shortest text that reads back as `v`.
std::string number(double v) {
  std::array<char, 32> text{};
  const auto r = std::to_chars(text.data(), text.data() + text.size(), v);
  return {text.data(), r.ptr};
}

std::string at_line(double t_s, std::int64_t line) {
  return number(t_s) + " on line " + std::to_string(line);
}

}  // namespace

CsvCutReader::CsvCutReader(const std::filesystem::path& path, double sample_rate_hz,
                           OnBadLine on_bad_line)
    : sample_rate_hz_(sample_rate_hz),
      on_bad_line_(std::move(on_bad_line)),
      read_bytes_(kDefaultBufferBytes) {
  file_ = std::make_unique<std::ifstream>(path, std::ios::binary);
  if (!*file_) {
    throw std::runtime_error(path.string() + ": cannot read: " + std::strerror(errno));
  }
  in_ = file_.get();
  read_header(path.string());
}

CsvCutReader::CsvCutReader(std::istream& in, const std::string& name, double sample_rate_hz,
                           OnBadLine on_bad_line, std::size_t buffer_bytes)
    : in_(&in),
      sample_rate_hz_(sample_rate_hz),
      on_bad_line_(std::move(on_bad_line)),
      read_bytes_(std::max<std::size_t>(buffer_bytes, 1)) {
  read_header(name);
}

CsvCutReader::CsvCutReader(std::istream& in, const TextLayout& layout, double sample_rate_hz,
                           OnBadLine on_bad_line, std::size_t buffer_bytes)
    : in_(&in),
      layout_(layout),
      sample_rate_hz_(sample_rate_hz),
      on_bad_line_(std::move(on_bad_line)),
      line_(layout.header_lines),
      read_bytes_(std::max<std::size_t>(buffer_bytes, 1)) {
  if (!(sample_rate_hz > 0.0) || !std::isfinite(sample_rate_hz)) {
    throw std::invalid_argument("CsvCutReader: the sample rate must be positive");
  }
}

std::string CsvCutReader::parse_mapped(std::string_view line, double* v) {
  const TextLayout& l = layout_;
  split_fields(line, l.delimiter, fields_);
  if (fields_.size() < static_cast<std::size_t>(l.needed_columns)) {
    return "fewer than " + std::to_string(l.needed_columns) + " columns";
  }
  for (std::size_t q = 0; q < 4; ++q) {
    if (l.column[q] < 0) {  // no time column: the row's place
      v[q] = static_cast<double>(data_rows_ - 1) / sample_rate_hz_;
      continue;
    }
    if (!parse_number(fields_[static_cast<std::size_t>(l.column[q])], l.decimal_comma, v[q])) {
      return l.label[q] + " is not a number";
    }
    v[q] *= l.scale[q];
  }
  return {};
}

void CsvCutReader::read_header(const std::string& name) {
  std::string_view line;
  if (!take_line(line) || line != kHeader) {
    throw std::runtime_error(name + ":1: header is \"" + excerpt(line, 80) + "\"; expected \"" +
                             kHeader + "\"");
  }
}

bool CsvCutReader::fill() {
  if (next_ < lines_end_) {
    return true;
  }
  while (true) {
    // The unfinished line [next_, data_end_) moves to the front; the read goes after it.
    const std::size_t kept = data_end_ - next_;
    if (kept > 0 && next_ > 0) {
      std::memmove(buffer_.data(), buffer_.data() + next_, kept);
    }
    next_ = 0;
    lines_end_ = 0;
    data_end_ = kept;
    // Room for a read and an end-of-line, and for read_decimal_row4() to look that far past.
    const std::size_t needed = kept + read_bytes_ + 1 + kDecimalRowReach;
    if (buffer_.size() < needed) {
      // After a line of up to 4 KiB; a longer line doubles it.
      buffer_.resize(std::max(needed, std::max(2 * buffer_.size(), read_bytes_ + 4096)));
    }
    if (at_end_) {
      if (kept == 0) {
        return false;
      }
      buffer_[data_end_++] = '\n';  // a last line without its end-of-line
      unterminated_ = true;
      lines_end_ = data_end_;
      return true;
    }
    in_->read(buffer_.data() + kept, static_cast<std::streamsize>(read_bytes_));
    const auto n = static_cast<std::size_t>(in_->gcount());
    data_end_ += n;
    at_end_ = n < read_bytes_;
    // The kept bytes hold no '\n': the last one, if any, is in what was just read.
    if (const void* eol = n == 0 ? nullptr : memrchr(buffer_.data() + kept, '\n', n);
        eol != nullptr) {
      lines_end_ = static_cast<std::size_t>(static_cast<const char*>(eol) - buffer_.data()) + 1;
      return true;
    }
  }
}

bool CsvCutReader::take_line(std::string_view& line) {
  if (!fill()) {
    return false;
  }
  const char* from = buffer_.data() + next_;
  // Found: [next_, lines_end_) ends in '\n'.
  const auto* eol = static_cast<const char*>(std::memchr(from, '\n', lines_end_ - next_));
  next_ = static_cast<std::size_t>(eol - buffer_.data()) + 1;
  line = line_text(from, eol);
  return true;
}

void CsvCutReader::bad(std::int64_t line, const std::string& problem) {
  ++bad_lines_;
  if (on_bad_line_) {
    on_bad_line_(line, problem);
  }
}

bool CsvCutReader::parse_next(Row& row) {
  double v[4] = {};
  while (fill()) {
    ++line_;
    std::string_view line;
    if (layout_.format == TextFormat::kMillwatch) {
      const char* from = buffer_.data() + next_;
      const char* p = from;
      // The usual row at once (fill() leaves kDecimalRowReach readable bytes past the data);
      // any other, or a bad one, number by number.
      if (const int length = read_decimal_row4(from, v); length > 0) {
        p = from + length - 1;
      } else if (const char* problem = parse_row(p, buffer_.data() + lines_end_, v);
                 problem != nullptr) {
        take_line(line);
        if (!line.empty()) {  // an empty line is no row
          bad(line_, std::string(problem) + " in \"" + excerpt(line, 60) + "\"");
        }
        continue;
      }
      next_ = static_cast<std::size_t>(p - buffer_.data()) + 1;
      line = line_text(from, p);
    } else {
      take_line(line);
      if (line.empty()) {
        continue;
      }
      ++data_rows_;
      if (const std::string problem = parse_mapped(line, v); !problem.empty()) {
        bad(line_, problem + " in \"" + excerpt(line, 60) + "\"");
        continue;
      }
    }
    if (!std::isfinite(v[0])) {
      const std::string_view time_text =
          layout_.format == TextFormat::kMillwatch
              ? line.substr(0, std::min<std::size_t>(line.find(','), 30))
              : fields_[static_cast<std::size_t>(layout_.column[0])].substr(0, 30);
      bad(line_, layout_.label[0] + " is not finite (" + std::string(time_text) + ")");
      continue;
    }
    // In range: the block's utime (µs) stays within what the pipeline accepts.
    if (!(std::fabs(v[0] * 1e6) <= static_cast<double>(monitor::kMaxAbsUtime_us))) {
      bad(line_, layout_.label[0] + " " + number(v[0]) + " is out of range (more than " +
                     number(static_cast<double>(monitor::kMaxAbsUtime_us) * 1e-6) + " s from 0)");
      continue;
    }
    row.t_s = v[0];
    row.f_N[0] = v[1];
    row.f_N[1] = v[2];
    row.f_N[2] = v[3];
    row.line = line_;
    return true;
  }
  return false;
}

bool CsvCutReader::next_row(Row& row) {
  const double dt_s = 1.0 / sample_rate_hz_;
  while (true) {
    if (have_ahead_) {
      row = ahead_;
      have_ahead_ = false;
    } else if (!parse_next(row)) {
      return false;
    }
    if (have_last_ && !(row.t_s > last_.t_s)) {
      bad(row.line, layout_.label[0] + " " + number(row.t_s) +
                        " is not after the previous row's (" + at_line(last_.t_s, last_.line) +
                        ")");
      continue;
    }
    // A jump ahead (or the first row): a damaged time if the next row comes back before it;
    // a gap in the recording leaves the next row after it.
    if (!have_last_ || row.t_s - last_.t_s > 1.5 * dt_s) {
      Row next;
      if (parse_next(next)) {
        ahead_ = next;
        have_ahead_ = true;
        if (next.t_s < row.t_s && (!have_last_ || next.t_s > last_.t_s)) {
          bad(row.line, layout_.label[0] + " " + number(row.t_s) +
                            " jumps ahead of the rows around it (" +
                            (have_last_ ? at_line(last_.t_s, last_.line) + ", " : "") +
                            at_line(next.t_s, next.line) + ")");
          continue;
        }
      }
    }
    last_ = row;
    have_last_ = true;
    return true;
  }
}

monitor::SampleBlock CsvCutReader::next(std::size_t max_samples) {
  fx_.clear();
  fy_.clear();
  fz_.clear();
  double t0 = 0.0;
  Row row;
  const double dt = 1.0 / sample_rate_hz_;
  while (fx_.size() < max_samples) {
    if (pending_) {
      row = pending_row_;
      pending_ = false;
    } else if (!next_row(row)) {
      break;
    }
    if (fx_.empty()) {
      t0 = row.t_s;
    } else if (std::fabs(row.t_s - (t0 + static_cast<double>(fx_.size()) * dt)) > 0.5 * dt) {
      pending_row_ = row;  // time jumps: this row opens the next block
      pending_ = true;
      break;
    }
    fx_.push_back(row.f_N[0]);
    fy_.push_back(row.f_N[1]);
    fz_.push_back(row.f_N[2]);
  }
  monitor::SampleBlock b;
  b.utime_us = std::llround(t0 * 1e6);  // |t0| ≤ kMaxAbsUtime_us µs: exact, no overflow
  b.seq = seq_++;
  b.sample_rate_hz = sample_rate_hz_;
  b.fx_N = fx_;
  b.fy_N = fy_;
  b.fz_N = fz_;
  return b;
}

}  // namespace millwatch::shell
