#include "shell/text_layout.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "shell/decimal_number.hpp"
#include "shell/out_of_range_number.hpp"

namespace millwatch::shell {
namespace {

constexpr std::string_view kMillwatchHeader = "t_s,fx_N,fy_N,fz_N";
constexpr int kMaxPreambleLines = 200;
constexpr int kRateRows = 2000;  // rows read ahead to estimate the rate from a time column
// Rows without a gap from the start it takes for the time column to belie a stated or
// configured rate (fewer: too little of the record to tell).
constexpr std::size_t kLeastBeliefRows = 200;

std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

bool starts_with_ci(std::string_view s, std::string_view prefix) {
  return s.size() >= prefix.size() && lower(s.substr(0, prefix.size())) == lower(prefix);
}

/// Reads a line without its end of line; false at the end.
bool get_line(std::istream& in, std::string& line) {
  line.clear();
  if (!std::getline(in, line)) {
    return false;
  }
  if (!line.empty() && line.back() == '\r') {
    line.pop_back();
  }
  return true;
}

char detect_delimiter(std::string_view line) {
  const auto commas = std::count(line.begin(), line.end(), ',');
  const auto semicolons = std::count(line.begin(), line.end(), ';');
  const auto tabs = std::count(line.begin(), line.end(), '\t');
  if (commas == 0 && semicolons == 0 && tabs == 0) {
    return ' ';
  }
  if (semicolons >= commas && semicolons >= tabs) {
    return ';';
  }
  return tabs > commas ? '\t' : ',';
}

bool all_numbers(const std::vector<std::string_view>& fields, bool decimal_comma) {
  double v = 0.0;
  return !fields.empty() && std::all_of(fields.begin(), fields.end(), [&](std::string_view f) {
    return parse_number(f, decimal_comma, v);
  });
}

bool any_number(const std::vector<std::string_view>& fields, bool decimal_comma) {
  double v = 0.0;
  return std::any_of(fields.begin(), fields.end(),
                     [&](std::string_view f) { return parse_number(f, decimal_comma, v); });
}

/// "Fx [N]" → "fx": a channel name without a bracketed unit, lower case.
std::string bare_name(std::string_view name) {
  const auto bracket = name.find_first_of("[(");
  std::string_view s = name.substr(0, bracket);
  while (!s.empty() && s.back() == ' ') {
    s.remove_suffix(1);
  }
  return lower(s);
}

/// Factor from a unit to N (forces) or s (time); 1 for units it does not know.
double unit_factor(std::string_view unit, bool time) {
  const std::string u = lower(unit);
  if (time) {
    if (u == "ms") {
      return 1e-3;
    }
    if (u == "us" || u == "\xC2\xB5s" || u == "\xCE\xBCs") {
      return 1e-6;
    }
    return 1.0;
  }
  if (u == "kn") {
    return 1e3;
  }
  if (u == "mn") {
    return 1e-3;
  }
  return 1.0;
}

std::string join(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) {
    if (!s.empty()) {
      s += ", ";
    }
    s += n;
    if (s.size() > 200) {
      return s + ", ...";
    }
  }
  return s;
}

/// Resolves a ColumnSpec against the header (-1: not found).
int resolve(const ColumnSpec& spec, const std::vector<std::string>& header) {
  if (spec.index > 0) {
    return spec.index - 1;
  }
  for (std::size_t i = 0; i < header.size(); ++i) {
    if (header[i] == spec.source) {
      return static_cast<int>(i);
    }
  }
  const std::string want = lower(spec.source);
  for (std::size_t i = 0; i < header.size(); ++i) {
    if (lower(header[i]) == want) {
      return static_cast<int>(i);
    }
  }
  return -1;
}

/// The column map applied to a header: columns, scales, labels, needed columns.
void apply_map(TextLayout& l, const ColumnMap& map, const std::string& name,
               std::int64_t header_line) {
  for (std::size_t q = 0; q < 4; ++q) {
    const ColumnSpec& spec = map.column[q];
    if (!spec.given()) {
      l.column[q] = -1;  // only t may be absent (ColumnMap checks the forces)
      continue;
    }
    const int c = resolve(spec, l.channels);
    if (c < 0) {
      if (l.channels.empty()) {
        throw std::runtime_error(name + ": no header row: name the columns by their index (" +
                                 std::string(ColumnMap::kKeys[q]) + "=2, ...)");
      }
      throw std::runtime_error(name + ":" + std::to_string(header_line) + ": no column \"" +
                               spec.source + "\" for " + ColumnMap::kKeys[q] +
                               " (columns: " + excerpt(join(l.channels), 200) + ")");
    }
    if (!l.channels.empty() && static_cast<std::size_t>(c) >= l.channels.size()) {
      // An index past the header: said once here, not as every row being short of columns.
      throw std::runtime_error(name + ":" + std::to_string(header_line) + ": no column " +
                               std::to_string(c + 1) + " for " + ColumnMap::kKeys[q] +
                               " (the header has " + std::to_string(l.channels.size()) + ": " +
                               excerpt(join(l.channels), 200) + ")");
    }
    for (std::size_t earlier = 0; earlier < q; ++earlier) {
      if (l.column[earlier] == c) {  // by name and by index, or two names of one column
        throw std::runtime_error(name + ": columns: " + ColumnMap::kKeys[earlier] + " and " +
                                 ColumnMap::kKeys[q] + " both read " + l.label[earlier] +
                                 " (each needs its own column)");
      }
    }
    l.column[q] = c;
    l.scale[q] = spec.scale;
    const auto uc = static_cast<std::size_t>(c);
    l.label[q] = (uc < l.channels.size() ? l.channels[uc] + " (column " : "(column ") +
                 std::to_string(c + 1) + ")";
  }
  if (map.fs().given()) {
    throw std::runtime_error(name +
                             ": columns: fs names a .mat variable; a text file's rate "
                             "comes from its time column or the configuration");
  }
  l.needed_columns = 1 + *std::max_element(l.column.begin(), l.column.end());
}

/// DynoWare's preamble, from its first line; leaves `in` after the channel row.
void read_dynoware(std::istream& in, const std::string& name, const std::string& first,
                   TextLayout& l, std::int64_t& line_no) {
  l.format = TextFormat::kDynoWare;
  std::string line = first;
  std::vector<std::string_view> fields;
  while (true) {
    if (line_no > kMaxPreambleLines) {
      throw std::runtime_error(name +
                               ": a DynoWare preamble without its channel row in the first " +
                               std::to_string(kMaxPreambleLines) + " lines");
    }
    if (!line.empty()) {
      const char d = detect_delimiter(line);
      split_fields(line, d, fields);
      const bool preamble =
          line_no == 1 || (!fields.empty() && !fields[0].empty() && fields[0].back() == ':');
      if (!preamble) {
        l.delimiter = d;
        break;  // the channel row
      }
      const std::string key(fields.empty() ? std::string_view() : fields[0]);
      std::string value;
      for (std::size_t i = 1; i < fields.size(); ++i) {
        if (i > 1) {
          value += ' ';
        }
        value += fields[i];
      }
      l.preamble.emplace_back(key, value);
      double rate = 0.0;
      if (starts_with_ci(key, "sampling rate") && fields.size() > 1 &&
          parse_number(fields[1], d != ',', rate) && std::isfinite(rate) && rate > 0.0) {
        l.sample_rate_hz = lower(key).find("khz") != std::string::npos ? rate * 1e3 : rate;
        l.rate_stated = true;
      }
    }
    if (!get_line(in, line)) {
      throw std::runtime_error(name + ": a DynoWare export that ends before its channel row");
    }
    ++line_no;
  }
  l.decimal_comma = l.delimiter != ',';
  for (auto f : fields) {
    l.channels.emplace_back(f);
  }
}

/// Rate from the time column: the first rows read ahead, then `in` goes back. Also keeps, in
/// l.lead_times_s, the leading run of the times without a gap (every step positive and under
/// 1.9 medians: printed times rounded to half a step still count), and from it, where it is
/// long enough to belie a rate, l.time_rate_hz.
double estimate_rate(std::istream& in, TextLayout& l) {
  const std::streampos start = in.tellg();
  if (start < 0) {
    return 0.0;
  }
  std::string line;
  std::vector<std::string_view> fields;
  std::vector<double> t;
  const auto tc = static_cast<std::size_t>(l.column[0]);
  for (int n = 0; n < kRateRows && get_line(in, line); ++n) {
    split_fields(line, l.delimiter, fields);
    double v = 0.0;
    if (fields.size() > tc && parse_number(fields[tc], l.decimal_comma, v) && std::isfinite(v)) {
      t.push_back(v * l.scale[0]);
    }
  }
  in.clear();
  in.seekg(start);
  if (t.size() < 2) {
    return 0.0;
  }
  std::vector<double> dt;
  for (std::size_t i = 1; i < t.size(); ++i) {
    if (t[i] > t[i - 1]) {
      dt.push_back(t[i] - t[i - 1]);
    }
  }
  if (dt.empty()) {
    return 0.0;
  }
  std::nth_element(dt.begin(), dt.begin() + static_cast<std::ptrdiff_t>(dt.size() / 2), dt.end());
  const double median = dt[dt.size() / 2];
  std::size_t run = 1;
  while (run < t.size() && t[run] > t[run - 1] && t[run] - t[run - 1] < 1.9 * median) {
    ++run;
  }
  l.lead_times_s.assign(t.begin(), t.begin() + static_cast<std::ptrdiff_t>(run));
  l.time_rate_hz =
      run >= kLeastBeliefRows ? static_cast<double>(run - 1) / (t[run - 1] - t[0]) : 0.0;
  // Over the longest run of steady steps from the start: printed times are rounded.
  std::size_t k = 1;
  while (k < t.size() && t[k] - t[k - 1] > 0.5 * median && t[k] - t[k - 1] < 1.5 * median) {
    ++k;
  }
  const double rate = static_cast<double>(k - 1) / (t[k - 1] - t[0]);
  return k > 2 && std::isfinite(rate) && rate > 0.0 ? rate : 1.0 / median;
}

}  // namespace

