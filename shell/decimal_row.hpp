#pragma once
// Reading a row of four plain decimals ("t,fx,fy,fz\n", millwatch's CSV) at once. read_decimal()
// reads a number digit by digit, and where one number ends decides where the next begins: each
// row waits on its numbers' lengths, and on the branches that find them. Here the row's
// separators, points and signs are found first, by SSE2 comparisons over 64 bytes, so every
// field's digits are known before any is converted; each field is then converted eight digits
// at a time, the four fields independently of each other. A row in any other form (spaces,
// CRLF, exponents, nan, more or fewer columns, more than 19 digits, a mantissa above 2⁵³, a
// row of more than 63 bytes) is left to the general reader, which says what is wrong with it.
// Where a row is read, every number is the double read_decimal() gives (the same mantissa and
// decimals, one correctly rounded division by an exact power of ten).

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "shell/decimal_number.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace millwatch::shell {

/// Bytes read_decimal_row4() may read from the row's start, whatever the row's length: the 64 it
/// scans, and eight from a field's start at byte 62 at most.
inline constexpr std::size_t kDecimalRowReach = 72;

/// Whether read_decimal_row4() reads rows here (it needs SSE2; without it, it leaves every row
/// to the general reader).
#if defined(__SSE2__)
inline constexpr bool kDecimalRowsRead = true;
#else
inline constexpr bool kDecimalRowsRead = false;
#endif

namespace detail {

inline std::uint64_t load_u64(const char* p) {
  std::uint64_t v = 0;
  std::memcpy(&v, p, sizeof v);
  return v;
}

/// The value of the n (0..8) digits at p (bytes known to be digits; 8 bytes readable).
inline std::uint64_t eight_digits(const char* p, int n) {
  if (n == 0) {
    return 0;
  }
  // Little-endian: the first digit in the lowest byte. Shifted up, the bytes below the first
  // digit are zeros: leading zeros of an eight-digit number, converted by three multiplies.
  std::uint64_t x = (load_u64(p) - 0x3030303030303030ULL) << (8 * (8 - n));
  x = x * 10 + (x >> 8);
  return (((x & 0x000000FF000000FFULL) * (100 + (1000000ULL << 32))) +
          (((x >> 16) & 0x000000FF000000FFULL) * (1 + (10000ULL << 32)))) >>
         32;
}

/// The value of the n (0..19) digits at p.
inline std::uint64_t digit_run(const char* p, int n) {
  constexpr std::uint64_t kE8 = 100000000ULL;
  if (n <= 8) {
    return eight_digits(p, n);
  }
  if (n <= 16) {
    return eight_digits(p, n - 8) * kE8 + eight_digits(p + n - 8, 8);
  }
  return (eight_digits(p, n - 16) * kE8 + eight_digits(p + n - 16, 8)) * kE8 +
         eight_digits(p + n - 8, 8);
}

#if defined(__SSE2__)
/// Bit i: byte i of the 64 equals `c`.
inline std::uint64_t byte_mask(const __m128i (&v)[4], char c) {
  const __m128i k = _mm_set1_epi8(c);
  std::uint64_t m = 0;
  for (int i = 0; i < 4; ++i) {
    m |= static_cast<std::uint64_t>(
             static_cast<std::uint16_t>(_mm_movemask_epi8(_mm_cmpeq_epi8(v[i], k))))
         << (16 * i);
  }
  return m;
}

/// Bit i: byte i of the 64 is not a digit ('0'..'9').
inline std::uint64_t non_digit_mask(const __m128i (&v)[4]) {
  // (byte − '0') as unsigned is below 10; SSE2 compares signed bytes, so both sides are moved
  // by 0x80: (byte − '0') ^ 0x80 > −128 + 9 means 10 or more.
  const __m128i zero = _mm_set1_epi8('0');
  const __m128i flip = _mm_set1_epi8(static_cast<char>(0x80));
  const __m128i nine = _mm_set1_epi8(static_cast<char>(-128 + 9));
  std::uint64_t m = 0;
  for (int i = 0; i < 4; ++i) {
    const __m128i moved = _mm_xor_si128(_mm_sub_epi8(v[i], zero), flip);
    m |= static_cast<std::uint64_t>(
             static_cast<std::uint16_t>(_mm_movemask_epi8(_mm_cmpgt_epi8(moved, nine))))
         << (16 * i);
  }
  return m;
}
#endif

/// A field's digits as an integer and the power of ten to divide it by.
struct DecimalField {
  std::uint64_t mantissa = 0;
  int decimals = 0;
  bool negative = false;
  bool plain = false;  ///< '-'? digits ('.' digits)?, ≤ 19 digits, mantissa ≤ 2⁵³
};

/// The field [s, e) of the row at p, given the row's points and minus signs.
[[gnu::always_inline]] inline DecimalField decimal_field(const char* p, int s, int e,
                                                         std::uint64_t points,
                                                         std::uint64_t minus) {
  static constexpr std::uint64_t kIntPow10[] = {1ULL,
                                                10ULL,
                                                100ULL,
                                                1000ULL,
                                                10000ULL,
                                                100000ULL,
                                                1000000ULL,
                                                10000000ULL,
                                                100000000ULL,
                                                1000000000ULL,
                                                10000000000ULL,
                                                100000000000ULL,
                                                1000000000000ULL,
                                                10000000000000ULL,
                                                100000000000000ULL,
                                                1000000000000000ULL,
                                                10000000000000000ULL,
                                                100000000000000000ULL,
                                                1000000000000000000ULL,
                                                10000000000000000000ULL};
  DecimalField f;
  f.negative = ((minus >> s) & 1U) != 0;
  s += f.negative ? 1 : 0;
  // e ≤ 62 and s ≤ e: both shifts are defined.
  const std::uint64_t point =
      points & ((std::uint64_t{1} << e) - 1) & ~((std::uint64_t{1} << s) - 1);
  if (point == 0) {
    const int whole = e - s;
    if (whole == 0 || whole > 19) {
      return f;
    }
    f.mantissa = digit_run(p + s, whole);
  } else {
    const int at = __builtin_ctzll(point);
    const int whole = at - s;
    f.decimals = e - at - 1;
    if ((point & (point - 1)) != 0 || (whole == 0 && f.decimals == 0) || whole + f.decimals > 19) {
      return f;
    }
    f.mantissa =
        digit_run(p + s, whole) * kIntPow10[f.decimals] + digit_run(p + at + 1, f.decimals);
  }
  f.plain = f.mantissa <= (std::uint64_t{1} << 53);
  return f;
}

}  // namespace detail

