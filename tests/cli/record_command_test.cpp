// End-to-end tests of `millwatch record` as a user runs it: a cut published by `millwatch
// publish` over udpm:// (in a private network namespace) recorded and replayed to the summary of
// the cut's own file; an existing log kept unless --force; a bad expression named.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/support/private_network.hpp"
#include "tests/support/run_command.hpp"
#include "tests/support/test_paths.hpp"

namespace millwatch {
namespace {

namespace fs = std::filesystem;

nlohmann::json replay_json(const fs::path& input, const std::string& options = "") {
  // A subshell so that run_command's own 2>&1 does not bring the log into the JSON.
  std::string command = test::millwatch_cli();
  command += " replay " + input.string() + " --no-identify --json " + options;
  const auto r = test::run_command("(" + command + " 2>/dev/null)");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return r.exit_code == 0 ? nlohmann::json::parse(r.output) : nlohmann::json();
}

TEST(RecordCommand, RecordsAPublishedCutThatReplaysAsTheCutsFile) {
  if (std::string why; !test::private_network_works(why)) {
    GTEST_SKIP() << "no private network namespace here (unshare -n): " << why;
  }
  const fs::path dir = test::fresh_temp_dir();
  const std::string cli = test::millwatch_cli();
  std::ofstream(dir / "scenario.json")
      << R"({"recording": {"sample_rate_hz": 50000, "duration_s": 0.5, "seed": 3},
             "noise": {"enabled": true}})";
  const auto sim = test::run_command(cli + " simulate " + (dir / "scenario.json").string() +
                                     " -o " + (dir / "cut.csv").string() + " 2>&1");
  ASSERT_EQ(sim.exit_code, 0) << sim.output;
  // The recorder runs until SIGINT; the publisher starts once it says it is recording. The
  // session is a script file so that no shell between here and it expands its variables.
  const std::string url = "'udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304'";
  std::ofstream(dir / "session.sh")
      << "set -e\ncd " << dir.string() << "\n"
      << test::kPrivateNetworkSetUp << "\n"
      << cli << " record cut.lcmlog --url " << url
      << " --channels MILLWATCH_FORCE_RAW >record.out 2>&1 &\nrec=$!\n"
      << "for i in $(seq 100); do grep -q recording record.out && break; sleep 0.1; done\n"
      << cli << " publish cut.csv --url " << url << " --speed 4 --block 500\n"
      << "sleep 0.5\nkill -INT $rec\nwait $rec\n";
  const auto r =
      test::run_command("timeout -k 5 60 unshare -n sh " + (dir / "session.sh").string() + " 2>&1");
  std::string said;
  std::getline(std::ifstream(dir / "record.out"), said, '\0');
  ASSERT_EQ(r.exit_code, 0) << r.output << said;
  EXPECT_NE(said.find("50 events"), std::string::npos) << said;  // 25,000 samples in 500s
  EXPECT_NE(said.find("MILLWATCH_FORCE_RAW: 50"), std::string::npos) << said;

  const nlohmann::json from_log =
      replay_json(dir / "cut.lcmlog", "--sidecar " + (dir / "cut.json").string());
  const nlohmann::json from_csv = replay_json(dir / "cut.csv");
  ASSERT_FALSE(from_log.is_null());
  EXPECT_EQ(from_log["samples"], 25000) << from_log.dump(1).substr(0, 2000);
  EXPECT_EQ(from_log["samples"], from_csv["samples"]);
  EXPECT_GE(from_csv["revolutions"].get<int>(), 200);  // 208 turns at 25,000 rpm in 0.5 s
  EXPECT_EQ(from_log["revolutions"], from_csv["revolutions"]);
  EXPECT_EQ(from_log["alpha_deg"], from_csv["alpha_deg"]);
}

