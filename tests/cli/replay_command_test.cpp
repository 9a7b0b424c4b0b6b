// End-to-end tests of `millwatch replay` as a user runs it: a simulated cut with known truth,
// bad CSV lines, wrong headers, missing sidecars, corrupt and truncated LCM logs.

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/sim/scenario.hpp"
#include "tests/support/force_log.hpp"
#include "tests/support/recording.hpp"
#include "tests/support/run_command.hpp"
#include "tests/support/test_paths.hpp"

namespace millwatch {
namespace {

namespace fs = std::filesystem;

/// Simulates `scenario` into dir/name.csv (+ .json) with the CLI; returns the CSV path.
fs::path simulate(const fs::path& dir, const std::string& name, const nlohmann::json& scenario) {
  const fs::path s = dir / (name + "_scenario.json");
  std::ofstream(s) << scenario.dump(2);
  const fs::path csv = dir / (name + ".csv");
  const auto r =
      test::run_command(test::millwatch_cli() + " simulate " + s.string() + " -o " + csv.string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return csv;
}

nlohmann::json base_scenario() {
  return {{"recording", {{"sample_rate_hz", 50000.0}, {"duration_s", 1.0}, {"seed", 5}}},
          {"spindle", {{"actual_rpm", 25252.0}}},
          {"noise", {{"enabled", true}}}};
}

/// Rewrites a text file line by line: edit(line number from 1, line) gives the new line.
void rewrite_lines(const fs::path& path,
                   const std::function<std::string(int, const std::string&)>& edit) {
  std::ifstream in(path);
  std::stringstream out;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    out << edit(n, line) << '\n';
  }
  in.close();
  std::ofstream(path) << out.str();
}

struct ReplayRun {
  int exit_code;
  std::string log;
  nlohmann::json summary;
};

/// `millwatch replay ARGS`; without identification unless asked (the tests that do not look at
/// it run faster; identification has its own tests and SummarisesASimulatedCut runs it).
ReplayRun replay(const std::string& args, const fs::path& summary, bool identify = false) {
  const auto r = test::run_command(
      "(" + test::millwatch_cli() + " replay " + args + (identify ? "" : " --no-identify") +
      " --summary " + summary.string() + " 2>" + (summary.string() + ".log") + " >/dev/null)");
  ReplayRun out{r.exit_code, "", nullptr};
  std::stringstream log;
  log << std::ifstream(summary.string() + ".log").rdbuf();
  out.log = log.str();
  if (fs::exists(summary)) {
    out.summary = nlohmann::json::parse(std::ifstream(summary));
  }
  return out;
}

TEST(ReplayCommand, SummarisesASimulatedCutWithTheIssuesKeys) {
  const fs::path dir = test::fresh_temp_dir();
  const fs::path csv = simulate(dir, "cut", base_scenario());
  const ReplayRun r = replay(csv.string(), dir / "summary.json", true);
  ASSERT_EQ(r.exit_code, 0) << r.log;
  const auto& j = r.summary;
  for (const char* key :
       {"samples", "duration_s", "revolutions", "spindle_rpm", "spindle_rpm_commanded", "alpha_deg",
        "tooth_period_s", "peak_force_N", "delta_fy_N", "residual_rms_N", "alerts",
        "dropped_samples", "warnings"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_EQ(j["samples"], 50000);
  EXPECT_NEAR(j["spindle_rpm"].get<double>(), 25252.0, 0.0005 * 25252.0);
  EXPECT_EQ(j["spindle_rpm_commanded"], 25000.0);
  EXPECT_GT(j["revolutions"].get<int>(), 150);
  EXPECT_EQ(j["tooth_period_s"].size(), 2u);
  EXPECT_NEAR(j["tooth_period_s"][0].get<double>() + j["tooth_period_s"][1].get<double>(),
              60.0 / 25252.0, 1e-6);
  EXPECT_EQ(j["peak_force_N"]["fx"].size(), 2u);
  EXPECT_EQ(j["dropped_samples"], 0);
  EXPECT_TRUE(j["warnings"].empty());
  // The sidecar's model is the true cut: the residual is measurement noise only.
  EXPECT_LT(j["residual_rms_N"]["fx"].get<double>(), 0.02);
}

// Identification turned off (--no-identify, or identification.enabled false in the
// configuration): the summary says so, not that the record lacked a full window of revolutions
// (this one has five).
TEST(ReplayCommand, SaysIdentificationWasTurnedOff) {
  const fs::path dir = test::fresh_temp_dir();
  const fs::path csv = simulate(dir, "cut", base_scenario());
  const fs::path config = dir / "off.json";
  std::ofstream(config) << R"({"identification": {"enabled": false}})";
  const std::array<std::pair<ReplayRun, std::string>, 2> runs{
      std::pair{replay(csv.string(), dir / "flag.json"), std::string("(--no-identify)")},
      std::pair{replay(csv.string() + " --config " + config.string(), dir / "config.json", true),
                std::string("(identification.enabled is false)")}};
  for (const auto& [r, why] : runs) {
    ASSERT_EQ(r.exit_code, 0) << r.log;
    EXPECT_GT(r.summary["revolutions"].get<int>(), 150);
    int said = 0;
    for (const auto& w : r.summary["warnings"]) {
      if (w["kind"] == "no identification") {
        ++said;
        const auto detail = w["detail"].get<std::string>();
        EXPECT_NE(detail.find("identification is off " + why), std::string::npos) << detail;
        EXPECT_EQ(detail.find("need one full"), std::string::npos) << detail;
      }
    }
    EXPECT_EQ(said, 1) << why << ": " << r.summary["warnings"].dump();
  }
}

TEST(ReplayCommand, ZeroPhaseOptionMeasuresTheSameAlphaAsTheCausalFilter) {
  const fs::path dir = test::fresh_temp_dir();
  const fs::path csv = simulate(dir, "cut", base_scenario());
  const ReplayRun causal = replay(csv.string(), dir / "causal.json");
  const ReplayRun zero = replay(csv.string() + " --zero-phase", dir / "zero.json");
  ASSERT_EQ(causal.exit_code, 0) << causal.log;
  ASSERT_EQ(zero.exit_code, 0) << zero.log;
  EXPECT_EQ(causal.summary["filter"], "causal");
  EXPECT_EQ(zero.summary["filter"], "zero_phase");
  EXPECT_EQ(zero.summary["samples"], 50000);
  EXPECT_NEAR(zero.summary["revolutions"].get<double>(),
              causal.summary["revolutions"].get<double>(), 2.0);
  EXPECT_NEAR(zero.summary["alpha_deg"]["mean"].get<double>(),
              causal.summary["alpha_deg"]["mean"].get<double>(), 0.3);
  EXPECT_LT(zero.summary["residual_rms_N"]["fx"].get<double>(), 0.02);
}

TEST(ReplayCommand, BadCsvLinesAreReportedByLineAndCountedNotFatal) {
  const fs::path dir = test::fresh_temp_dir();
  const fs::path csv = simulate(dir, "cut", base_scenario());
  // Spoil lines 1001 (a word), 20001 (3 columns) and 30001 (NaN force) of the file.
  rewrite_lines(csv, [](int n, const std::string& line) -> std::string {
    if (n == 1001) {
      return "0.01998,abc,1,2";
    }
    if (n == 20001) {
      return "0.39998,1,2";
    }
    return n == 30001 ? line.substr(0, line.find(',')) + ",nan,0,0" : line;
  });
  const ReplayRun r = replay(csv.string(), dir / "summary.json");
  ASSERT_EQ(r.exit_code, 0) << r.log;
  EXPECT_NE(r.log.find(":1001: a force is not a number"), std::string::npos) << r.log;
  EXPECT_NE(r.log.find(":20001: fewer than 4 columns"), std::string::npos) << r.log;
  EXPECT_EQ(r.summary["bad_lines"], 2);
  EXPECT_EQ(r.summary["dropped_samples"], 2);  // the two skipped rows, as gaps
  EXPECT_EQ(r.summary["counters"]["nonfinite_samples"], 1);
  EXPECT_EQ(r.summary["samples"], 50000 - 2);
  EXPECT_GT(r.summary["revolutions"].get<int>(), 150);  // it kept measuring
}

// A file of which no row can be read (here a trailing comma on every row: five fields where the
// header has four) is a failed replay, said as such; it had passed with exit code 0 and a
// summary of 0 samples.
TEST(ReplayCommand, AFileWithNoReadableRowFails) {
  const fs::path dir = test::fresh_temp_dir();
  const fs::path csv = simulate(dir, "cut", base_scenario());
  rewrite_lines(csv, [](int n, const std::string& line) { return n == 1 ? line : line + ","; });
  const ReplayRun r = replay(csv.string(), dir / "summary.json");
  EXPECT_EQ(r.exit_code, 2) << r.log;
  EXPECT_NE(r.log.find("cut.csv: more bad lines follow; their number comes at the end"),
            std::string::npos)
      << r.log;
  EXPECT_NE(r.log.find("cut.csv: 50000 bad lines skipped"), std::string::npos) << r.log;
  EXPECT_NE(
      r.log.find("cut.csv: no samples to replay: all 50000 lines were bad (the first named above)"),
      std::string::npos)
      << r.log;
  EXPECT_FALSE(fs::exists(dir / "summary.json"));
}

// A record with nothing to measure in it is a failed replay that says what the file held: a CSV
// of its header alone (it had passed with exit code 0 and a summary of 0 samples; in a campaign
// table its row said "ok").
TEST(ReplayCommand, ARecordWithNoSamplesFailsAndSaysWhatItHeld) {
  const fs::path dir = test::fresh_temp_dir();
  const fs::path csv = simulate(dir, "cut", base_scenario());
  std::string header;
  std::getline(std::ifstream(csv), header);
  std::ofstream(csv) << header << '\n';
  const ReplayRun r = replay(csv.string(), dir / "summary.json");
  EXPECT_EQ(r.exit_code, 2) << r.log;
  EXPECT_NE(r.log.find("cut.csv: no samples to replay: no rows after its header"),
            std::string::npos)
      << r.log;
  EXPECT_FALSE(fs::exists(dir / "summary.json"));
}

// A file cut short mid-number reads its last row as it stands ("-8.8" for "-8.858"): that the
// last line had no end-of-line is said, with its number; a whole file says nothing.
TEST(ReplayCommand, ALastLineWithoutItsEndOfLineIsSaid) {
  const fs::path dir = test::fresh_temp_dir();
  const fs::path csv = simulate(dir, "cut", base_scenario());
  const ReplayRun whole = replay(csv.string(), dir / "whole.json");
  ASSERT_EQ(whole.exit_code, 0) << whole.log;
  EXPECT_EQ(whole.log.find("end-of-line"), std::string::npos) << whole.log;
  fs::resize_file(csv, fs::file_size(csv) - 3);  // the newline and two digits
  const ReplayRun cut = replay(csv.string(), dir / "cut.json");
  ASSERT_EQ(cut.exit_code, 0) << cut.log;
  EXPECT_NE(cut.log.find("cut.csv: line 50001, the last, has no end-of-line: if the file was cut "
                         "short there, its last number may be too (the row was read as it "
                         "stands, unless named bad above)"),
            std::string::npos)
      << cut.log;
  EXPECT_EQ(cut.summary["samples"], 50000);
}

// A sidecar given as --config (as one replaying an LCM log of a simulated cut might) is said to
// be one, with the option that takes it; it had failed on its "columns" list, "expected text".
TEST(ReplayCommand, ASidecarGivenAsTheConfigurationIsSaidToBeOne) {
  const fs::path dir = test::fresh_temp_dir();
  const fs::path csv = simulate(dir, "cut", base_scenario());
  const ReplayRun r =
      replay(csv.string() + " --config " + (dir / "cut.json").string(), dir / "summary.json");
  EXPECT_EQ(r.exit_code, 2) << r.log;
  EXPECT_NE(r.log.find("cut.json: a recording's sidecar, not a monitor configuration: give it "
                       "with --sidecar"),
            std::string::npos)
      << r.log;
}

// A damaged time column: each bad time is reported by line and what is wrong with it, and its
// row skipped like any bad row (a one-sample gap); the rest of the cut is measured. (A time of
// 1e300 used to reach the pipeline as utime −2⁶³ and overflow in InputCheck under UBSan.)
TEST(ReplayCommand, DamagedTimestampsAreReportedByLineAndSkipped) {
  const fs::path dir = test::fresh_temp_dir();
  const fs::path csv = simulate(dir, "cut", base_scenario());
  std::ifstream in(csv);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) {
    lines.push_back(line);
  }
  in.close();
  ASSERT_EQ(lines.size(), 50001u);
  auto time_of = [&](int n) { return lines[n - 1].substr(0, lines[n - 1].find(',')); };
  auto set_time = [&](int n, const std::string& t) {
    lines[n - 1] = t + lines[n - 1].substr(lines[n - 1].find(','));
  };
  set_time(2, "5.5");                          // the first row, ahead of the next
  set_time(1001, "1e300");                     // out of range
  set_time(2001, "inf");                       // not finite
  set_time(3001, "nan");                       // not finite
  set_time(4001, "1e400");                     // beyond a double: not finite
  set_time(5001, time_of(4999));               // going back
  set_time(6001, time_of(6000));               // repeated
  set_time(7001, "0.7");                       // ahead of its neighbours (0.13996 and 0.14)
  set_time(8001, "-9.3e12");                   // out of range
  lines[9000] = time_of(9001) + ",1e400,0,0";  // a force beyond a double: a non-finite sample
  std::ofstream out(csv);
  for (const auto& line : lines) {
    out << line << '\n';
  }
  out.close();

  const ReplayRun r = replay(csv.string(), dir / "summary.json");
  ASSERT_EQ(r.exit_code, 0) << r.log;
  for (const char* expected :
       {"cut.csv:2: t_s 5.5 jumps ahead of the rows around it (2e-05 on line 3); skipped",
        "cut.csv:1001: t_s 1e+300 is out of range (more than 9007199254.740992 s from 0); skipped",
        "cut.csv:2001: t_s is not finite (inf); skipped",
        "cut.csv:3001: t_s is not finite (nan); skipped",
        "cut.csv:4001: t_s is not finite (1e400); skipped",
        "cut.csv:5001: t_s 0.09994 is not after the previous row's (0.09996 on line 5000); skipped",
        "cut.csv:6001: t_s 0.11996 is not after the previous row's (0.11996 on line 6000); skipped",
        "cut.csv:7001: t_s 0.7 jumps ahead of the rows around it "
        "(0.13996 on line 7000, 0.14 on line 7002); skipped",
        "cut.csv:8001: t_s -9.3e+12 is out of range"}) {
    EXPECT_NE(r.log.find(expected), std::string::npos) << expected << "\n" << r.log;
  }
  EXPECT_EQ(r.log.find("runtime error"), std::string::npos) << r.log;
  EXPECT_EQ(r.summary["bad_lines"], 9);
  EXPECT_EQ(r.summary["samples"], 50000 - 9);
  EXPECT_EQ(r.summary["dropped_samples"], 8);  // one-row gaps; the first row is before the start
  EXPECT_EQ(r.summary["counters"]["gaps"], 8);
  EXPECT_EQ(r.summary["counters"]["blocks_rejected"], 0);
  EXPECT_EQ(r.summary["counters"]["out_of_order_blocks"], 0);
  EXPECT_EQ(r.summary["counters"]["nonfinite_samples"], 1);
  EXPECT_GT(r.summary["revolutions"].get<int>(), 150);  // it kept measuring
}

TEST(ReplayCommand, WrongHeaderOrMissingSidecarFailsWithAClearMessage) {
  const fs::path dir = test::fresh_temp_dir();
  const fs::path csv = simulate(dir, "cut", base_scenario());
  std::ofstream(dir / "bad.csv") << "time,fx,fy,fz\n0,1,2,3\n";
  fs::copy_file(dir / "cut.json", dir / "bad.json");
  ReplayRun r = replay((dir / "bad.csv").string(), dir / "s1.json");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.log.find("bad.csv:1: header is \"time,fx,fy,fz\"; expected \"t_s,fx_N,fy_N,fz_N\""),
            std::string::npos)
      << r.log;
  fs::copy_file(csv, dir / "lonely.csv");
  r = replay((dir / "lonely.csv").string(), dir / "s2.json");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.log.find("lonely.json: sidecar not found"), std::string::npos) << r.log;
  // A sidecar with a bad field names it.
  nlohmann::json sidecar = nlohmann::json::parse(std::ifstream(dir / "cut.json"));
  sidecar["model"]["tool"]["flutes"] = 0;
  std::ofstream(dir / "zero.json") << sidecar.dump();
  fs::copy_file(csv, dir / "zero.csv");
  r = replay((dir / "zero.csv").string(), dir / "s3.json");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.log.find("zero.json: model.tool.flutes: value 0 is out of range [1, 8]"),
            std::string::npos)
      << r.log;
  EXPECT_FALSE(fs::exists(dir / "s3.json"));  // no partial summary
  // `replay cut.csv --json > cut.json`: the shell empties the default sidecar before replay
  // reads it; said as such, not as a JSON syntax error at line 1.
  std::ofstream(dir / "emptied.json").close();
  fs::copy_file(csv, dir / "emptied.csv");
  r = replay((dir / "emptied.csv").string(), dir / "s4.json");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.log.find("emptied.json: empty, and read as emptied.csv's sidecar"), std::string::npos)
      << r.log;
  // With --config describing the cut the emptied file is left out, as a missing one is.
  std::ofstream(dir / "monitor.json") << R"({"monitor": {"sample_rate_hz": 50000}})";
  r = replay((dir / "emptied.csv").string() + " --config " + (dir / "monitor.json").string(),
             dir / "s5.json");
  EXPECT_EQ(r.exit_code, 0) << r.log;
  EXPECT_NE(r.log.find("emptied.json: empty, left out"), std::string::npos) << r.log;
  // A summary's folder that is not there fails before the replay, not after it.
  const auto missing =
      test::run_command(test::millwatch_cli() + " replay --no-identify " + csv.string() +
                        " --summary " + (dir / "nowhere" / "s.json").string() + " 2>&1");
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.output.find(": no folder "), std::string::npos) << missing.output;
  EXPECT_EQ(missing.output.find("spindle locked"), std::string::npos) << missing.output;
  // Nor a summary that is a folder, nor plots that are a file (the whole replay had run first,
  // then "cannot rename …partial" or the library's "filesystem error").
  fs::create_directories(dir / "afolder");
  std::ofstream(dir / "afile") << "x";
  for (const auto& [args, said] :
       {std::pair{" --summary " + (dir / "afolder").string(), ": a folder; one cut writes a file"},
        std::pair{" --plot " + (dir / "afile").string(), ": a file, not a folder for the plots"},
        std::pair{" --summary " + (dir / "afile").string() + " " + csv.string(),
                  ": cannot make the folder for the cuts"}}) {
    const auto early = test::run_command(test::millwatch_cli() + " replay --no-identify " +
                                         csv.string() + args + " 2>&1");
    EXPECT_NE(early.exit_code, 0) << args;
    EXPECT_NE(early.output.find(said), std::string::npos) << early.output;
    EXPECT_EQ(early.output.find("spindle locked"), std::string::npos) << early.output;
  }
}