/// Reads the row "a,b,c,d\n" at p into v[0..3]: the row's length with its '\n', or 0 when the row
/// is not four plain decimals (v untouched or partly written: the caller reads it otherwise).
/// kDecimalRowReach bytes from p must be readable; the row must end in '\n' (before any byte
/// past the data).
inline int read_decimal_row4(const char* p, double* v) {
#if defined(__SSE2__)
  __m128i bytes[4];
  for (int i = 0; i < 4; ++i) {
    bytes[i] = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + 16 * i));
  }
  const std::uint64_t newlines = detail::byte_mask(bytes, '\n');
  if (newlines == 0) {
    return 0;
  }
  const int end = __builtin_ctzll(newlines);
  if (end == 63) {
    return 0;  // a row of 64 bytes or more: the general reader
  }
  const std::uint64_t row = (std::uint64_t{1} << end) - 1;
  std::uint64_t commas = detail::byte_mask(bytes, ',') & row;
  const std::uint64_t points = detail::byte_mask(bytes, '.') & row;
  const std::uint64_t minus = detail::byte_mask(bytes, '-') & row;
  const std::uint64_t other = detail::non_digit_mask(bytes) & row;
  int comma[3] = {};
  for (int& c : comma) {
    if (commas == 0) {
      return 0;
    }
    c = __builtin_ctzll(commas);
    commas &= commas - 1;
  }
  if (commas != 0) {
    return 0;
  }
  const std::uint64_t separators = (std::uint64_t{1} << comma[0]) | (std::uint64_t{1} << comma[1]) |
                                   (std::uint64_t{1} << comma[2]);
  // Nothing but digits, the separators, points and a minus at a field's start.
  if ((other & ~(separators | points | minus)) != 0 ||
      (minus & ~(std::uint64_t{1} | (separators << 1))) != 0) {
    return 0;
  }
  const detail::DecimalField f[4] = {
      detail::decimal_field(p, 0, comma[0], points, minus),
      detail::decimal_field(p, comma[0] + 1, comma[1], points, minus),
      detail::decimal_field(p, comma[1] + 1, comma[2], points, minus),
      detail::decimal_field(p, comma[2] + 1, end, points, minus)};
  if (!(f[0].plain && f[1].plain && f[2].plain && f[3].plain)) {
    return 0;
  }
  // mantissa / 10^decimals, both exact (below 2⁵³; 10^k exact up to 10^22): the correctly
  // rounded quotient, as read_decimal() computes it. The sign goes in by its bit, not by a
  // branch: a row's signs follow no pattern a branch predictor could learn.
  for (int i = 0; i < 4; ++i) {
    const double x = static_cast<double>(f[i].mantissa) / detail::kPow10[f[i].decimals];
    v[i] = std::bit_cast<double>(std::bit_cast<std::uint64_t>(x) ^
                                 (static_cast<std::uint64_t>(f[i].negative) << 63));
  }
  return end + 1;
#else
  (void)p;
  (void)v;
  return 0;
#endif
}

}  // namespace millwatch::shell