std::string_view to_string(TextFormat f) {
  switch (f) {
    case TextFormat::kMillwatch:
      return "millwatch CSV";
    case TextFormat::kDynoWare:
      return "DynoWare export";
    case TextFormat::kDelimited:
      return "delimited text";
  }
  return "text";
}

void split_fields(std::string_view line, char delimiter, std::vector<std::string_view>& out) {
  out.clear();
  auto clean = [](std::string_view f) {
    while (!f.empty() && (f.front() == ' ' || f.front() == '\t')) {
      f.remove_prefix(1);
    }
    while (!f.empty() && (f.back() == ' ' || f.back() == '\t')) {
      f.remove_suffix(1);
    }
    if (f.size() >= 2 && f.front() == '"' && f.back() == '"') {
      f = f.substr(1, f.size() - 2);
    }
    return f;
  };
  if (delimiter == ' ') {
    std::size_t i = 0;
    while (i < line.size()) {
      while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) {
        ++i;
      }
      const std::size_t from = i;
      while (i < line.size() && line[i] != ' ' && line[i] != '\t') {
        ++i;
      }
      if (i > from) {
        out.push_back(clean(line.substr(from, i - from)));
      }
    }
    return;
  }
  std::size_t from = 0;
  while (true) {
    const std::size_t to = line.find(delimiter, from);
    out.push_back(clean(line.substr(from, to == std::string_view::npos ? line.npos : to - from)));
    if (to == std::string_view::npos) {
      return;
    }
    from = to + 1;
  }
}

