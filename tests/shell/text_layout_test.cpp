// Recordings in delimited text as users have them, read from memory: DynoWare exports
// (preamble, channel row, units row, time starting anywhere, units converted), any delimited
// text with a column map (header names or indices, scales, semicolons with decimal commas, no
// time column), the errors that name file, line and column, and bad rows counted and skipped.

#include "shell/text_layout.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "shell/csv_cut_reader.hpp"
#include "shell/recording_source.hpp"
#include "tests/support/test_paths.hpp"

namespace millwatch::shell {
namespace {

struct Read {
  TextLayout layout;
  std::vector<std::pair<std::int64_t, std::string>> bad;
  std::vector<std::int64_t> utimes_us;
  std::vector<double> fx, fy, fz;
  double rate_hz = 0.0;
};

/// Reads `text` with `map`; the rate is the layout's, else `rate_hz`.
Read read(const std::string& text, const ColumnMap& map = {}, double rate_hz = 0.0) {
  std::istringstream in(text);
  Read out;
  out.layout = read_text_layout(in, "mem.csv", map);
  out.rate_hz = out.layout.rate_stated || rate_hz == 0.0 ? out.layout.sample_rate_hz : rate_hz;
  CsvCutReader reader(in, out.layout, out.rate_hz, [&](std::int64_t line, const std::string& p) {
    out.bad.emplace_back(line, p);
  });
  for (auto b = reader.next(4); !b.fx_N.empty(); b = reader.next(4)) {
    out.utimes_us.push_back(b.utime_us);
    out.fx.insert(out.fx.end(), b.fx_N.begin(), b.fx_N.end());
    out.fy.insert(out.fy.end(), b.fy_N.begin(), b.fy_N.end());
    out.fz.insert(out.fz.end(), b.fz_N.begin(), b.fz_N.end());
  }
  EXPECT_EQ(reader.bad_lines(), static_cast<std::int64_t>(out.bad.size()));
  return out;
}

std::string error_of(const std::string& text, const ColumnMap& map = {}) {
  std::istringstream in(text);
  try {
    read_text_layout(in, "mem.csv", map);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

/// A DynoWare export of 10 kHz from second 5, with an Mz channel between the forces.
std::string dynoware(const std::string& force_unit = "N") {
  std::string s =
      "DynoWare,Version 2.5.1.2\n"
      "Filename:,C:\\DynoWare\\cut_07.dwd\n"
      "Date:,2024-03-12\n"
      "Sampling rate [Hz]:,10000\n"
      "Measuring time [s]:,50\n"
      "Samples per channel:,500001\n"
      "Cycle No:,1\n"
      "Time,Fx,Mz,Fy,Fz\n"
      "s," +
      force_unit + ",Nm," + force_unit + "," + force_unit + "\n";
  for (int i = 0; i < 10; ++i) {
    s += std::to_string(5.0 + i * 1e-4) + "," + std::to_string(i) + ",9," + std::to_string(-i) +
         "," + std::to_string(2 * i) + "\n";
  }
  return s;
}

TEST(TextLayout, DynoWareExportIsReadByContentWithItsRateAndChannels) {
  const Read r = read(dynoware());
  EXPECT_EQ(r.layout.format, TextFormat::kDynoWare);
  EXPECT_TRUE(r.layout.rate_stated);
  EXPECT_DOUBLE_EQ(r.layout.sample_rate_hz, 10000.0);
  EXPECT_EQ(r.layout.channels, (std::vector<std::string>{"Time", "Fx", "Mz", "Fy", "Fz"}));
  EXPECT_EQ(r.layout.column, (std::array<int, 4>{0, 1, 3, 4}));
  EXPECT_EQ(r.layout.header_lines, 9);  // preamble, channel row, units row
  ASSERT_GE(r.layout.preamble.size(), 7u);
  EXPECT_EQ(r.layout.preamble[5],
            std::make_pair(std::string("Samples per channel:"), std::string("500001")));
  EXPECT_TRUE(r.bad.empty());
  // Ten samples from t = 5 s (not from 0), Mz skipped, in blocks of at most 4.
  ASSERT_EQ(r.fx.size(), 10u);
  EXPECT_EQ(r.utimes_us, (std::vector<std::int64_t>{5000000, 5000400, 5000800}));
  EXPECT_EQ(r.fx[7], 7.0);
  EXPECT_EQ(r.fy[7], -7.0);
  EXPECT_EQ(r.fz[7], 14.0);
}

// A preamble whose rate the Time column belies (20 kHz stated, the times step at 10 kHz) is read
// at the Time column's: at the stated rate every sample was a block of its own, "older than
// expected", and all but every other one rejected.
TEST(TextLayout, DynoWareRateTheTimeColumnBeliesGivesWayToIt) {
  std::string text = dynoware();
  const std::string stated = "Sampling rate [Hz]:,10000";
  text.replace(text.find(stated), stated.size(), "Sampling rate [Hz]:,20000");
  for (int i = 10; i < 300; ++i) {  // 300 rows: enough of the record to belie a rate
    text += std::to_string(5.0 + i * 1e-4) + ",1,9,2,3\n";
  }
  const std::filesystem::path path = test::fresh_temp_dir() / "belied.txt";
  std::ofstream(path) << text;
  const auto source = open_recording(path, RecordingOptions{});
  EXPECT_NEAR(source->sample_rate_hz(), 10000.0, 1e-6);
  EXPECT_TRUE(source->rate_stated());
  const auto block = source->next(1000);
  ASSERT_TRUE(block.has_value());
  EXPECT_EQ(block->fx_N.size(), 300u);  // one block: every sample where the rate puts it
}

// Times printed to 10 µs at 51.2 kHz (the PHM files' format at a standard DAQ rate): the steps
// are 20 µs and now and then 10 or 30 µs. The stated rate puts every row within half a sample
// of its time, so it stands; a median step (50 kHz) would have broken the file into gaps.
TEST(TextLayout, RoundedTimesDoNotBelieTheirRate) {
  std::string text =
      "DynoWare,Version 2.5.1.2\nSampling rate [Hz]:,51200\nTime,Fx,Fy,Fz\ns,N,N,N\n";
  for (int i = 0; i < 2000; ++i) {
    char time[32];
    std::snprintf(time, sizeof time, "%.5f", i / 51200.0);
    text += std::string(time) + ",1,2,3\n";
  }
  const std::filesystem::path path = test::fresh_temp_dir() / "rounded.txt";
  std::ofstream(path) << text;
  const auto source = open_recording(path, RecordingOptions{});
  EXPECT_DOUBLE_EQ(source->sample_rate_hz(), 51200.0);
  const auto block = source->next(4000);
  ASSERT_TRUE(block.has_value());
  EXPECT_EQ(block->fx_N.size(), 2000u);
}

TEST(TextLayout, DynoWareUnitsAreConvertedToNewtons) {
  const Read r = read(dynoware("kN"));
  ASSERT_EQ(r.fx.size(), 10u);
  EXPECT_DOUBLE_EQ(r.fx[3], 3000.0);
  EXPECT_DOUBLE_EQ(r.fz[3], 6000.0);
}

TEST(TextLayout, DynoWareBadRowsAreCountedByLineAndSkipped) {
  std::string text = dynoware();
  text += "5.001,x,0,0,0\n5.0011,1,0\n5.0012,1,2,3,4\n";
  const Read r = read(text);
  ASSERT_EQ(r.bad.size(), 2u);
  EXPECT_EQ(r.bad[0],
            std::make_pair(std::int64_t{20},
                           std::string("Fx (column 2) is not a number in \"5.001,x,0,0,0\"")));
  EXPECT_EQ(r.bad[1], std::make_pair(std::int64_t{21},
                                     std::string("fewer than 5 columns in \"5.0011,1,0\"")));
  EXPECT_EQ(r.fx.size(), 11u);  // the good row after them is read
}

TEST(TextLayout, DynoWareWithoutAForceChannelNamesWhatItHas) {
  std::string text = dynoware();
  text.replace(text.find("Time,Fx,Mz,Fy,Fz"), 16, "Time,Fx,Mz,Fy,F3");
  EXPECT_EQ(error_of(text),
            "mem.csv:8: a DynoWare export without a channel Fz (channels: Time, Fx, Mz, Fy, F3); "
            "name them with --columns");
  // ... which a column map resolves.
  const Read r = read(text, parse_column_map("t=Time,fx=Fx,fy=Fy,fz=F3"));
  EXPECT_EQ(r.fz.size(), 10u);
  EXPECT_EQ(r.fz[2], 4.0);
}

TEST(TextLayout, DelimitedTextByHeaderNamesWithScalesAndTime) {
  const std::string text =
      "index;time_ms;Fx_kN;Fy_kN;Fz_kN\n"
      "0;0,0;0,001;0,002;0,003\n"
      "1;0,02;0,004;0,005;0,006\n"
      "2;0,04;0,007;0,008;0,009\n";
  const Read r = read(text, parse_column_map("t=time_ms*0.001,fx=Fx_kN*1000,fy=Fy_kN*1000,"
                                             "fz=Fz_kN*1000"));
  EXPECT_EQ(r.layout.format, TextFormat::kDelimited);
  EXPECT_EQ(r.layout.delimiter, ';');
  EXPECT_TRUE(r.layout.decimal_comma);
  EXPECT_FALSE(r.layout.rate_stated);
  EXPECT_NEAR(r.layout.sample_rate_hz, 50000.0, 1e-6);  // from the time column
  EXPECT_TRUE(r.bad.empty());
  ASSERT_EQ(r.fx.size(), 3u);
  EXPECT_NEAR(r.fx[1], 4.0, 1e-12);
  EXPECT_NEAR(r.fz[2], 9.0, 1e-12);
  EXPECT_EQ(r.utimes_us.front(), 0);
}

// A units row after the header converts a column the map did not scale; a scale the map gives
// is the whole conversion (time in ms with t=time_ms*0.001 had been scaled by the row's "ms"
// too: 50 MHz). A column index past the header is said at the header, once.
TEST(TextLayout, AUnitsRowConvertsOnlyWhatTheMapDidNotScale) {
  const std::string text =
      "time_ms;Fx;Fy;Fz\n"
      "ms;kN;N;N\n"
      "0,0;0,001;2;3\n"
      "0,02;0,004;5;6\n";
  const Read scaled = read(text, parse_column_map("t=time_ms*0.001,fx=Fx,fy=Fy,fz=Fz"));
  EXPECT_EQ(scaled.layout.header_lines, 2);
  EXPECT_NEAR(scaled.layout.sample_rate_hz, 50000.0, 1e-6);
  ASSERT_EQ(scaled.fx.size(), 2u);
  EXPECT_NEAR(scaled.fx[1], 4.0, 1e-12);  // kN from the units row
  const Read by_unit = read(text, parse_column_map("t=time_ms,fx=Fx*1,fy=Fy,fz=Fz"));
  EXPECT_NEAR(by_unit.layout.sample_rate_hz, 50000.0, 1e-6);  // ms from the units row
  EXPECT_NEAR(by_unit.fx[1], 0.004, 1e-15);                   // the map's *1 stands

  const std::string wide = error_of("t,a,b,c\n0,1,2,3\n", parse_column_map("fx=9,fy=2,fz=3"));
  EXPECT_EQ(wide.rfind("mem.csv:1: no column 9 for fx (the header has 4: t, a, b, c)", 0), 0u)
      << wide;
}

TEST(TextLayout, NoTimeColumnTakesTheGivenRateAndABadRowIsAGap) {
  // Seven columns, forces first, no time: like the PHM 2010 raw windows.
  std::string text = "force_x_N,force_y_N,force_z_N,vx,vy,vz,ae\n";
  for (int i = 0; i < 8; ++i) {
    text += (i == 5 ? std::string("oops") : std::to_string(i)) + ",1,2,0,0,0,0\n";
  }
  const Read r = read(text, parse_column_map("fx=force_x_N,fy=force_y_N,fz=force_z_N"), 50000.0);
  EXPECT_EQ(r.layout.column[0], -1);
  EXPECT_DOUBLE_EQ(r.rate_hz, 50000.0);
  ASSERT_EQ(r.bad.size(), 1u);
  EXPECT_EQ(r.bad[0].first, 7);
  EXPECT_EQ(r.bad[0].second, "force_x_N (column 1) is not a number in \"oops,1,2,0,0,0,0\"");
  EXPECT_EQ(r.fx, (std::vector<double>{0, 1, 2, 3, 4, 6, 7}));
  // Row 5 is missing: the samples after it start a new block 6 samples (120 µs) in.
  EXPECT_EQ(r.utimes_us, (std::vector<std::int64_t>{0, 80, 120}));
}

TEST(TextLayout, ColumnsByIndexWithoutAHeader) {
  const Read r = read("1 2 3\n4 5 6\n", parse_column_map("fx=3,fy=1,fz=2*-1"), 1000.0);
  EXPECT_EQ(r.layout.header_lines, 0);
  EXPECT_EQ(r.layout.delimiter, ' ');
  EXPECT_EQ(r.fx, (std::vector<double>{3, 6}));
  EXPECT_EQ(r.fy, (std::vector<double>{1, 4}));
  EXPECT_EQ(r.fz, (std::vector<double>{-2, -5}));
}

TEST(TextLayout, MillwatchCsvNeedsNoMapAndOtherTextsSayWhatToDo) {
  const Read r = read("t_s,fx_N,fy_N,fz_N\n0,1,2,3\n0.00002,4,5,6\n");
  EXPECT_EQ(r.layout.format, TextFormat::kMillwatch);
  EXPECT_NEAR(r.layout.sample_rate_hz, 50000.0, 1e-6);
  EXPECT_EQ(r.fx, (std::vector<double>{1, 4}));
  const std::string e = error_of("Time,Fx,Fy,Fz\n0,1,2,3\n");
  EXPECT_EQ(e.rfind("mem.csv:1: header is \"Time,Fx,Fy,Fz\"; expected \"t_s,fx_N,fy_N,fz_N\" "
                    "(millwatch's CSV), a DynoWare export, or a column map: --columns",
                    0),
            0u)
      << e;
  EXPECT_EQ(error_of("Time,Fx,Fy,Fz\n", parse_column_map("t=Time,fx=Fx,fy=Fy,fz=Force_z")),
            "mem.csv:1: no column \"Force_z\" for fz (columns: Time, Fx, Fy, Fz)");
  // One column by its name and by its index (or two spellings of its name): read twice.
  EXPECT_EQ(error_of("Time,Fx,Fy,Fz\n", parse_column_map("t=Time,fx=Fx,fy=2,fz=Fz")),
            "mem.csv: columns: fx and fy both read Fx (column 2) (each needs its own column)");
  EXPECT_EQ(error_of("Time,Fx,Fy,Fz\n", parse_column_map("t=Time,fx=Fx,fy=fx,fz=Fz")),
            "mem.csv: columns: fx and fy both read Fx (column 2) (each needs its own column)");
  EXPECT_EQ(error_of("1,2,3\n", parse_column_map("fx=a,fy=b,fz=c")),
            "mem.csv: no header row: name the columns by their index (fx=2, ...)");
  EXPECT_EQ(error_of(""), "mem.csv:1: the file is empty");
  EXPECT_EQ(error_of("DynoWare,Version 2\nFilename:,x\n"),
            "mem.csv: a DynoWare export that ends before its channel row");
}

// A binary file given as a recording: the header the error quotes shows its control bytes as
// \xNN (they had gone to the terminal as they were, an escape sequence among them).
TEST(TextLayout, AnErrorQuotesControlBytesAsEscapes) {
  const std::string e = error_of(std::string("\x7f"
                                             "ELF\x02\x01\x1b[2J\tx\0y",
                                             14) +
                                 "\n");
  EXPECT_EQ(e.rfind("mem.csv:1: header is \"\\x7fELF\\x02\\x01\\x1b[2J\tx\\x00y\"; expected", 0),
            0u)
      << e;
  EXPECT_EQ(excerpt("abc,d\x01", 4), "abc,");
  EXPECT_EQ(excerpt("Kraft [N]\tZeit", 80), "Kraft [N]\tZeit");  // tabs and text unchanged
  // Cut before a character that would not fit whole ("µ" is two bytes, "€" three): half a
  // character would print as a replacement glyph.
  EXPECT_EQ(excerpt("F \xc2\xb5N", 3), "F ");
  EXPECT_EQ(excerpt("F \xc2\xb5N", 4), "F \xc2\xb5");
  EXPECT_EQ(excerpt("\xe2\x82\xac"
                    "1",
                    2),
            "");
  EXPECT_EQ(excerpt("\xe2\x82\xac"
                    "1",
                    3),
            "\xe2\x82\xac");
  // Bytes that are no UTF-8 (a binary file's continuation-like run) are cut where they stand.
  EXPECT_EQ(excerpt("ab\x80\x81\x82\x83\x84", 4), "ab\x80\x81");
}

}  // namespace
}  // namespace millwatch::shell
