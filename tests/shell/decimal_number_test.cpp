// read_decimal against std::from_chars (the truth it must reproduce bit for bit, end pointer and
// error included): plain decimals of every length the fast path takes, and the forms it hands
// on (exponents, long mantissas, nan, inf, junk).

#include "shell/decimal_number.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

namespace millwatch::shell {
namespace {

void expect_same(const std::string& text) {
  const char* first = text.data();
  const char* last = text.data() + text.size();
  double expected = 12345.0, got = 12345.0;  // both left alone on an error
  const auto e = std::from_chars(first, last, expected);
  const auto g = read_decimal(first, last, got);
  EXPECT_EQ(g.ec, e.ec) << text;
  EXPECT_EQ(g.ptr - first, e.ptr - first) << text;
  EXPECT_EQ(std::bit_cast<std::uint64_t>(got), std::bit_cast<std::uint64_t>(expected)) << text;
}

TEST(DecimalNumber, SameAsFromCharsOnPlainDecimals) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> magnitude(-12.0, 6.0);
  std::uniform_int_distribution<int> precision(0, 25);
  for (int i = 0; i < 200000; ++i) {
    const double v = (rng() % 2 == 0 ? -1.0 : 1.0) * std::pow(10.0, magnitude(rng));
    char text[80];
    std::snprintf(text, sizeof text, (rng() % 2 == 0) ? "%.*f" : "%.*g", precision(rng), v);
    expect_same(text);
    expect_same(std::string(text) + ",0.5");  // the field ends at the delimiter
  }
}

TEST(DecimalNumber, SameAsFromCharsOnEdgeCases) {
  for (const char* t :
       {"0",
        "-0",
        "-0.0",
        "0.000020000",
        "5.",
        "-5.",
        ".5",
        "-.5",
        ".",
        "-",
        "-.",
        "",
        "+1",
        "1e5",
        "1E-3",
        "2.5e",
        "nan",
        "-inf",
        "inf",
        "abc",
        "1.2.3",
        "12345678901234567890",
        "9007199254740992",
        "9007199254740993",
        "9007199254740993.5",
        "0.1234567890123456789012",
        "0.12345678901234567890123",
        "1.0000000000000000000000001",
        "00000000000000000000000012.5",
        "0.0000000000000000000000000001",
        "123456789012345678.9",
        "1e400",
        "-1e-400",
        "179769313486231570000000000000000000000000000000000000000000000000000000000000000000"
        "00000000000000000000000000000000000000000000000000000000000000000000000000000000000000"
        "00000000000000000000000000000000000000000000000000000000000000000000000000000000000000"
        "0000000000000000000000000000000000000000000000000000000000000000000.0",
        "0.142822 ",
        "3,4"}) {
    expect_same(t);
  }
}

}  // namespace
}  // namespace millwatch::shell