bool parse_number(std::string_view field, bool decimal_comma, double& value) {
  char buffer[64];
  if (decimal_comma && field.find(',') != std::string_view::npos) {
    if (field.size() >= sizeof buffer) {
      return false;
    }
    std::copy(field.begin(), field.end(), buffer);
    std::replace(buffer, buffer + field.size(), ',', '.');
    field = std::string_view(buffer, field.size());
  }
  const char* first = field.data();
  const char* last = field.data() + field.size();
  if (first != last && *first == '+') {
    ++first;
  }
  if (first == last) {
    return false;
  }
  const auto r = read_decimal(first, last, value);
  if (r.ec == std::errc::result_out_of_range) {
    value = out_of_range_value(first, r.ptr);
  } else if (r.ec != std::errc()) {
    return false;
  }
  return r.ptr == last;
}

TextLayout read_text_layout(std::istream& in, const std::string& name, const ColumnMap& map) {
  TextLayout l;
  std::string first;
  std::int64_t line_no = 1;
  if (!get_line(in, first)) {
    throw std::runtime_error(name + ":1: the file is empty");
  }
  if (first.rfind("\xEF\xBB\xBF", 0) == 0) {
    first.erase(0, 3);  // a UTF-8 byte-order mark
  }
  std::vector<std::string_view> fields;
  if (map.empty() && first == kMillwatchHeader) {
    l.sample_rate_hz = estimate_rate(in, l);  // millwatch's own CSV
    return l;
  }
  const std::string_view opening =
      std::string_view(first).substr(!first.empty() && first.front() == '"' ? 1 : 0);
  if (starts_with_ci(opening, "DynoWare")) {
    read_dynoware(in, name, first, l, line_no);
    ColumnMap dyno = map;
    if (map.empty()) {
      // Time, Fx, Fy, Fz by name, with or without a bracketed unit.
      const std::array<std::string, 4> wanted = {"time", "fx", "fy", "fz"};
      for (std::size_t q = 0; q < 4; ++q) {
        for (std::size_t i = 0; i < l.channels.size(); ++i) {
          if (bare_name(l.channels[i]) == wanted[q] ||
              (q == 0 && bare_name(l.channels[i]) == "t")) {
            dyno.column[q].index = static_cast<int>(i) + 1;
            break;
          }
        }
        if (q > 0 && !dyno.column[q].given()) {
          throw std::runtime_error(
              name + ":" + std::to_string(line_no) + ": a DynoWare export without a channel " +
              (q == 1   ? "Fx"
               : q == 2 ? "Fy"
                        : "Fz") +
              " (channels: " + excerpt(join(l.channels), 200) + "); name them with --columns");
        }
      }
    }
    apply_map(l, dyno, name, line_no);
    l.header_lines = line_no;
  } else {
    if (map.empty()) {
      throw std::runtime_error(
          name + ":1: header is \"" + excerpt(first, 80) + "\"; expected \"" +
          std::string(kMillwatchHeader) +
          "\" (millwatch's CSV), a DynoWare export, or a column map: --columns "
          "t=Time,fx=Fx,fy=Fy,fz=Fz (header names or 1-based indices; without a time column, "
          "sample_rate_hz in --config)");
    }
    l.format = TextFormat::kDelimited;
    l.delimiter = detect_delimiter(first);
    l.decimal_comma = l.delimiter != ',';
    split_fields(first, l.delimiter, fields);
    if (all_numbers(fields, l.decimal_comma)) {
      l.header_lines = 0;  // no header: the first line is a sample
      in.clear();
      in.seekg(0);
    } else {
      for (auto f : fields) {
        l.channels.emplace_back(f);
      }
      l.header_lines = 1;
    }
    apply_map(l, map, name, 1);
  }
  // A units row after the channel names: no number in it.
  if (!l.channels.empty()) {
    const std::streampos after_header = in.tellg();
    std::string units;
    if (after_header >= 0 && get_line(in, units)) {
      split_fields(units, l.delimiter, fields);
      if (!units.empty() && !any_number(fields, l.decimal_comma)) {
        ++l.header_lines;
        for (std::size_t q = 0; q < 4; ++q) {
          const int c = l.column[q];
          // A scale the map gave is the whole conversion (t=time_ms*0.001 over a "ms" unit
          // had been converted twice: a rate of 50 MHz).
          if (c >= 0 && static_cast<std::size_t>(c) < fields.size() && !map.column[q].scaled) {
            l.scale[q] *= unit_factor(fields[static_cast<std::size_t>(c)], q == 0);
          }
        }
      } else {
        in.clear();
        in.seekg(after_header);
      }
    }
  }
  if (l.column[0] >= 0) {
    const double estimated = estimate_rate(in, l);
    if (!l.rate_stated) {
      l.sample_rate_hz = estimated;
    }
  }
  return l;
}