// publish sends any recording replay reads, described the same way: a real PHM 2010 window
// with its configuration (no sidecar), as an LCM log that replays to the CSV's own summary. It
// had taken a millwatch CSV with a sidecar only (and any other file for a scenario); a file it
// cannot read or that holds no sample is an error that names it.
TEST(RecordCommand, PublishSendsARealRecordingDescribedAsForReplay) {
  const fs::path data = test::shared_dir() / "data" / "phm2010";
  if (!fs::exists(data / "c1_cut158_window.csv")) {
    GTEST_SKIP() << "real recordings not found at " << data;
  }
  const fs::path dir = test::fresh_temp_dir();
  const std::string cli = test::millwatch_cli();
  const std::string config = (test::source_dir() / "config" / "phm2010_c1.json").string();
  const fs::path csv = data / "c1_cut158_window.csv";
  const auto published = test::run_command(
      cli + " publish " + csv.string() + " --config " + config + " --url 'file://" +
      (dir / "cut.lcmlog").string() + "?mode=w' --speed 0 2>&1");
  ASSERT_EQ(published.exit_code, 0) << published.output;
  EXPECT_NE(published.output.find("published 5 blocks, 5000 samples"), std::string::npos)
      << published.output;
  const nlohmann::json from_log = replay_json(dir / "cut.lcmlog", "--config " + config);
  const nlohmann::json from_csv = replay_json(csv, "--config " + config);
  ASSERT_FALSE(from_log.is_null());
  EXPECT_EQ(from_log["samples"], 5000);
  EXPECT_EQ(from_log["revolutions"], from_csv["revolutions"]);
  EXPECT_EQ(from_log["alpha_deg"], from_csv["alpha_deg"]);
  EXPECT_EQ(from_log["spindle_rpm"], from_csv["spindle_rpm"]);

  const auto no_sidecar =
      test::run_command(cli + " publish " + csv.string() + " --url memq:// --speed 0 2>&1");
  EXPECT_EQ(no_sidecar.exit_code, 2);
  EXPECT_NE(no_sidecar.output.find("c1_cut158_window.json: sidecar not found (describe the cut "
                                   "with --sidecar or --config)"),
            std::string::npos)
      << no_sidecar.output;
  // A scenario (any case of .json) takes no description of a recording; a recording no
  // --duration.
  fs::copy_file(test::source_dir() / "config" / "demo.json", dir / "SCENARIO.JSON");
  const auto upper = test::run_command(cli + " publish " + (dir / "SCENARIO.JSON").string() +
                                       " --duration 0.01 --url memq:// --speed 0 2>&1");
  EXPECT_EQ(upper.exit_code, 0) << upper.output;
  const auto described = test::run_command(cli + " publish " + (dir / "SCENARIO.JSON").string() +
                                           " --config " + config + " --url memq:// 2>&1");
  EXPECT_EQ(described.exit_code, 2);
  EXPECT_NE(described.output.find("a scenario describes its cut itself: --sidecar, --config and "
                                  "--columns are for a recording"),
            std::string::npos)
      << described.output;
  const auto shortened = test::run_command(cli + " publish " + csv.string() + " --config " +
                                           config + " --duration 0.01 --url memq:// 2>&1");
  EXPECT_EQ(shortened.exit_code, 2);
  EXPECT_NE(shortened.output.find("--duration is for a scenario"), std::string::npos)
      << shortened.output;
  std::ofstream(dir / "header.csv") << "t_s,fx_N,fy_N,fz_N\n";
  const auto empty = test::run_command(cli + " publish " + (dir / "header.csv").string() +
                                       " --config " + config + " --url memq:// --speed 0 2>&1");
  EXPECT_EQ(empty.exit_code, 2);
  EXPECT_NE(empty.output.find("header.csv: no samples to publish: no rows after its header"),
            std::string::npos)
      << empty.output;
  // Bad rows are named and counted, as the replay does (publish had named the first twenty and
  // never said how many it left out).
  std::ofstream(dir / "bad_rows.csv") << "t_s,fx_N,fy_N,fz_N\n0,1,2,3\n0.00002,1,x,3\n"
                                         "0.00004,1,2,3\n0.00006,1,2\n0.00008,1,2,3\n";
  const auto bad = test::run_command(cli + " publish " + (dir / "bad_rows.csv").string() +
                                     " --config " + config + " --url memq:// --speed 0 2>&1");
  EXPECT_EQ(bad.exit_code, 0) << bad.output;
  EXPECT_NE(bad.output.find("bad_rows.csv:3: "), std::string::npos) << bad.output;
  EXPECT_NE(bad.output.find("bad_rows.csv:5: "), std::string::npos) << bad.output;
  EXPECT_NE(bad.output.find("bad_rows.csv: 2 bad lines skipped"), std::string::npos) << bad.output;
  EXPECT_NE(bad.output.find("3 samples on"), std::string::npos) << bad.output;
}

// Recording from a log (file://…?speed=0: a log's channels filtered into a new one) ends at the
// log's end with the counts; it had ended "LCM: cannot receive (lcm_handle failed)", exit 2,
// without them, the log it wrote being complete.
TEST(RecordCommand, RecordingFromALogEndsAtItsEnd) {
  const fs::path dir = test::fresh_temp_dir();
  const std::string cli = test::millwatch_cli();
  const std::string demo = (test::source_dir() / "config" / "demo.json").string();
  const auto published =
      test::run_command(cli + " publish " + demo + " --duration 0.05 --speed 0 --url 'file://" +
                        (dir / "source.lcmlog").string() + "?mode=w' 2>&1");
  ASSERT_EQ(published.exit_code, 0) << published.output;
  const auto r =
      test::run_command("timeout 30 " + cli + " record " + (dir / "copy.lcmlog").string() +
                        " --url 'file://" + (dir / "source.lcmlog").string() + "?speed=0' 2>&1");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("read to its end"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("MILLWATCH_FORCE_RAW: 17"), std::string::npos) << r.output;
  EXPECT_EQ(fs::file_size(dir / "copy.lcmlog"), fs::file_size(dir / "source.lcmlog"));
}

TEST(RecordCommand, KeepsAnExistingLogUnlessForced) {
  const fs::path dir = test::fresh_temp_dir();
  const fs::path log = dir / "kept.lcmlog";
  std::ofstream(log) << "an earlier recording";
  const std::string cli = test::millwatch_cli();
  const auto refused =
      test::run_command(cli + " record " + log.string() + " --url memq:// --duration 0.1 2>&1");
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  EXPECT_NE(refused.output.find(log.string() + " exists"), std::string::npos) << refused.output;
  std::string kept;
  std::getline(std::ifstream(log), kept);
  EXPECT_EQ(kept, "an earlier recording");

  const auto forced = test::run_command(cli + " record " + log.string() +
                                        " --url memq:// --duration 0.1 --force 2>&1");
  EXPECT_EQ(forced.exit_code, 0) << forced.output;
  EXPECT_NE(forced.output.find("0 events"), std::string::npos) << forced.output;
  EXPECT_NE(forced.output.find("nothing recorded"), std::string::npos) << forced.output;
  EXPECT_EQ(fs::file_size(log), 0u);
}

TEST(RecordCommand, ABadChannelExpressionIsNamed) {
  const fs::path log = test::fresh_temp_dir() / "x.lcmlog";
  const auto r = test::run_command(test::millwatch_cli() + " record " + log.string() +
                                   " --url memq:// --channels 'RAW[' 2>&1");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("bad channel regular expression 'RAW['"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace millwatch