// A sidecar whose sample rate the CSV's time column belies (100 kHz said, the times step at
// 50 kHz) is read at the time column's rate, with a warning: before, every other sample was a
// "gap" (0.5 s of a 1 s cut, 24,999 gaps and a sensor alert) and α moved. A rate that is no rate
// is refused with the field named, as the daemon's check refuses it (replay had read over it).
TEST(ReplayCommand, ARateTheTimeColumnBeliesGivesWayAndOneThatIsNoRateIsRefused) {
  const fs::path dir = test::fresh_temp_dir();
  const fs::path csv = simulate(dir, "cut", base_scenario());
  const ReplayRun right = replay(csv.string(), dir / "right.json");
  ASSERT_EQ(right.exit_code, 0) << right.log;
  nlohmann::json sidecar = nlohmann::json::parse(std::ifstream(dir / "cut.json"));
  sidecar["sample_rate_hz"] = 100000.0;
  std::ofstream(dir / "fast.json") << sidecar.dump();
  fs::copy_file(csv, dir / "fast.csv");
  const ReplayRun fast = replay((dir / "fast.csv").string(), dir / "fast_summary.json");
  ASSERT_EQ(fast.exit_code, 0) << fast.log;
  EXPECT_NE(fast.log.find("the recording's rate is 50000 Hz (stated, or its time column's steps)"),
            std::string::npos)
      << fast.log;
  EXPECT_NE(fast.log.find("fast.json says 100000 Hz; using the recording's"), std::string::npos)
      << fast.log;
  EXPECT_EQ(fast.summary["samples"], right.summary["samples"]);
  EXPECT_EQ(fast.summary["sample_rate_hz"], 50000.0);
  // The summary says it too: one who keeps only the summary had no trace of the rate set aside.
  EXPECT_NE(test::warning_detail(fast.summary["warnings"], "rate overridden")
                .find("fast.json says 100000 Hz; using the recording's"),
            std::string::npos)
      << fast.summary["warnings"].dump();
  EXPECT_EQ(test::warning_detail(right.summary["warnings"], "rate overridden"), "");
  EXPECT_EQ(fast.summary["dropped_samples"], 0);
  EXPECT_EQ(fast.summary["alpha_deg"]["mean"], right.summary["alpha_deg"]["mean"]);
  for (const char* bad : {"\"fifty\"", "0", "null"}) {
    sidecar["sample_rate_hz"] = nlohmann::json::parse(bad);
    std::ofstream(dir / "bad.json") << sidecar.dump();
    fs::copy_file(csv, dir / "bad.csv", fs::copy_options::overwrite_existing);
    const ReplayRun r = replay((dir / "bad.csv").string(), dir / "bad_summary.json");
    EXPECT_NE(r.exit_code, 0) << bad;
    EXPECT_NE(r.log.find("bad.json: sample_rate_hz: "), std::string::npos) << bad << r.log;
  }
  // The same for a text without a time column, whose rate only the configuration gives (it had
  // been "no time column and no sample rate", the bad value unnamed).
  {
    std::ofstream out(dir / "forces.txt");
    out << "Fx Fy Fz\n";
    for (int i = 0; i < 100; ++i) {
      out << i << " " << -i << " 0.5\n";
    }
  }
  for (const char* bad : {"\"fifty\"", "0", "null"}) {
    std::ofstream(dir / "rate.json") << R"({"monitor": {"sample_rate_hz": )" << bad << "}}";
    const ReplayRun r =
        replay((dir / "forces.txt").string() + " --columns fx=1,fy=2,fz=3 --config " +
                   (dir / "rate.json").string(),
               dir / "text_summary.json");
    EXPECT_EQ(r.exit_code, 2) << bad;
    EXPECT_NE(r.log.find("rate.json: sample_rate_hz: "), std::string::npos) << bad << r.log;
  }
}

