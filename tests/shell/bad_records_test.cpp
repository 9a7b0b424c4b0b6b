// What replay, diagnose, calibrate and publish say of a recording's bad records, on CSV files read
// by open_recording: the first twenty each by line, then once that more follow; at the end how
// the file ended and how many were skipped; and why a file gave no sample at all.

#include "shell/bad_records.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tests/support/test_paths.hpp"

namespace millwatch::shell {
namespace {

namespace fs = std::filesystem;

const std::string kHeader = "t_s,fx_N,fy_N,fz_N\n";

/// Rows t = i·20 µs for i in [first, end).
std::string rows(int first, int end) {
  std::string s;
  for (int i = first; i < end; ++i) {
    s += std::to_string(i * 2e-5) + ",1,2,3\n";
  }
  return s;
}

struct Said {
  std::vector<std::string> lines;
  std::int64_t samples = 0;
};

/// Reads `text` as cut.csv to its end, as the commands do, collecting what the log says.
Said read(const std::string& text, std::string* why = nullptr) {
  const fs::path csv = test::fresh_temp_dir() / "cut.csv";
  std::ofstream(csv, std::ios::binary) << text;
  Said said;
  BadRecordLog log(csv.filename().string(), detect_recording_format(csv),
                   [&](const std::string& s) { said.lines.push_back(s); });
  RecordingOptions options;
  options.config_rate_hz = 50000.0;
  options.on_bad = log.handler();
  const auto source = open_recording(csv, options);
  while (const auto block = source->next(1000)) {
    said.samples += static_cast<std::int64_t>(block->fx_N.size());
  }
  log.finish(*source);
  EXPECT_EQ(log.count(), source->bad_records());
  if (why != nullptr) {
    *why = why_no_samples(*source);
  }
  return said;
}

TEST(BadRecordLog, NamesTheFirstTwentyByLineThenSaysMoreFollowThenTheirNumber) {
  // 25 bad rows (a letter where fy goes), one every ten rows from line 2 on.
  std::string text = kHeader;
  for (int i = 0; i < 25; ++i) {
    text += std::to_string(i * 10 * 2e-5) + ",1,x,3\n" + rows(i * 10 + 1, i * 10 + 10);
  }
  const Said s = read(text);
  EXPECT_EQ(s.samples, 25 * 9);
  ASSERT_EQ(s.lines.size(), 22u);
  for (int i = 0; i < 20; ++i) {
    const std::string place = "cut.csv:" + std::to_string(2 + 10 * i) + ": ";
    EXPECT_EQ(s.lines[static_cast<std::size_t>(i)].rfind(place, 0), 0u) << s.lines[i];
    EXPECT_NE(s.lines[static_cast<std::size_t>(i)].find("; skipped"), std::string::npos);
  }
  EXPECT_EQ(s.lines[20], "cut.csv: more bad lines follow; their number comes at the end");
  EXPECT_EQ(s.lines[21], "cut.csv: 25 bad lines skipped");
}

TEST(BadRecordLog, OneBadLineIsSaidInTheSingular) {
  const Said s = read(kHeader + rows(0, 5) + "0.0001,1,2\n" + rows(6, 10));
  ASSERT_EQ(s.lines.size(), 2u);
  EXPECT_EQ(s.lines[0].rfind("cut.csv:7: ", 0), 0u) << s.lines[0];
  EXPECT_EQ(s.lines[1], "cut.csv: 1 bad line skipped");
}

TEST(BadRecordLog, AFileCutShortIsSaidBeforeTheTotal) {
  std::string text = kHeader + rows(0, 10);
  text.pop_back();  // the last line without its end-of-line
  const Said s = read(text);
  EXPECT_EQ(s.samples, 10);
  ASSERT_EQ(s.lines.size(), 1u);
  EXPECT_EQ(s.lines[0].rfind("cut.csv: line 11, the last, has no end-of-line", 0), 0u)
      << s.lines[0];
}

TEST(BadRecordLog, TheEndNoteComesBeforeTheTotal) {
  std::string text = kHeader + rows(0, 5) + "0.0001,1,2\n" + rows(6, 10);
  text.pop_back();
  const Said s = read(text);
  ASSERT_EQ(s.lines.size(), 3u);
  EXPECT_EQ(s.lines[1].rfind("cut.csv: line 11, the last, has no end-of-line", 0), 0u)
      << s.lines[1];
  EXPECT_EQ(s.lines[2], "cut.csv: 1 bad line skipped");
}

TEST(BadRecordLog, AGoodFileSaysNothing) {
  const Said s = read(kHeader + rows(0, 100));
  EXPECT_EQ(s.samples, 100);
  EXPECT_TRUE(s.lines.empty());
}

TEST(BadRecordLog, PlacesAnEventLikeALineAndAMatSampleByItsNumber) {
  std::vector<std::string> said;
  const auto say = [&](const std::string& s) { said.push_back(s); };
  BadRecordLog log_events("raw.lcmlog", RecordingFormat::kLcmLog, say);
  log_events.add(21, "unreadable event at byte 481660");
  BadRecordLog mat("cut.mat", RecordingFormat::kMat, say);
  for (int i = 0; i <= BadRecordLog::kNamed; ++i) {
    mat.add(1234 + i, "t is not after the previous sample's");
  }
  ASSERT_EQ(said.size(), 2u + static_cast<std::size_t>(BadRecordLog::kNamed));
  EXPECT_EQ(said[0], "raw.lcmlog:21: unreadable event at byte 481660; skipped");
  EXPECT_EQ(said[1], "cut.mat: sample 1234: t is not after the previous sample's; skipped");
  EXPECT_EQ(said.back(), "cut.mat: more bad samples follow; their number comes at the end");
}

TEST(WhyNoSamples, SaysWhatTheFileHeldOrThatEveryLineWasBad) {
  std::string why;
  EXPECT_EQ(read(kHeader, &why).samples, 0);
  EXPECT_EQ(why, "no rows after its header");
  EXPECT_EQ(read(kHeader + "0,1,2\n0.00002,1,2\n", &why).samples, 0);
  EXPECT_EQ(why, "all 2 lines were bad (named above)");
  EXPECT_EQ(read(kHeader + "0,1,2\n", &why).samples, 0);
  EXPECT_EQ(why, "its one line was bad (named above)");
  std::string many = kHeader;
  for (int i = 0; i < 21; ++i) {
    many += std::to_string(i * 2e-5) + ",1,2\n";
  }
  EXPECT_EQ(read(many, &why).samples, 0);
  EXPECT_EQ(why, "all 21 lines were bad (the first named above)");
}

}  // namespace
}  // namespace millwatch::shell
