#pragma once
// What std::from_chars leaves unset: a number out of a double's range ("1e400", "-1e999",
// "1e-400") as the value it stands for. Shared by the CSV and delimited-text readers.

#include <limits>

namespace millwatch::shell {

/// ±infinity, or zero when the exponent is negative, for the characters [first, last) that
/// from_chars reported as out of range.
inline double out_of_range_value(const char* first, const char* last) {
  const bool negative = first < last && *first == '-';
  bool tiny = false;
  for (const char* p = first; p + 1 < last; ++p) {
    if (*p == 'e' || *p == 'E') {
      tiny = p[1] == '-';
    }
  }
  const double magnitude = tiny ? 0.0 : std::numeric_limits<double>::infinity();
  return negative ? -magnitude : magnitude;
}

}  // namespace millwatch::shell