bool misplaces_rows(const TextLayout& l, double rate_hz) {
  if (l.time_rate_hz <= 0.0 || !(rate_hz > 0.0)) {
    return false;
  }
  // The reader's own test: a row more than half a sample off where the rate puts it opens a
  // new block (a gap, or a block "older than expected").
  const std::vector<double>& t = l.lead_times_s;
  for (std::size_t i = 1; i < t.size(); ++i) {
    if (std::fabs(t[i] - t[0] - static_cast<double>(i) / rate_hz) > 0.5 / rate_hz) {
      return true;
    }
  }
  return false;
}

std::string excerpt(std::string_view line, std::size_t max_bytes) {
  // Cut before a UTF-8 character that would not fit whole: back over its continuation bytes
  // (10xxxxxx, at most 3) onto its lead byte (11xxxxxx). Other bytes (a binary file's, Latin-1
  // text's) are cut where they stand.
  std::size_t n = std::min(max_bytes, line.size());
  const auto top_bits = [&](std::size_t i) { return static_cast<unsigned char>(line[i]) & 0xC0U; };
  if (n < line.size() && top_bits(n) == 0x80U) {
    std::size_t lead = n;
    while (lead > 0 && n - lead < 3 && top_bits(lead) == 0x80U) {
      --lead;
    }
    if (top_bits(lead) == 0xC0U) {
      n = lead;
    }
  }
  std::string out;
  for (const char c : line.substr(0, n)) {
    const auto byte = static_cast<unsigned char>(c);
    if ((byte < 0x20 && c != '\t') || byte == 0x7f) {
      constexpr std::string_view kHex = "0123456789abcdef";
      out += "\\x";
      out += kHex[byte >> 4U];
      out += kHex[byte & 15U];
    } else {
      out += c;
    }
  }
  return out;
}

}  // namespace millwatch::shell