/// The simulated cut's raw blocks in an LCM log, as lcm-logger records them.
fs::path write_log(const fs::path& dir, double duration_s) {
  sim::Scenario s;
  s.sample_rate_hz = 50000.0;
  s.duration_s = duration_s;
  s.spindle.actual_rpm = 25252.0;
  const fs::path path = dir / "raw.lcmlog";
  test::write_force_log(path, s, 1000);
  return path;
}

fs::path monitor_config(const fs::path& dir) {
  const nlohmann::json c = {{"monitor", {{"sample_rate_hz", 50000.0}}}};
  std::ofstream(dir / "monitor.json") << c.dump();
  return dir / "monitor.json";
}

TEST(ReplayCommand, ReplaysAnLcmLogAndSurvivesCorruptionAndTruncation) {
  const fs::path dir = test::fresh_temp_dir();
  const fs::path log = write_log(dir, 1.0);
  const fs::path config = monitor_config(dir);
  ReplayRun whole = replay(log.string() + " --config " + config.string(), dir / "whole.json");
  ASSERT_EQ(whole.exit_code, 0) << whole.log;
  EXPECT_EQ(whole.summary["samples"], 50000);
  EXPECT_NEAR(whole.summary["spindle_rpm"].get<double>(), 25252.0, 0.0005 * 25252.0);

  // Damage the log the ways a disk or a killed logger does: samples scribbled over inside event
  // 10, event 20's sync word and event 30's channel length broken, the last event cut short.
  std::string bytes;
  {
    std::ifstream in(log, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const std::string sync = "\xED\xA1\xDA\x01";
  std::vector<std::size_t> starts;
  for (std::size_t at = bytes.find(sync); at != std::string::npos; at = bytes.find(sync, at + 1)) {
    starts.push_back(at);
  }
  ASSERT_EQ(starts.size(), 50u);
  std::string spoiled = bytes.substr(0, bytes.size() - (bytes.size() - starts.back()) / 2);
  for (std::size_t i = starts[10] + 200; i < starts[10] + 240; ++i) {
    spoiled[i] = '\x7f';  // eight samples become NaN
  }
  spoiled[starts[20] + 1] = '\0';                           // sync word
  spoiled.replace(starts[30] + 20, 4, "\x7f\x00\x00\x00");  // channel length
  std::ofstream(dir / "bad.lcmlog", std::ios::binary) << spoiled;
  ReplayRun bad =
      replay((dir / "bad.lcmlog").string() + " --config " + config.string(), dir / "bad.json");
  ASSERT_EQ(bad.exit_code, 0) << bad.log;
  EXPECT_EQ(bad.summary["samples"], 47000);                    // events 20, 30 and 50 lost, no more
  EXPECT_EQ(bad.summary["dropped_samples"], 2000);             // events 20 and 30, as gaps
  EXPECT_EQ(bad.summary["counters"]["nonfinite_samples"], 5);  // 40 bytes: 5 whole doubles
  EXPECT_EQ(bad.summary["bad_lines"], 3);  // two broken headers and the truncated end
  // Only the damaged events are lost: reading resumes at the next event.
  EXPECT_NE(bad.log.find("bad.lcmlog:21: unreadable event at byte " + std::to_string(starts[20]) +
                         "; " + std::to_string(starts[21] - starts[20]) + " bytes skipped"),
            std::string::npos)
      << bad.log;
  EXPECT_NE(bad.log.find("bad.lcmlog:30: unreadable event at byte " + std::to_string(starts[30])),
            std::string::npos)
      << bad.log;
  EXPECT_NE(bad.log.find("log ends inside an event"), std::string::npos) << bad.log;
  EXPECT_GT(bad.summary["revolutions"].get<int>(), 100);
  EXPECT_NEAR(bad.summary["spindle_rpm"].get<double>(), 25252.0, 0.0005 * 25252.0);
}

// A log whose events are all on other channels than --channel's (a mistyped channel, a log of
// results alone) is a failed replay naming the channels it does hold; it had read as an empty
// record, exit code 0.
TEST(ReplayCommand, ALogWithoutTheRawChannelFailsAndNamesTheChannelsItHolds) {
  const fs::path dir = test::fresh_temp_dir();
  const fs::path log = write_log(dir, 0.2);
  const ReplayRun r = replay(
      log.string() + " --config " + monitor_config(dir).string() + " --channel FORCE_RAW_TYPO",
      dir / "summary.json");
  EXPECT_EQ(r.exit_code, 2) << r.log;
  EXPECT_NE(r.log.find("raw.lcmlog: no samples to replay: no event on channel FORCE_RAW_TYPO; "
                       "the log holds MILLWATCH_FORCE_RAW (10 events) (--channel names the "
                       "log's raw channel)"),
            std::string::npos)
      << r.log;
  EXPECT_FALSE(fs::exists(dir / "summary.json"));  // no summary of a replay that failed
}

// Well-framed events whose force_block_t is malformed (a sample count that wraps lcm-gen's size
// check, a negative count, a count that does not match the length) are reported by event and
// reason and skipped before they are decoded; the rest of the log is measured. (The wrapped
// count made lcm-gen's decode read past the event's buffer: ASan heap-buffer-overflow.)
TEST(ReplayCommand, MalformedRawBlocksInALogAreReportedAndSkipped) {
  const fs::path dir = test::fresh_temp_dir();
  const fs::path log = write_log(dir, 1.0);
  std::string bytes;
  {
    std::ifstream in(log, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const std::string sync = "\xED\xA1\xDA\x01";
  std::vector<std::size_t> starts;
  for (std::size_t at = bytes.find(sync); at != std::string::npos; at = bytes.find(sync, at + 1)) {
    starts.push_back(at);
  }
  ASSERT_EQ(starts.size(), 50u);
  // An event: 28-byte header, the channel's 19 bytes, then the message; its num_samples is at
  // byte 32 of the message (msgs/force_block_check.hpp).
  auto set_count = [&](std::size_t event, std::uint32_t n) {
    const std::size_t at = starts[event] + 28 + 19 + 32;
    for (int i = 0; i < 4; ++i) {
      bytes[at + static_cast<std::size_t>(i)] = static_cast<char>(n >> (24 - 8 * i));
    }
  };
  set_count(10, (1u << 28) + 1);  // 8 · n wraps lcm-gen's int size check
  set_count(20, 0xFFFFFFFFu);     // −1
  set_count(30, 999);             // 24 bytes short of what the event holds
  std::ofstream(dir / "bad.lcmlog", std::ios::binary) << bytes;
  const ReplayRun r =
      replay((dir / "bad.lcmlog").string() + " --config " + monitor_config(dir).string(),
             dir / "bad.json");
  ASSERT_EQ(r.exit_code, 0) << r.log;
  auto expect_line = [&](int event, const std::string& reason) {
    const std::string line = "bad.lcmlog:" + std::to_string(event) +
                             ": event on MILLWATCH_FORCE_RAW of 24036 bytes does not decode as "
                             "millwatch.force_block_t: ";
    EXPECT_NE(r.log.find(line + reason + "; skipped"), std::string::npos) << line << reason << "\n"
                                                                          << r.log;
  };
  expect_line(11,
              "36 + 24 x 268435457 = 6442451004 bytes expected for num_samples 268435457, "
              "got 24036");
  expect_line(21, "num_samples -1 is negative");
  expect_line(31, "36 + 24 x 999 = 24012 bytes expected for num_samples 999, got 24036");
  EXPECT_EQ(r.log.find("runtime error"), std::string::npos) << r.log;
  EXPECT_EQ(r.summary["bad_lines"], 3);
  EXPECT_EQ(r.summary["samples"], 47000);
  EXPECT_EQ(r.summary["dropped_samples"], 3000);  // as gaps
  EXPECT_EQ(r.summary["counters"]["gaps"], 3);
  EXPECT_GT(r.summary["revolutions"].get<int>(), 100);
}

// A recording nothing describes (no sidecar beside it, a configuration without "model") is
// replayed with the built-in model, and the summary says so and which: a cut of another tool
// or speed is then missed with nothing to say why.
TEST(ReplayCommand, ACutNothingDescribesSaysTheModelAssumed) {
  const fs::path dir = test::fresh_temp_dir();
  nlohmann::json s = base_scenario();
  s["recording"]["duration_s"] = 0.3;
  const fs::path csv = simulate(dir, "bare", s);
  const nlohmann::json sidecar =
      nlohmann::json::parse(std::ifstream(fs::path(csv).replace_extension(".json")));
  fs::remove(fs::path(csv).replace_extension(".json"));
  std::ofstream(dir / "rate_only.json")
      << nlohmann::json{{"sample_rate_hz", sidecar["sample_rate_hz"]}}.dump();
  const ReplayRun r =
      replay(csv.string() + " --config " + (dir / "rate_only.json").string(), dir / "s.json");
  ASSERT_EQ(r.exit_code, 0) << r.log;
  std::string detail;
  for (const auto& w : r.summary["warnings"]) {
    if (w["kind"] == "cut not described") {
      detail = w["detail"].get<std::string>();
    }
  }
  EXPECT_NE(detail.find("no sidecar beside the recording; "), std::string::npos) << detail;
  EXPECT_NE(detail.find("rate_only.json has no \"model\"): the built-in model is assumed, a 0.4 "
                        "mm 2-flute tool at 25000 rpm"),
            std::string::npos)
      << detail;
  // With the sidecar, nothing is assumed.
  std::ofstream(fs::path(csv).replace_extension(".json")) << sidecar.dump();
  const ReplayRun described = replay(csv.string(), dir / "d.json");
  ASSERT_EQ(described.exit_code, 0) << described.log;
  for (const auto& w : described.summary["warnings"]) {
    EXPECT_NE(w["kind"], "cut not described");
  }
}

// --publish says what it published and dropped (the daemon's log does; the replay had said
// nothing, a full-speed replay's publisher dropping some unsaid).
TEST(ReplayCommand, PublishingSaysHowManyMessagesWentOut) {
  const fs::path dir = test::fresh_temp_dir();
  nlohmann::json s = base_scenario();
  s["recording"]["duration_s"] = 0.3;
  const fs::path csv = simulate(dir, "published", s);
  const ReplayRun r = replay(csv.string() + " --no-identify --publish 'file://" +
                                 (dir / "out.lcmlog").string() + "?mode=w'",
                             dir / "s.json");
  ASSERT_EQ(r.exit_code, 0) << r.log;
  const std::size_t at = r.log.find(" messages published, ");
  ASSERT_NE(at, std::string::npos) << r.log;
  const std::size_t from = r.log.rfind(' ', at - 1) + 1;
  EXPECT_GT(std::stol(r.log.substr(from, at - from)), r.summary["revolutions"].get<long>());
  EXPECT_GT(fs::file_size(dir / "out.lcmlog"), 1000u);
}

TEST(ReplayCommand, PacesAtRealTimeWhenAsked) {
  const fs::path dir = test::fresh_temp_dir();
  nlohmann::json s = base_scenario();
  s["recording"]["duration_s"] = 0.4;
  const fs::path csv = simulate(dir, "short", s);
  const auto start = std::chrono::steady_clock::now();
  const ReplayRun r = replay(csv.string() + " --speed 2", dir / "s.json");
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_EQ(r.exit_code, 0) << r.log;
  EXPECT_GT(elapsed, 0.2 * 0.95);  // 0.4 s of data at twice real time
}

TEST(ReplayCommand, SigintEndsAPacedReplayWithASummaryOfWhatWasReplayed) {
  const fs::path dir = test::fresh_temp_dir();
  const fs::path csv = simulate(dir, "long", base_scenario());  // 1 s, 50,000 samples
  // At real time the replay is still reading when SIGINT comes 0.5 s in; a signal that killed
  // it, or a read it cut short and called an error, would leave no summary.
  const fs::path summary = dir / "s.json";
  const auto r = test::run_command("(" + test::millwatch_cli() + " replay " + csv.string() +
                                   " --realtime --no-identify --no-progress --summary " +
                                   summary.string() + " >/dev/null 2>" + summary.string() +
                                   ".log & pid=$!; sleep 0.5; kill -INT $pid; wait $pid)");
  std::stringstream log;
  log << std::ifstream(summary.string() + ".log").rdbuf();
  // 128 + SIGINT, as a shell reports a command the signal ended: its output is partial.
  ASSERT_EQ(r.exit_code, 130) << log.str();
  EXPECT_NE(log.str().find("interrupted: the summary covers the samples replayed so far"),
            std::string::npos)
      << log.str();
  ASSERT_TRUE(fs::exists(summary)) << log.str();
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(summary));
  EXPECT_GT(j["samples"].get<int>(), 5000) << j.dump(1).substr(0, 1000);
  EXPECT_LT(j["samples"].get<int>(), 50000) << j.dump(1).substr(0, 1000);
  // The summary says it is partial (it had said "warnings: none" for part of a record).
  bool said = false;
  for (const auto& w : j["warnings"]) {
    if (w["kind"] == "interrupted") {
      said = true;
      const std::string detail = w["detail"].get<std::string>();
      EXPECT_NE(detail.find("stopped by SIGINT after 0."), std::string::npos) << detail;
      EXPECT_NE(detail.find(std::to_string(j["samples"].get<int>()) + " samples read"),
                std::string::npos)
          << detail;
    }
  }
  EXPECT_TRUE(said) << j["warnings"];
}

}  // namespace
}  // namespace millwatch
