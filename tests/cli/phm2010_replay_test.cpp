// The monitor on real dynamometer recordings: three 0.1 s windows of the PHM 2010 data
// challenge's cutter c1 (3-flute ball-nose end mill, ~10,400 rpm, 50 kHz) at cuts 1, 158 and
// 315, replayed with the shipped config/phm2010_c1.json. The truth here is what is known of the
// set-up (three equally spaced flutes, the nominal speed) and the measured flank wear.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "tests/support/run_command.hpp"
#include "tests/support/test_paths.hpp"

namespace millwatch {
namespace {

namespace fs = std::filesystem;

fs::path data_dir() {
  return test::shared_dir() / "data" / "phm2010";
}

nlohmann::json replay_window(const std::string& cut, const fs::path& dir) {
  const fs::path summary = dir / ("cut" + cut + ".json");
  const auto r =
      test::run_command(test::millwatch_cli() + " replay " +
                        (data_dir() / ("c1_cut" + cut + "_window.csv")).string() + " --config " +
                        (test::source_dir() / "config" / "phm2010_c1.json").string() +
                        " --summary " + summary.string() + " >/dev/null");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return fs::exists(summary) ? nlohmann::json::parse(std::ifstream(summary)) : nlohmann::json();
}

/// Mean flank wear of the three flutes after `cut`, from c1_wear.csv.
double mean_wear_um(int cut) {
  std::ifstream in(data_dir() / "c1_wear.csv");
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::stringstream s(line);
    std::string field;
    std::getline(s, field, ',');
    if (std::stoi(field) != cut) {
      continue;
    }
    double sum = 0.0;
    for (int f = 0; f < 3; ++f) {
      std::getline(s, field, ',');
      sum += std::stod(field);
    }
    return sum / 3.0;
  }
  return std::nan("");
}

double mean_of(const nlohmann::json& a) {
  double sum = 0.0;
  for (const auto& v : a) {
    sum += v.get<double>();
  }
  return sum / static_cast<double>(a.size());
}

TEST(Phm2010Replay, TracksSpeedToothPeriodsAndForceGrowthWithWear) {
  if (!fs::exists(data_dir() / "c1_cut158_window.csv")) {
    GTEST_SKIP() << "real recordings not found at " << data_dir();
  }
  const fs::path dir = test::fresh_temp_dir();
  const nlohmann::json fresh = replay_window("001", dir);
  const nlohmann::json mid = replay_window("158", dir);
  const nlohmann::json worn = replay_window("315", dir);
  ASSERT_FALSE(mid.is_null());
  ASSERT_FALSE(worn.is_null());

  for (const nlohmann::json* s : {&fresh, &mid, &worn}) {
    EXPECT_EQ((*s)["samples"], 5000);
    EXPECT_EQ((*s)["dropped_samples"], 0);
  }
  // Cut 1 is light and barely periodic (its spindle harmonics stand 6–12 dB above the noise):
  // no speed is stated, and the summary says why (issue 6 §4; before, it "locked" at three
  // different speeds and reported 10,259 rpm as fact).
  EXPECT_TRUE(fresh["spindle_rpm"].is_null()) << fresh["spindle_rpm"];
  EXPECT_EQ(fresh["revolutions"], 0);
  bool said_why = false;
  for (const auto& w : fresh["warnings"]) {
    // ... with the threshold it stands for (spindle.min_snr_db, 12 dB by default).
    said_why = said_why ||
               (w["kind"] == "no steady tooth-passing signal" &&
                w["detail"].get<std::string>().find("min_snr_db (12 dB)") != std::string::npos);
  }
  EXPECT_TRUE(said_why) << fresh["warnings"];

  for (const nlohmann::json* s : {&mid, &worn}) {
    const double rpm = (*s)["spindle_rpm"].get<double>();
    EXPECT_NEAR(rpm, 10400.0, 0.02 * 10400.0);
    // 17 revolutions in 0.1 s: at least 15 measured with the shipped configuration (issue 6 §2).
    EXPECT_GE((*s)["revolutions"].get<int>(), 15);
    EXPECT_LE((*s)["revolutions"].get<int>(), 17);
    // Three flutes evenly spaced: three tooth periods that add up to a revolution, α near 120°.
    const auto& periods = (*s)["tooth_period_s"];
    ASSERT_EQ(periods.size(), 3u);
    const double revolution_s = 60.0 / rpm;
    EXPECT_NEAR(3.0 * mean_of(periods), revolution_s, 0.005 * revolution_s);
    for (const auto& p : periods) {
      EXPECT_NEAR(p.get<double>(), revolution_s / 3.0, 0.03 * revolution_s / 3.0);
    }
    EXPECT_NEAR((*s)["alpha_deg"]["mean"].get<double>(), 120.0, 3.0);
  }
  // The two steady windows see the same spindle.
  EXPECT_NEAR(mid["spindle_rpm"].get<double>(), worn["spindle_rpm"].get<double>(), 0.002 * 10400.0);

  // Flank wear grows from cut 158 to 315; so do the cutting forces (rubbing on the wear land),
  // flute by flute and more than in proportion.
  const double wear_ratio = mean_wear_um(315) / mean_wear_um(158);
  EXPECT_GT(wear_ratio, 1.2);
  const double force_ratio =
      mean_of(worn["peak_force_N"]["resultant"]) / mean_of(mid["peak_force_N"]["resultant"]);
  EXPECT_GT(force_ratio, wear_ratio);
  for (std::size_t f = 0; f < 3; ++f) {
    EXPECT_GT(worn["peak_force_N"]["resultant"][f].get<double>(),
              2.0 * mid["peak_force_N"]["resultant"][f].get<double>());
  }
}

// The lockstep model on these cuts (a_e 0.125 mm of a 6 mm tool: each flute cuts 17° of its
// 120°, the model's force is zero over the rest) with the runout switched off: three equal
// flutes, equally spaced, so its α is the pitch and its ΔFy nothing — whatever the measured
// revolutions (whose valleys are not quiet) make of them. Its valleys had been fitted on the
// flat stretch's edge or the filter's ringing: 119.25° on cut 158.
TEST(Phm2010Replay, TheModelsAlphaWithoutRunoutIsThePitch) {
  if (!fs::exists(data_dir() / "c1_cut158_window.csv")) {
    GTEST_SKIP() << "real recordings not found at " << data_dir();
  }
  const fs::path dir = test::fresh_temp_dir();
  nlohmann::json config =
      nlohmann::json::parse(std::ifstream(test::source_dir() / "config" / "phm2010_c1.json"));
  config["model"]["effects"]["runout"]["enabled"] = false;
  std::ofstream(dir / "no_runout.json") << config.dump();
  for (const std::string cut : {"158", "315"}) {
    SCOPED_TRACE("cut " + cut);
    const fs::path summary = dir / ("cut" + cut + ".json");
    const auto r =
        test::run_command(test::millwatch_cli() + " replay " +
                          (data_dir() / ("c1_cut" + cut + "_window.csv")).string() + " --config " +
                          (dir / "no_runout.json").string() + " --no-identify --summary " +
                          summary.string() + " >/dev/null");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const auto s = nlohmann::json::parse(std::ifstream(summary));
    EXPECT_NEAR(s["model"]["alpha_deg"].get<double>(), 120.0, 0.05) << s["model"];
    EXPECT_NEAR(s["model"]["delta_fy_N"].get<double>(), 0.0, 0.02) << s["model"];
    // The measured α stays what the revolutions say (the model's events do not move them).
    EXPECT_NEAR(s["alpha_deg"]["mean"].get<double>(), 120.0, 3.0);
  }
}

// 20 ms cut out of cut 315's 0.1 s (a gap the tracker bridges, the last value held over it):
// the tracker windows over the gap hear no cutting, and the next cutting window overlaps the
// last one counted. The turns heard while cutting stay within what the record's span holds
// (10,424 rpm: 17.4 in 0.1 s); counting that window whole had stated ~21, and a "revolutions
// missed" warning on them.
TEST(Phm2010Replay, TurnsHeardAcrossAGapStayWithinTheRecordsSpan) {
  if (!fs::exists(data_dir() / "c1_cut315_window.csv")) {
    GTEST_SKIP() << "real recordings not found at " << data_dir();
  }
  const fs::path dir = test::fresh_temp_dir();
  {
    std::ifstream in(data_dir() / "c1_cut315_window.csv");
    std::ofstream out(dir / "gap.csv");
    std::string line;
    for (int n = 0; std::getline(in, line); ++n) {  // line 0: the header
      if (n <= 2000 || n > 3000) {
        out << line << '\n';
      }
    }
  }
  const fs::path summary = dir / "gap.json";
  const auto r = test::run_command(test::millwatch_cli() + " replay " + (dir / "gap.csv").string() +
                                   " --config " +
                                   (test::source_dir() / "config" / "phm2010_c1.json").string() +
                                   " --no-identify --summary " + summary.string() + " >/dev/null");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto s = nlohmann::json::parse(std::ifstream(summary));
  const double rpm = s["spindle_rpm"].get<double>();
  const double span = 0.1 * rpm / 60.0;
  EXPECT_LE(s["revolutions_cutting"].get<double>(), span + 0.5) << s["revolutions_cutting"];
  // At least the turns in the 0.08 s of samples that came.
  EXPECT_GE(s["revolutions_cutting"].get<double>(), 0.08 * rpm / 60.0 - 0.5);
}

}  // namespace
}  // namespace millwatch
