// The CSV reader on in-memory cuts: blocks split where time jumps, bad rows reported by line
// (numbers, columns, damaged times) and skipped, values beyond a double's range.

#include "shell/csv_cut_reader.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace millwatch::shell {
namespace {

constexpr double kRate_hz = 50000.0;  // 20 µs per sample

struct Read {
  std::vector<std::pair<std::int64_t, std::string>> bad;  // line, problem
  std::vector<std::int64_t> utimes_us;                    // of each block
  std::vector<std::vector<double>> fx_N;                  // of each block
};

Read read(const std::string& text, std::size_t block = 1000,
          std::size_t buffer_bytes = CsvCutReader::kDefaultBufferBytes) {
  std::istringstream in(text);
  Read out;
  CsvCutReader reader(
      in, "mem.csv", kRate_hz,
      [&](std::int64_t line, const std::string& p) { out.bad.emplace_back(line, p); },
      buffer_bytes);
  for (auto b = reader.next(block); !b.fx_N.empty(); b = reader.next(block)) {
    out.utimes_us.push_back(b.utime_us);
    out.fx_N.emplace_back(b.fx_N.begin(), b.fx_N.end());
  }
  EXPECT_EQ(reader.bad_lines(), static_cast<std::int64_t>(out.bad.size()));
  return out;
}

/// Rows t = i·20 µs, fx = i, for i in [first, end).
std::string rows(int first, int end) {
  std::string s;
  for (int i = first; i < end; ++i) {
    s += std::to_string(i * 2e-5) + "," + std::to_string(i) + ",0,0\n";
  }
  return s;
}

const std::string kHeader = "t_s,fx_N,fy_N,fz_N\n";

TEST(CsvCutReader, ReadsBlocksAndSplitsThemWhereTimeJumps) {
  // CRLF and blank lines are fine; the last line needs no end-of-line.
  const Read r = read(kHeader + "0,0,0,0\r\n\n0.00002,1,0,0\r\n" + rows(2, 5) + rows(10, 12) +
                      "0.00024,12,0,0");
  EXPECT_TRUE(r.bad.empty());
  ASSERT_EQ(r.utimes_us.size(), 2u);
  EXPECT_EQ(r.utimes_us[0], 0);
  EXPECT_EQ(r.fx_N[0], (std::vector<double>{0, 1, 2, 3, 4}));
  EXPECT_EQ(r.utimes_us[1], 200);
  EXPECT_EQ(r.fx_N[1], (std::vector<double>{10, 11, 12}));
}

TEST(CsvCutReader, AWrongHeaderIsAnErrorNamingTheInput) {
  std::istringstream in("time,fx,fy,fz\n0,1,2,3\n");
  try {
    CsvCutReader reader(in, "mem.csv", kRate_hz, nullptr);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(),
                 "mem.csv:1: header is \"time,fx,fy,fz\"; expected \"t_s,fx_N,fy_N,fz_N\"");
  }
  std::istringstream empty("");
  EXPECT_THROW(CsvCutReader(empty, "empty.csv", kRate_hz, nullptr), std::runtime_error);
}

TEST(CsvCutReader, DamagedTimesAreReportedByLineAndSkipped) {
  const Read r = read(kHeader + rows(0, 3) +  // lines 2-4
                      "nan,9,0,0\n" +         // 5
                      "-inf,9,0,0\n" +        // 6
                      "9.1e9,9,0,0\n" +       // 7: beyond ±2^53 µs
                      "0.00002,9,0,0\n" +     // 8: going back
                      "0.00004,9,0,0\n" +     // 9: repeated
                      "4,9,0,0\n" +           // 10: ahead of its neighbours
                      rows(3, 5));            // 11-12
  ASSERT_EQ(r.bad.size(), 6u);
  EXPECT_EQ(r.bad[0], std::make_pair(std::int64_t{5}, std::string("t_s is not finite (nan)")));
  EXPECT_EQ(r.bad[1], std::make_pair(std::int64_t{6}, std::string("t_s is not finite (-inf)")));
  EXPECT_EQ(r.bad[2].first, 7);
  EXPECT_EQ(r.bad[2].second, "t_s 9.1e+09 is out of range (more than 9007199254.740992 s from 0)");
  EXPECT_EQ(r.bad[3].first, 8);
  EXPECT_EQ(r.bad[3].second, "t_s 2e-05 is not after the previous row's (4e-05 on line 4)");
  EXPECT_EQ(r.bad[4].first, 9);
  EXPECT_EQ(r.bad[4].second, "t_s 4e-05 is not after the previous row's (4e-05 on line 4)");
  EXPECT_EQ(r.bad[5].first, 10);
  EXPECT_EQ(r.bad[5].second,
            "t_s 4 jumps ahead of the rows around it (4e-05 on line 4, 6e-05 on line 11)");
  // Nothing was lost but the bad rows: one block, in order.
  ASSERT_EQ(r.fx_N.size(), 1u);
  EXPECT_EQ(r.fx_N[0], (std::vector<double>{0, 1, 2, 3, 4}));
}

TEST(CsvCutReader, AGapInTheRecordingIsNotADamagedTime) {
  // A jump ahead whose next row follows it is a gap: both blocks are kept.
  const Read r = read(kHeader + rows(0, 3) + rows(1000, 1003));
  EXPECT_TRUE(r.bad.empty());
  ASSERT_EQ(r.utimes_us.size(), 2u);
  EXPECT_EQ(r.utimes_us[1], 20000);
  // A first row ahead of the second is the damaged one.
  const Read first = read(kHeader + "7,9,0,0\n" + rows(1, 3));
  ASSERT_EQ(first.bad.size(), 1u);
  EXPECT_EQ(first.bad[0].second, "t_s 7 jumps ahead of the rows around it (2e-05 on line 3)");
  ASSERT_EQ(first.utimes_us.size(), 1u);
  EXPECT_EQ(first.utimes_us[0], 20);
}

