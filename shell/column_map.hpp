#pragma once
// Which columns (or MATLAB variables) of a recording hold the time and the three forces:
// `--columns t=Time,fx=Fx,fy=Fy,fz=Fz` on the command line, `"columns"` in a configuration.
//
//   key=SOURCE[*SCALE], comma-separated; keys t (optional), fx, fy, fz, and fs (.mat only: the
//   variable holding the sample rate, Hz). SOURCE is a header name or a 1-based column index
//   (delimited text), or a variable name (.mat: `F(:,1)` a column of a matrix, `F(2,:)` a row,
//   `data.Fx` a field of a struct). SCALE multiplies the values: `fx=Fx_kN*1000` gives N,
//   `t=time_ms*0.001` gives s, `fx=Fx*-1` flips the sign.
//
// In JSON: the same text, or an object {"t": "Time", "fx": 2, "fy": "Fy*1000", ...}.

#include <array>
#include <nlohmann/json.hpp>
#include <string>

namespace millwatch::shell {

struct ColumnSpec {
  std::string source;  ///< header name or variable (empty: by index, or not given)
  int index = 0;       ///< 1-based column index (0: by name)
  double scale = 1.0;
  bool scaled = false;  ///< the map gave the scale ("*k"): a units row's factor does not apply
  [[nodiscard]] bool given() const { return index > 0 || !source.empty(); }
  /// "Fx" or "3", as written in a map.
  [[nodiscard]] std::string describe_source() const;
};

struct ColumnMap {
  /// t, fx, fy, fz, fs in that order.
  static constexpr std::array<const char*, 5> kKeys = {"t", "fx", "fy", "fz", "fs"};
  std::array<ColumnSpec, 5> column{};

  [[nodiscard]] const ColumnSpec& t() const { return column[0]; }
  [[nodiscard]] const ColumnSpec& force(int axis) const {
    return column[static_cast<std::size_t>(1 + axis)];
  }
  [[nodiscard]] const ColumnSpec& fs() const { return column[4]; }
  [[nodiscard]] bool empty() const;
  /// Back to the command-line text.
  [[nodiscard]] std::string to_string() const;
};

/// Parses `--columns` text. @throws std::invalid_argument "columns: ..." naming the entry.
ColumnMap parse_column_map(const std::string& text);
/// Parses the JSON form (text or object). @throws std::invalid_argument naming `path`.
ColumnMap column_map_from_json(const nlohmann::json& j, const std::string& path = "columns");

}  // namespace millwatch::shell
