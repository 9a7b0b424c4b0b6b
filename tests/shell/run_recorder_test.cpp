// The replay's per-revolution rows and the synchronous average it keeps for the plots, fed by
// hand: which values a row carries for a valid, a bounded and an unbounded revolution (the
// summary's rules) and one without a measured speed, and a bin of the average that no sample
// reached.

#include "shell/run_recorder.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "core/monitor/sync_average.hpp"
#include "tests/support/test_paths.hpp"

namespace millwatch::shell {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> fields(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream in(line);
  std::string f;
  while (std::getline(in, f, ',')) {
    out.push_back(f);
  }
  if (!line.empty() && line.back() == ',') {
    out.emplace_back();
  }
  return out;
}

monitor::RevolutionRecord revolution(std::int64_t n, bool valid, bool bounded) {
  monitor::RevolutionRecord r;
  r.revolution = n;
  r.utime_us = 14694 + n * 1000;
  r.spindle_rpm = 10421.5;
  auto& m = r.measured;
  m.flutes = 2;
  m.valid = valid;
  m.bounded = bounded;
  m.flute_period_s = {0.003, 0.0027};
  m.alpha_deg = 170.0;
  m.delta_fy_N = 1.5;
  m.peak_N[0] = {-10.0, -4.0, -2.0};
  m.peak_N[1] = {-8.0, -3.0, -1.0};
  m.peak_resultant_N = {10.5, 8.5};
  return r;
}

TEST(RunRecorder, PeaksNeedTheBoundsAndAlphaEveryEvent) {
  const fs::path path = test::fresh_temp_dir() / "revolutions.csv";
  RunRecorder rec(2, path, true);
  rec.on_revolution(revolution(0, true, true));    // every event
  rec.on_revolution(revolution(1, false, true));   // both CE1 events, flute 2's missing
  rec.on_revolution(revolution(2, false, false));  // not even its bounds
  monitor::RevolutionRecord coasted = revolution(3, false, false);
  coasted.spindle_rpm = 0.0;  // its closing CE1 missed: the events' filter measured no speed
  rec.on_revolution(coasted);
  rec.commit();
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  const std::vector<std::string> header = fields(line);
  auto column = [&](const std::string& name) {
    for (std::size_t i = 0; i < header.size(); ++i) {
      if (header[i] == name) {
        return i;
      }
    }
    ADD_FAILURE() << "no column " << name << " in " << line;
    return std::size_t{0};
  };
  std::vector<std::vector<std::string>> rows;
  while (std::getline(in, line)) {
    rows.push_back(fields(line));
  }
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[0][column("t_s")], "0.014694");
  EXPECT_EQ(rows[0][column("alpha_deg")], "170");
  EXPECT_EQ(rows[0][column("period_s_2")], "0.0027");
  EXPECT_EQ(rows[0][column("peak_resultant_N_2")], "8.5");
  EXPECT_EQ(rows[1][column("valid")], "0");
  EXPECT_EQ(rows[1][column("alpha_deg")], "");
  EXPECT_EQ(rows[1][column("period_s_1")], "");
  EXPECT_EQ(rows[1][column("delta_fy_N")], "");
  EXPECT_EQ(rows[1][column("peak_fx_N_1")], "-10");
  EXPECT_EQ(rows[1][column("peak_resultant_N_2")], "8.5");
  EXPECT_EQ(rows[2][column("peak_resultant_N_1")], "");
  EXPECT_EQ(rows[2][column("spindle_rpm")], "10421.5");
  EXPECT_EQ(rows[3][column("spindle_rpm")], "");  // absent, not 0
  // What the plots keep: the bounded revolutions, α only where valid.
  ASSERT_EQ(rec.rows().size(), 4u);
  EXPECT_TRUE(std::isnan(rec.rows()[3].spindle_rpm));
  EXPECT_TRUE(rec.rows()[1].bounded);
  EXPECT_FALSE(rec.rows()[1].valid);
  EXPECT_FALSE(rec.rows()[2].bounded);
}

// One flute: α is 360° and ΔFy 0 by definition, absent in the rows as in the summary (which
// warns "no alpha"), in the CSV, the JSON Lines and what the plots keep (they had drawn 360°).
TEST(RunRecorder, OneFluteHasNoAlphaNorDeltaFy) {
  for (const char* name : {"revolutions.csv", "revolutions.jsonl"}) {
    SCOPED_TRACE(name);
    const fs::path path = test::fresh_temp_dir() / name;
    RunRecorder rec(1, path, true);
    monitor::RevolutionRecord r = revolution(0, true, true);
    r.measured.flutes = 1;
    r.measured.flute_period_s = {0.0057, 0.0};
    r.measured.alpha_deg = 360.0;
    r.measured.delta_fy_N = 0.0;
    rec.on_revolution(r);
    rec.commit();
    std::ifstream in(path);
    std::string line;
    if (path.extension() == ".csv") {
      std::getline(in, line);
      const std::vector<std::string> header = fields(line);
      std::getline(in, line);
      const std::vector<std::string> row = fields(line);
      ASSERT_EQ(row.size(), header.size()) << line;
      for (std::size_t i = 0; i < header.size(); ++i) {
        if (header[i] == "alpha_deg" || header[i] == "delta_fy_N") {
          EXPECT_EQ(row[i], "") << header[i];
        }
        if (header[i] == "period_s_1") {
          EXPECT_EQ(row[i], "0.0057");
        }
      }
    } else {
      std::getline(in, line);
      const auto j = nlohmann::json::parse(line);
      EXPECT_TRUE(j.at("alpha_deg").is_null()) << line;
      EXPECT_TRUE(j.at("delta_fy_N").is_null()) << line;
    }
    ASSERT_EQ(rec.rows().size(), 1u);
    EXPECT_TRUE(std::isnan(rec.rows()[0].alpha_deg));
    EXPECT_TRUE(std::isnan(rec.rows()[0].delta_fy_N));
  }
}

