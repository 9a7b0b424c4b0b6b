// read_decimal_row4 against read_decimal, number by number (itself checked against
// std::from_chars): a row of four plain decimals gives the same doubles bit for bit and its length;
// any other row is left to the general reader (0), whatever the bytes after it.

#include "shell/decimal_row.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "shell/decimal_number.hpp"

namespace millwatch::shell {
namespace {

/// The row followed by bytes up to exactly kDecimalRowReach past its start (at least its own
/// length), in an allocation of that size (AddressSanitizer sees a read beyond it): bytes that
/// would mislead a reader looking past the row's '\n' (digits, separators, points, signs, another
/// end-of-line, zeros).
std::unique_ptr<char[]> padded(const std::string& row, int pattern = 0) {
  static const char* const kPatterns[] = {"7,-.\n9", "9999", "\n", ","};
  const std::string fill = pattern == 4 ? std::string(1, '\0') : kPatterns[pattern];
  const std::size_t size = std::max(row.size(), kDecimalRowReach);
  auto text = std::make_unique<char[]>(size);
  for (std::size_t i = 0; i < size; ++i) {
    text[i] = i < row.size() ? row[i] : fill[(i - row.size()) % fill.size()];
  }
  return text;
}

/// Reads the row number by number as the general reader does: four plain decimals separated by
/// commas and ended by '\n'. False if it is not that.
bool read_by_numbers(const std::string& row, std::vector<double>& v) {
  const char* p = row.data();
  const char* last = row.data() + row.size();
  v.assign(4, 0.0);
  for (int i = 0; i < 4; ++i) {
    const auto r = read_decimal(p, last, v[static_cast<std::size_t>(i)]);
    if (r.ec != std::errc() || r.ptr == p) {
      return false;
    }
    p = r.ptr;
    if (*p != (i < 3 ? ',' : '\n')) {
      return false;
    }
    ++p;
  }
  return p == last;
}

void expect_read_as_numbers(const std::string& row) {
  std::vector<double> expected;
  ASSERT_TRUE(read_by_numbers(row, expected)) << row;
  for (int pattern = 0; pattern < 5; ++pattern) {
    const auto text = padded(row, pattern);
    double got[4] = {-1.0, -1.0, -1.0, -1.0};
    ASSERT_EQ(read_decimal_row4(text.get(), got), static_cast<int>(row.size())) << row;
    for (std::size_t i = 0; i < 4; ++i) {
      EXPECT_EQ(std::bit_cast<std::uint64_t>(got[i]), std::bit_cast<std::uint64_t>(expected[i]))
          << row << " field " << i;
    }
  }
}

void expect_left_to_general_reader(const std::string& row) {
  for (int pattern = 0; pattern < 5; ++pattern) {
    const auto text = padded(row, pattern);
    double got[4] = {};
    EXPECT_EQ(read_decimal_row4(text.get(), got), 0) << row;
  }
}

/// A row of four random decimals printed with "%.*f": magnitudes 10^[lo, hi), either sign, 0 to
/// max_decimals decimals.
std::string random_row(std::mt19937_64& rng, double lo, double hi, int max_decimals) {
  std::uniform_real_distribution<double> magnitude(lo, hi);
  std::uniform_int_distribution<int> decimals(0, max_decimals);
  std::string row;
  for (int f = 0; f < 4; ++f) {
    const double v = (rng() % 2 == 0 ? -1.0 : 1.0) * std::pow(10.0, magnitude(rng));
    char field[64];
    std::snprintf(field, sizeof field, "%.*f", decimals(rng), v);
    row += field;
    row += f < 3 ? ',' : '\n';
  }
  return row;
}

TEST(DecimalRow, SameAsNumberByNumberOnPlainRows) {
  if (!kDecimalRowsRead) {
    GTEST_SKIP() << "no SSE2: every row is left to the general reader";
  }
  // At most 4 + 11 digits a field: every mantissa below 2^53, every row read.
  std::mt19937_64 rng(11);
  for (int i = 0; i < 100000; ++i) {
    const std::string row = random_row(rng, -9.0, 3.9, 11);
    if (row.size() > 63) {
      expect_left_to_general_reader(row);  // beyond the reach
      continue;
    }
    expect_read_as_numbers(row);
  }
}

TEST(DecimalRow, ReadRowsAreReadAsNumberByNumber) {
  if (!kDecimalRowsRead) {
    GTEST_SKIP() << "no SSE2: every row is left to the general reader";
  }
  // Any lengths: a row is read (the same doubles) or left whole, never read otherwise.
  std::mt19937_64 rng(12);
  int read = 0;
  for (int i = 0; i < 100000; ++i) {
    const std::string row = random_row(rng, -12.0, 8.0, 22);
    const auto text = padded(row);
    double got[4] = {};
    const int length = read_decimal_row4(text.get(), got);
    if (length == 0) {
      continue;
    }
    ++read;
    ASSERT_EQ(length, static_cast<int>(row.size())) << row;
    std::vector<double> expected;
    ASSERT_TRUE(read_by_numbers(row, expected)) << row;
    for (std::size_t k = 0; k < 4; ++k) {
      EXPECT_EQ(std::bit_cast<std::uint64_t>(got[k]), std::bit_cast<std::uint64_t>(expected[k]))
          << row << " field " << k;
    }
  }
  EXPECT_GT(read, 1000);
}

TEST(DecimalRow, RecordingsAsMillwatchWritesThem) {
  if (!kDecimalRowsRead) {
    GTEST_SKIP() << "no SSE2: every row is left to the general reader";
  }
  expect_read_as_numbers("0.000000000,-0.000610352,0.00854492,0.0012207\n");
  expect_read_as_numbers("0.000020000,0.142822,0.186768,0.00244141\n");
  expect_read_as_numbers("123456.789012345,-12345.6789,0,-0\n");
  expect_read_as_numbers("1,2,3,4\n");
  expect_read_as_numbers("5.,-5.,.5,-.5\n");
  expect_read_as_numbers("-0.0,0.0,0000000000000000.5,0000012.5000\n");
  expect_read_as_numbers("9007199254740992,900719925474099.2,0.9007199254740992,1\n");
  expect_read_as_numbers("000000000000001234.5,0.000000000000000123,1.5,2\n");  // 19 digits
  expect_left_to_general_reader("1234567890123456789,0.5,1.5,2\n");             // 19, above 2^53
  expect_read_as_numbers("12345678.12345678,1234567.123456789,1.23456789,12345678\n");
}

TEST(DecimalRow, OtherRowsLeftToTheGeneralReader) {
  for (const char* row : {
           "0.1,0.2,0.3,0.4\r\n",                   // CRLF
           "0.1, 0.2,0.3,0.4\n",                    // a space
           "1e5,0.2,0.3,0.4\n",                     // an exponent
           "0.1,nan,0.3,0.4\n",                     // not a number
           "0.1,-inf,0.3,0.4\n",                    //
           "0.1,0.2,0.3\n",                         // three columns
           "0.1,0.2,0.3,0.4,0.5\n",                 // five
           "0.1,,0.3,0.4\n",                        // an empty field
           "0.1,0.2,0.3,\n",                        //
           ",0.2,0.3,0.4\n",                        //
           "0.1,.,0.3,0.4\n",                       // a point alone
           "0.1,-,0.3,0.4\n",                       // a sign alone
           "+0.1,0.2,0.3,0.4\n",                    // a plus sign
           "0.1,--0.2,0.3,0.4\n",                   // two signs
           "0.1,0.2-1,0.3,0.4\n",                   // a sign inside
           "0.1,1.2.3,0.3,0.4\n",                   // two points
           "12345678901234567890,0.2,0.3,0.4\n",    // 20 digits
           "0.12345678901234567890,0.2,0.3,0.4\n",  //
           "9007199254740993,0.2,0.3,0.4\n",        // a mantissa above 2^53
           "0.1,0.2,0.3,0.4x\n",                    // junk
           "0.1,0.2,0.3,0.4 \n",                    //
           "0.1;0.2;0.3;0.4\n",                     // another separator
           "0,1,0,2,0,3\n",                         //
           "\n",                                    // an empty line
           "0.1,0.2,0.3,\xc3\xa9\n",                // not ASCII
       }) {
    expect_left_to_general_reader(row);
  }
  // 63 bytes with its '\n': read; 64 and more: left (the reach is 64 bytes).
  // No end-of-line within the 64 bytes scanned.
  expect_left_to_general_reader("1.5,2.5,3.5," + std::string(60, '1') + "\n");
  const std::string longest = "1234567.1234567,-234567.1234567,3234567.1234567,-34567.1234567\n";
  ASSERT_EQ(longest.size(), 63U);
  if (kDecimalRowsRead) {
    expect_read_as_numbers(longest);
    // Short fields ending just before the 63rd byte: their eight-byte loads reach furthest.
    expect_read_as_numbers("0000000000000000001,0000000000000000001,-0000000000000000001,5\n");
  }
  expect_left_to_general_reader("0" + longest);
}

}  // namespace
}  // namespace millwatch::shell
