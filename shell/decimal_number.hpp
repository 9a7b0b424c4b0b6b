#pragma once
// Reading a decimal number from text fast: the plain decimals that recordings hold
// ("-0.142822", "12", "0.000020000") by Clinger's exact fast path (an integer mantissa below 2⁵³
// and at most 22 decimals: one correctly rounded division by an exact power of ten, so the same
// double as std::from_chars), anything else (exponents, long mantissas, nan, inf) by
// std::from_chars.

#include <charconv>
#include <cstdint>

namespace millwatch::shell {

namespace detail {

/// 10^k, exact in a double for k ≤ 22: Clinger's fast path divides by them.
inline constexpr double kPow10[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                    1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                    1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

/// Reads digits from p into mantissa while fewer than 19 are read in all (no overflow). One at a
/// time: eight at a time (SWAR) was slower here, 27 ms against 23 ms for the 2 M numbers of a
/// 10 s, 50 kHz CSV (1 to 9 digits a run), and no faster on 12-digit numbers.
inline const char* read_digits(const char* p, const char* last, std::uint64_t& mantissa,
                               int& digits) {
  while (p < last && static_cast<unsigned char>(*p - '0') < 10 && digits < 19) {
    mantissa = mantissa * 10 + static_cast<std::uint64_t>(*p - '0');
    ++digits;
    ++p;
  }
  return p;
}

}  // namespace detail

/// std::from_chars(first, last, value) for a double, with the same result and end pointer.
inline std::from_chars_result read_decimal(const char* first, const char* last, double& value) {
  const char* p = first;
  const bool negative = p < last && *p == '-';
  p += negative ? 1 : 0;
  std::uint64_t mantissa = 0;
  int digits = 0;  // digits read into the mantissa, leading zeros included (at most 19)
  const char* start = p;
  p = detail::read_digits(p, last, mantissa, digits);
  const bool integer_part = p > start;
  int decimals = 0;  // digits after the point
  if (p < last && *p == '.') {
    ++p;
    const char* fraction = p;
    p = detail::read_digits(p, last, mantissa, digits);
    decimals = static_cast<int>(p - fraction);
    if (!integer_part && decimals == 0) {
      return std::from_chars(first, last, value);  // "." or "-.": from_chars says what it is
    }
  } else if (!integer_part) {
    return std::from_chars(first, last, value);  // not a plain decimal (nan, inf, junk)
  }
  const bool more = p < last && ((*p >= '0' && *p <= '9') || *p == 'e' || *p == 'E' || *p == '.');
  if (more || mantissa > (std::uint64_t{1} << 53) || decimals > 22) {
    return std::from_chars(first, last, value);
  }
  const double v = static_cast<double>(mantissa) / detail::kPow10[decimals];
  value = negative ? -v : v;
  return {p, std::errc()};
}

}  // namespace millwatch::shell