TEST(CsvCutReader, NumbersBeyondADoubleAreInfiniteOrZero) {
  const Read r = read(kHeader + "0,1e400,0,0\n0.00002,-1e999,0,0\n0.00004,1e-400,0,0\n" +
                      "0.00006,-2e-999,0,0\n");
  EXPECT_TRUE(r.bad.empty());
  ASSERT_EQ(r.fx_N.size(), 1u);
  ASSERT_EQ(r.fx_N[0].size(), 4u);
  EXPECT_EQ(r.fx_N[0][0], std::numeric_limits<double>::infinity());
  EXPECT_EQ(r.fx_N[0][1], -std::numeric_limits<double>::infinity());
  EXPECT_EQ(r.fx_N[0][2], 0.0);
  EXPECT_EQ(r.fx_N[0][3], 0.0);
  const Read t = read(kHeader + "1e400,1,0,0\n");
  ASSERT_EQ(t.bad.size(), 1u);
  EXPECT_EQ(t.bad[0].second, "t_s is not finite (1e400)");
}

TEST(CsvCutReader, MalformedRowsAreReportedByLine) {
  const Read r = read(kHeader + "0,1,2,3\nx,1,2,3\n0.00002,y,2,3\n0.00002,1,2\n0.00002,1,2,3,4\n");
  ASSERT_EQ(r.bad.size(), 4u);
  EXPECT_EQ(r.bad[0].second, "t_s is not a number in \"x,1,2,3\"");
  EXPECT_EQ(r.bad[1].second, "a force is not a number in \"0.00002,y,2,3\"");
  EXPECT_EQ(r.bad[2].second, "fewer than 4 columns in \"0.00002,1,2\"");
  EXPECT_EQ(r.bad[3].first, 6);
  EXPECT_EQ(r.bad[3].second, "more than 4 columns in \"0.00002,1,2,3,4\"");
}

// A cell whose number is followed by more text is a cell that is not a number: these rows have
// their four columns (they had been said to have fewer); CRLF rows read as before.
TEST(CsvCutReader, ACellWithTextAfterItsNumberIsNotANumber) {
  const Read r = read(kHeader +
                      "0,1,2,3\r\n0.00002x,1,2,3\n0.00004,0x10,2,3\n0.00006,1;2,3,4\n0.00008,1,2,3 "
                      "N\n0.0001,1,2\r\n0.00012,5,2,3\r\n0.00014,1,2,3\r\r\n");
  ASSERT_EQ(r.bad.size(), 6u);
  EXPECT_EQ(r.bad[5].second, "a carriage return inside the row in \"0.00014,1,2,3\\x0d\"");
  EXPECT_EQ(r.bad[0].second, "t_s is not a number in \"0.00002x,1,2,3\"");
  EXPECT_EQ(r.bad[1].second, "a force is not a number in \"0.00004,0x10,2,3\"");
  EXPECT_EQ(r.bad[2].second, "a force is not a number in \"0.00006,1;2,3,4\"");
  EXPECT_EQ(r.bad[3].second, "a force is not a number in \"0.00008,1,2,3 N\"");
  EXPECT_EQ(r.bad[4].second, "fewer than 4 columns in \"0.0001,1,2\"");
  ASSERT_EQ(r.fx_N.size(), 2u);  // the gap splits the good rows' blocks
  EXPECT_EQ(r.fx_N[0], std::vector<double>{1.0});
  EXPECT_EQ(r.fx_N[1], std::vector<double>{5.0});
}

TEST(CsvCutReader, ReadsTheSameWhereverTheBufferEnds) {
  // Reads of 1 to 70 bytes cut every number, every CRLF and the header somewhere; a line longer
  // than the read (the bad one, 80 characters) spans several; the last line has no end-of-line.
  const std::string long_bad = "0.00010," + std::string(72, '7');
  const std::string text = "t_s,fx_N,fy_N,fz_N\r\n" + rows(0, 3) + "\r\n" +  // lines 2-5
                           "0.00006,-3.25,1e-3,0.5\r\n" +                    // 6
                           "0.00008,4,nan,0\n" + long_bad + "\n" +           // 7-8
                           "\n\n" + rows(6, 9) + "0.00018,9.125,0,0";        // 9-14
  for (std::size_t bytes = 1; bytes <= 70; ++bytes) {
    SCOPED_TRACE("reads of " + std::to_string(bytes) + " bytes");
    const Read r = read(text, 1000, bytes);
    ASSERT_EQ(r.bad.size(), 1u);
    EXPECT_EQ(r.bad[0].first, 8);
    EXPECT_EQ(r.bad[0].second, "fewer than 4 columns in \"" + long_bad.substr(0, 60) + "\"");
    ASSERT_EQ(r.utimes_us.size(), 2u);  // the bad line's sample is a gap
    EXPECT_EQ(r.utimes_us[0], 0);
    EXPECT_EQ(r.fx_N[0], (std::vector<double>{0, 1, 2, -3.25, 4}));
    EXPECT_EQ(r.utimes_us[1], 120);
    EXPECT_EQ(r.fx_N[1], (std::vector<double>{6, 7, 8, 9.125}));
  }
}

}  // namespace
}  // namespace millwatch::shell
