#pragma once
// The layout of a recording in delimited text, found from its content (never its name):
//
//   millwatch CSV   the header `t_s,fx_N,fy_N,fz_N` (what `millwatch simulate` writes)
//   DynoWare        a Kistler DynoWare export (File → Export): a preamble of `key:,value` lines
//                   opened by `DynoWare,Version ...` (`Sampling rate [Hz]:,10000`, ...), a row
//                   of channel names (`Time,Fx,Fy,Fz[,Mz...]`), a row of units (`s,N,N,N`), then
//                   the samples. Time, Fx, Fy, Fz are found by name; units N, kN, mN and s, ms, µs
//                   are converted to N and s.
//   delimited       anything else with a column map (ColumnMap): a header row of names, or no
//                   header (columns by index); comma, semicolon, tab or blank separated (with
//                   semicolons or tabs, a decimal comma is read as a point); a units row (no
//                   number in it) after the header is skipped.
//
// The sample rate: DynoWare states it; otherwise a time column gives it (estimated from its
// first rows); without a time column it has to come from the configuration.

#include <array>
#include <cstdint>
#include <istream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "shell/column_map.hpp"

namespace millwatch::shell {

enum class TextFormat { kMillwatch, kDynoWare, kDelimited };

std::string_view to_string(TextFormat f);

struct TextLayout {
  TextFormat format = TextFormat::kMillwatch;
  char delimiter = ',';  ///< ' ': runs of blanks and tabs
  bool decimal_comma = false;
  /// 0-based column of t, fx, fy, fz; t = -1: no time column (t = row / sample rate).
  std::array<int, 4> column = {0, 1, 2, 3};
  std::array<double, 4> scale = {1.0, 1.0, 1.0, 1.0};
  /// How messages name the four quantities: `Fx (column 2)`.
  std::array<std::string, 4> label = {"t_s", "fx_N", "fy_N", "fz_N"};
  int needed_columns = 4;         ///< a row with fewer is bad
  std::int64_t header_lines = 1;  ///< lines before the first sample
  double sample_rate_hz = 0.0;    ///< stated by the file or estimated from its time (0: none)
  bool rate_stated = false;       ///< stated (DynoWare's preamble), not estimated
  /// The time column's rate over its leading run of rows without a gap (0: none, or fewer
  /// than 200 rows), and those rows' times (s): what can belie a stated or configured rate.
  double time_rate_hz = 0.0;
  std::vector<double> lead_times_s;
  std::vector<std::string> channels;                          ///< the header's names
  std::vector<std::pair<std::string, std::string>> preamble;  ///< DynoWare's `key:` lines
};

/// Reads the layout from the start of `in` and leaves `in` at the first sample row.
/// @throws std::runtime_error "NAME:LINE: ..." for a text that is none of the above, a column
/// the map names but the header lacks, a DynoWare export without its channel row.
TextLayout read_text_layout(std::istream& in, const std::string& name, const ColumnMap& columns);

/// Whether reading at `rate_hz` would put a row of the time column's leading run more than half
/// a sample off its time (the reader would then break the run into gaps or reject its blocks).
bool misplaces_rows(const TextLayout& l, double rate_hz);

/// Splits a row at `delimiter` (' ': runs of blanks) into trimmed fields without quotes.
void split_fields(std::string_view line, char delimiter, std::vector<std::string_view>& out);

/// Parses one field as a number ("nan", "inf" are numbers; out of a double's range: ±inf or 0);
/// a decimal comma is read as a point when `decimal_comma`. False: not a number.
bool parse_number(std::string_view field, bool decimal_comma, double& value);

/// At most `max_bytes` of a line as a message quotes it: control bytes (a binary file's, an
/// escape sequence's) as \xNN, so that an error never writes them to the user's terminal; cut
/// before a UTF-8 character that would not fit whole.
std::string excerpt(std::string_view line, std::size_t max_bytes);

}  // namespace millwatch::shell