// The cutting column follows the pipeline's idle state: off from "cutting stopped", on again
// from "cutting resumed" or from a new lock (after "lock lost" the pipeline resumes there,
// without a "cutting resumed" of its own).
TEST(RunRecorder, CuttingAgainFromTheNextLock) {
  const fs::path path = test::fresh_temp_dir() / "revolutions.csv";
  RunRecorder rec(2, path, false);
  const auto event = [&](monitor::PipelineEventKind kind) {
    monitor::PipelineEvent e;
    e.kind = kind;
    rec.on_event(e);
  };
  rec.on_revolution(revolution(0, true, true));
  event(monitor::PipelineEventKind::kCuttingStopped);
  rec.on_revolution(revolution(1, false, false));
  event(monitor::PipelineEventKind::kLockLost);
  event(monitor::PipelineEventKind::kLockAcquired);
  rec.on_revolution(revolution(2, true, true));
  event(monitor::PipelineEventKind::kCuttingStopped);
  rec.on_revolution(revolution(3, false, false));
  event(monitor::PipelineEventKind::kCuttingResumed);
  rec.on_revolution(revolution(4, true, true));
  rec.commit();
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  const std::vector<std::string> header = fields(line);
  std::size_t cutting = header.size();
  for (std::size_t i = 0; i < header.size(); ++i) {
    cutting = header[i] == "cutting" ? i : cutting;
  }
  ASSERT_LT(cutting, header.size()) << line;
  std::string column;
  while (std::getline(in, line)) {
    column += fields(line)[cutting];
  }
  EXPECT_EQ(column, "10101");
}

// Rows say their lock and, after a relabelling of the flutes, which labelling they are of, in
// CSV and JSON Lines.
TEST(RunRecorder, RowsSayTheirLockAndLabelling) {
  for (const char* name : {"revolutions.csv", "revolutions.jsonl"}) {
    const fs::path path = test::fresh_temp_dir() / name;
    RunRecorder rec(2, path, false);
    monitor::PipelineEvent relabelled, locked;
    relabelled.kind = monitor::PipelineEventKind::kFlutesRelabelled;
    locked.kind = monitor::PipelineEventKind::kLockAcquired;
    rec.on_event(locked);
    rec.on_revolution(revolution(0, true, true));
    rec.on_event(relabelled);
    rec.on_event(locked);
    rec.on_revolution(revolution(1, true, true));
    rec.on_event(relabelled);
    rec.on_event(locked);
    rec.on_revolution(revolution(2, true, true));
    rec.on_event(locked);
    rec.on_revolution(revolution(3, true, true));
    rec.commit();
    std::ifstream in(path);
    std::string line, column;
    if (path.extension() == ".csv") {
      std::getline(in, line);
      const std::vector<std::string> header = fields(line);
      ASSERT_EQ(header.back(), "labelling") << line;
      ASSERT_EQ(header[header.size() - 2], "lock") << line;
      while (std::getline(in, line)) {
        const std::vector<std::string> f = fields(line);
        column += f[f.size() - 2] + f.back() + " ";
      }
    } else {
      while (std::getline(in, line)) {
        const nlohmann::json j = nlohmann::json::parse(line);
        column +=
            std::to_string(j["lock"].get<int>()) + std::to_string(j["labelling"].get<int>()) + " ";
      }
    }
    EXPECT_EQ(column, "10 21 32 42 ") << name;
  }
}

TEST(RunRecorder, ABinNoSampleReachedTakesItsNeighboursMean) {
  // 8 bins, one revolution with a sample at each bin's angle but bin 3's: bin 3 reads the mean
  // of bins 2 and 4, not 0 (which drew a spike to zero in sync_average.png).
  monitor::SyncAverage sync(8, 2);
  for (int b = 0; b < 8; ++b) {
    if (b != 3) {
      const double v = 10.0 + b;
      sync.add(2.0 * std::numbers::pi * b / 8.0, {v, v, v});
    }
  }
  sync.end_revolution();
  RunRecorder rec(2, "", true);
  rec.on_sync_average(sync, nullptr, 1, 0);
  ASSERT_EQ(rec.sync().measured[0].size(), 8u);
  EXPECT_DOUBLE_EQ(rec.sync().measured[0][2], 12.0);
  EXPECT_DOUBLE_EQ(rec.sync().measured[0][3], 13.0);
  EXPECT_DOUBLE_EQ(rec.sync().measured[1][4], 14.0);
  EXPECT_TRUE(std::isnan(rec.sync().model[0][3]));
}

}  // namespace
}  // namespace millwatch::shell
