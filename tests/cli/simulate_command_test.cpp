// End-to-end tests of `millwatch simulate` as a user runs it.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>

#include "tests/support/run_command.hpp"
#include "tests/support/test_paths.hpp"

namespace millwatch {
namespace {

namespace fs = std::filesystem;

fs::path write_file(const fs::path& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

TEST(SimulateCommand, WritesCsvAndSidecarForEveryPreset) {
  const fs::path dir = test::fresh_temp_dir();
  for (const auto& entry : fs::directory_iterator(test::source_dir() / "config" / "presets")) {
    const fs::path csv = dir / (entry.path().stem().string() + ".csv");
    const auto r = test::run_command(test::millwatch_cli() + " simulate " + entry.path().string() +
                                     " --duration 0.05 -o " + csv.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    std::ifstream in(csv);
    std::string header, first;
    std::getline(in, header);
    std::getline(in, first);
    EXPECT_EQ(header, "t_s,fx_N,fy_N,fz_N");
    EXPECT_EQ(first.rfind("0.000000000,", 0), 0u) << first;
    fs::path sidecar = csv;
    sidecar.replace_extension(".json");
    std::ifstream sj(sidecar);
    const auto j = nlohmann::json::parse(sj);
    EXPECT_EQ(j["format"], "millwatch-cut/1");
    EXPECT_EQ(j["csv"], csv.filename().string());
    for (const char* key : {"diameter_mm", "flutes", "helix_deg", "edge_radius_um"}) {
      EXPECT_TRUE(j["tool"].contains(key)) << key;
    }
    for (const char* key :
         {"operation", "spindle_rpm", "feed_per_tooth_um", "axial_depth_mm", "radial_depth_mm"}) {
      EXPECT_TRUE(j["process"].contains(key)) << key;
    }
    EXPECT_TRUE(j.contains("sample_rate_hz"));
    EXPECT_TRUE(j["material"].contains("law"));
    EXPECT_TRUE(j["force_sign_convention"].contains("axis_map"));
    // The truth per revolution in its own file, which the sidecar names (a replay reads the
    // sidecar, not the truth).
    EXPECT_FALSE(j["truth"].contains("revolutions"));
    EXPECT_TRUE(j["truth"].contains("spindle_rpm_actual"));
    // What the model's steady states played were like, said where they were not the model's
    // steady state revolution by revolution (the cp-Ti preset's cycle outgrows 64 revolutions:
    // CutSimulator.SaysWhenTheModelsCycleIsPlayedRoundAgain).
    const auto& played = j["truth"]["model_steady_state"];
    ASSERT_TRUE(played.is_object()) << j["truth"].dump();
    EXPECT_GE(played["evaluations"].get<int>(), 1);
    EXPECT_GE(played["longest_cycle_revolutions"].get<int>(), 1);
    const bool as_is = played["revolutions_round_again"].get<long>() == 0 &&
                       played["unsettled_slots"].get<int>() == 0;
    EXPECT_EQ(played["notes"].empty(), as_is) << played.dump();
    EXPECT_NE(r.output.find("model cycle"), std::string::npos) << r.output;
    if (entry.path().stem() == "cpti_masrani2023") {
      EXPECT_EQ(played["cycles_cut"], 1) << played.dump();
    }
    ASSERT_EQ(j["truth"]["revolutions_file"], entry.path().stem().string() + ".truth.json");
    std::ifstream tj(dir / j["truth"]["revolutions_file"].get<std::string>());
    const auto truth = nlohmann::json::parse(tj);
    EXPECT_EQ(truth["spindle_rpm_actual"], j["truth"]["spindle_rpm_actual"]);
    const auto& rpm = truth["revolutions"]["spindle_rpm"];
    ASSERT_FALSE(rpm.empty());
    // A cut cycle's revolutions from the 65th on replay the first 64 (the truth lists the
    // revolutions the record reached, each cutting in a preset).
    const long beyond = std::max(0L, static_cast<long>(rpm.size()) - 64);
    const long round_again = played["revolutions_round_again"].get<long>();
    if (played["cycles_cut"].get<int>() > 0) {
      EXPECT_EQ(round_again, beyond) << played.dump();
    } else {
      EXPECT_EQ(round_again, 0) << played.dump();
    }
    EXPECT_EQ(truth["revolutions"]["start_s"].size(), rpm.size());
    // A revolution takes 60/rpm s: the starts (on samples) are that far apart.
    if (rpm.size() >= 2) {
      EXPECT_NEAR(truth["revolutions"]["start_s"][1].get<double>() -
                      truth["revolutions"]["start_s"][0].get<double>(),
                  60.0 / rpm[0].get<double>(), 1.0 / j["sample_rate_hz"].get<double>());
    }
    EXPECT_EQ(
        j["samples"].get<long>() + 1,
        static_cast<long>(std::count(std::istreambuf_iterator<char>(std::ifstream(csv).rdbuf()),
                                     std::istreambuf_iterator<char>(), '\n')));
  }
}

// A record longer than a cut cycle (the cp-Ti preset's outgrows 64 revolutions; 0.3 s is 126)
// says, in the summary and the truth, how many of its revolutions replay the first 64.
TEST(SimulateCommand, SaysWhenTheModelsCycleIsPlayedRoundAgain) {
  const fs::path dir = test::fresh_temp_dir();
  const fs::path csv = dir / "cpti.csv";
  const auto r = test::run_command(
      test::millwatch_cli() + " simulate " +
      (test::source_dir() / "config" / "presets" / "cpti_masrani2023.json").string() +
      " --duration 0.3 -o " + csv.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("play the first 64 round again"), std::string::npos) << r.output;
  std::ifstream tj(dir / "cpti.truth.json");
  const auto truth = nlohmann::json::parse(tj);
  const auto& played = truth["model_steady_state"];
  const auto revolutions = static_cast<long>(truth["revolutions"]["start_s"].size());
  EXPECT_EQ(played["cycles_cut"], 1) << played.dump();
  // Each revolution from the 65th on (the truth lists those the record reached).
  EXPECT_EQ(played["revolutions_round_again"].get<long>(), revolutions - 64) << played.dump();
  ASSERT_EQ(played["notes"].size(), 1U) << played.dump();

  // h_min 3 µm for a 4 µm feed on a tool 5x softer: some slots' accumulation has no period
  // (a flute cuts every 4 or 5 revolutions, in no fixed order), and the truth says how many.
  std::ifstream in(test::source_dir() / "config" / "presets" / "cpti_masrani2023.json");
  nlohmann::json soft = nlohmann::json::parse(in);
  soft["model"]["effects"]["min_chip"]["h_min_um"] = 3.0;
  soft["model"]["effects"]["deflection"]["stiffness_N_per_um"] = 0.1;
  const fs::path soft_csv = dir / "soft.csv";
  const auto rs = test::run_command(test::millwatch_cli() + " simulate " +
                                    write_file(dir / "soft_scenario.json", soft.dump()).string() +
                                    " --duration 0.05 -o " + soft_csv.string());
  ASSERT_EQ(rs.exit_code, 0) << rs.output;
  EXPECT_NE(rs.output.find("did not repeat within 600 revolutions"), std::string::npos)
      << rs.output;
  std::ifstream sj(dir / "soft.truth.json");
  const auto soft_played = nlohmann::json::parse(sj)["model_steady_state"];
  EXPECT_GT(soft_played["unsettled_slots"].get<int>(), 0) << soft_played.dump();
  EXPECT_EQ(soft_played["slots"], 7200) << soft_played.dump();  // 10 discs, 720 steps
}

// Bad input: a clear error naming the field, value and range; non-zero exit; no files left.
TEST(SimulateCommand, BadScenarioFailsCleanlyWithoutPartialOutput) {
  const fs::path dir = test::fresh_temp_dir();
  struct Case {
    std::string json;
    std::string expected;
    std::string options = "";  // on the command line
  };
  const Case cases[] = {
      // The command line's overrides are checked as the file's values are (a --duration of 1e9
      // had died of bad_alloc, 3601 s had run for minutes, 1e-9 s written a recording of no
      // sample).
      {"{}", "with --duration 1000000000: recording.duration_s: value 1000000000 is out of range",
       "--duration 1e9"},
      {"{}", "with --duration 3601: recording.duration_s: value 3601 is out of range (0, 3600] s",
       "--duration 3601"},
      {"{}", "recording.duration_s: value 1e-09 s is shorter than one sample at 50000 Hz",
       "--duration 1e-9"},
      {R"({"model": {"tool": {"diameter_mm": -0.4}}})",
       "model.tool.diameter_mm: value -0.4 is out of range (0, 50] mm"},
      {R"({"model": {"tool": {"flutes": 0}}})",
       "model.tool.flutes: value 0 is out of range [1, 8]"},
      {R"({"model": {"process": {"spindle_rpm": 1e999}}})",
       "model.process.spindle_rpm: value 1e999 is not a finite number"},
      {R"({"recording": {"duration_s": "long"}})",
       "recording.duration_s: expected a number, got string \"long\""},
      {R"({"recording": {"sample_rate": 50000}})", "recording.sample_rate: unknown key"},
      {R"({"model": {"tool": {"diameter_mm": 0.4,}})", "JSON syntax error at line 1"},
  };
  int i = 0;
  for (const auto& c : cases) {
    const fs::path scenario = write_file(dir / ("bad" + std::to_string(i) + ".json"), c.json);
    const fs::path csv = dir / ("out" + std::to_string(i) + ".csv");
    const auto r = test::run_command(test::millwatch_cli() + " simulate " + scenario.string() +
                                     " -o " + csv.string() + " " + c.options);
    EXPECT_NE(r.exit_code, 0) << c.json;
    EXPECT_NE(r.output.find(c.expected), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(scenario.filename().string()), std::string::npos) << r.output;
    ++i;
  }
  // Nothing but the scenarios remains: no CSV, sidecar or .partial file.
  for (const auto& entry : fs::directory_iterator(dir)) {
    EXPECT_EQ(entry.path().extension(), ".json") << entry.path();
    EXPECT_EQ(entry.path().stem().string().rfind("bad", 0), 0u) << entry.path();
  }
}

// A number option that is not one says so in a line (CLI11's own check printed its range up to
// DBL_MAX, 309 digits).
TEST(SimulateCommand, ANumberOptionThatIsNoneSaysSoPlainly) {
  const std::string scenario = (test::source_dir() / "config" / "demo.json").string();
  const std::pair<const char*, const char*> cases[] = {
      {"--duration 0", "--duration: 0 is not a positive number"},
      {"--duration abc", "--duration: \"abc\" is not a number"},
      {"--seed -3", "--seed: -3 is not a non-negative whole number"},
      {"--seed 1.5", "--seed: \"1.5\" is not a whole number"}};
  for (const auto& [option, said] : cases) {
    // Appended, not a chain of +: GCC 12 warns (-Warray-bounds) on the chain's inlined copies.
    std::string command = test::millwatch_cli();
    command.append(" simulate ").append(scenario).append(" ").append(option);
    command.append(" -o /tmp/never.csv 2>&1");
    const auto r = test::run_command(command);
    EXPECT_NE(r.exit_code, 0) << option;
    EXPECT_NE(r.output.find(said), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("17976931348623157"), std::string::npos) << r.output;
  }
}

// `simulate cut.json -o cut.csv` had written the sidecar (cut.json) over the scenario it read:
// refused, the scenario left as it was, whichever way the paths are spelled; --truth-json too.
TEST(SimulateCommand, RefusesToWriteOverTheScenarioItReads) {
  const fs::path dir = test::fresh_temp_dir();
  const fs::path scenario = dir / "cut.json";
  fs::copy_file(test::source_dir() / "config" / "demo.json", scenario);
  const auto original = fs::file_size(scenario);
  const std::string simulate =
      test::millwatch_cli() + " simulate " + scenario.string() + " --duration 0.01 ";
  const std::pair<std::string, std::string> cases[] = {
      {"-o " + (dir / "cut.csv").string(),
       "its sidecar would go to " + (dir / "cut.json").string() +
           ", the scenario being read: name the output otherwise (e.g. -o " +
           (dir / "cut_cut.csv").string() + ")"},
      {"-o " + (dir / "sub" / ".." / "cut.csv").string(), "the scenario being read"},
      {"-o " + (dir / "other.csv").string() + " --truth-json " + scenario.string(),
       "--truth-json " + scenario.string() + ": the scenario being read"}};
  fs::create_directory(dir / "sub");
  for (const auto& [options, said] : cases) {
    const auto r = test::run_command(simulate + options + " 2>&1");
    EXPECT_EQ(r.exit_code, 2) << options;
    EXPECT_NE(r.output.find(said), std::string::npos) << r.output;
    EXPECT_EQ(fs::file_size(scenario), original);
  }
  EXPECT_FALSE(fs::exists(dir / "cut.csv"));
  EXPECT_FALSE(fs::exists(dir / "other.csv"));
}

// A recording that the monitor would refuse as its sidecar describes it (1 kHz: below the
// default 3.3 kHz low-pass's reach) is written, with a warning naming why; it had been written
// silently and replay then named a key that was in neither file.
TEST(SimulateCommand, WarnsWhenReplayWouldRefuseTheRecording) {
  const fs::path dir = test::fresh_temp_dir();
  nlohmann::json s =
      nlohmann::json::parse(std::ifstream(test::source_dir() / "config" / "demo.json"));
  s["recording"]["sample_rate_hz"] = 1000.0;
  write_file(dir / "slow.json", s.dump());
  const auto r =
      test::run_command(test::millwatch_cli() + " simulate " + (dir / "slow.json").string() +
                        " --duration 0.2 -o " + (dir / "cut.csv").string() + " 2>&1");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("cut.json: replay will refuse this recording as its sidecar describes "
                          "it (filter.cutoff_hz: value 3300 Hz (the default) must stay below "
                          "0.45 x the sample rate (450 Hz)); set the value in replay's --config"),
            std::string::npos)
      << r.output;
  EXPECT_TRUE(fs::exists(dir / "cut.csv"));
  // The demo itself replays as it is: no such warning.
  const auto demo =
      test::run_command(test::millwatch_cli() + " simulate " +
                        (test::source_dir() / "config" / "demo.json").string() +
                        " --duration 0.05 -o " + (dir / "demo.csv").string() + " 2>&1");
  EXPECT_EQ(demo.exit_code, 0) << demo.output;
  EXPECT_EQ(demo.output.find("replay will refuse"), std::string::npos) << demo.output;
  // 0.05 s at 25,252 rpm holds 21.04 turns: said as such (a 1 ms record had read "1 revolutions"
  // for 0.42 of one).
  EXPECT_NE(demo.output.find("= 0.050 s, 21 revolutions\n"), std::string::npos) << demo.output;
  const auto tiny =
      test::run_command(test::millwatch_cli() + " simulate " +
                        (test::source_dir() / "config" / "demo.json").string() +
                        " --duration 0.001 -o " + (dir / "tiny.csv").string() + " 2>&1");
  EXPECT_NE(tiny.output.find("= 0.001 s, 0.42 revolutions\n"), std::string::npos) << tiny.output;
  // A ramp from 20,000 to 30,000 rpm over the 0.2 s record: 83.3 turns, each at its own speed
  // (its starting speed alone would have given 67).
  s = nlohmann::json::parse(std::ifstream(test::source_dir() / "config" / "demo.json"));
  s["spindle"] = {{"profile", "ramp"},
                  {"actual_rpm", 20000.0},
                  {"ramp_end_rpm", 30000.0},
                  {"ramp_start_s", 0.0},
                  {"ramp_end_s", 0.2}};
  write_file(dir / "ramp.json", s.dump());
  const auto ramp =
      test::run_command(test::millwatch_cli() + " simulate " + (dir / "ramp.json").string() +
                        " --duration 0.2 -o " + (dir / "ramp_cut.csv").string() + " 2>&1");
  EXPECT_NE(ramp.output.find("= 0.200 s, 83 revolutions\n"), std::string::npos) << ramp.output;
}

// [002]'s copper preset at 96,000 rpm (tooth-passing 3,200 Hz): the default 3.3 kHz low-pass
// would pass its first harmonic alone. Its recording replays as it is, the cut-off that suits it
// said, and the speed measured against the simulator's truth.
TEST(SimulateCommand, AHighSpeedPresetReplaysWithTheCutoffItNeeds) {
  const fs::path dir = test::fresh_temp_dir();
  const std::string preset =
      (test::source_dir() / "config" / "presets" / "copper_li2007.json").string();
  const std::string csv = (dir / "cu.csv").string();
  const auto sim = test::run_command(test::millwatch_cli() + " simulate " + preset +
                                     " --duration 0.1 -o " + csv + " 2>&1");
  ASSERT_EQ(sim.exit_code, 0) << sim.output;
  EXPECT_EQ(sim.output.find("replay will refuse"), std::string::npos) << sim.output;
  const std::string summary_path = (dir / "s.json").string();
  const auto replay = test::run_command(test::millwatch_cli() + " replay " + csv +
                                        " --no-identify --summary " + summary_path + " 2>&1");
  ASSERT_EQ(replay.exit_code, 0) << replay.output;
  EXPECT_NE(replay.output.find("filter.cutoff_hz not given: the default 3300 Hz would not pass "
                               "1.5 x the tooth-passing frequency (3200 Hz"),
            std::string::npos)
      << replay.output;
  const auto summary = nlohmann::json::parse(std::ifstream(summary_path));
  EXPECT_EQ(summary["filter_cutoff_hz"], 12800.0);
  EXPECT_NEAR(summary["spindle_rpm"].get<double>(), 96000.0, 96.0) << summary.dump();
  // ~160 turns in 0.1 s; the lock takes the first 0.03 s.
  EXPECT_GT(summary["revolutions_measured"].get<int>(), 100) << summary.dump();
}

TEST(SimulateCommand, UnwritableOutputFailsCleanly) {
  const auto r = test::run_command(test::millwatch_cli() + " simulate " +
                                   (test::source_dir() / "config" / "demo.json").string() +
                                   " --duration 0.01 -o /nonexistent/dir/cut.csv");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("/nonexistent/dir/cut.csv"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace millwatch
