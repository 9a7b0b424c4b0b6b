// millwatchd as it runs beside the machine: multi-process LCM sessions inside a private network
// namespace (tests/daemon/lcm_session.sh: lcm-logger, lcm-logplayer, `millwatch publish`), the
// signals (SIGTERM, SIGHUP), garbage on the raw channel, bad configurations, a missing DAQ.
// Sessions that need `unshare -n` are skipped, saying why, where it is not permitted.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/sim/cut_simulator.hpp"
#include "millwatch/pipeline_status_t.hpp"
#include "millwatch/spindle_state_t.hpp"
#include "millwatch/tooth_periods_t.hpp"
#include "msgs/lcm_convert.hpp"
#include "tests/support/run_command.hpp"
#include "tests/support/test_paths.hpp"

namespace millwatch {
namespace {

namespace fs = std::filesystem;

const std::string kDaemon = MILLWATCH_DAEMON;

std::string read_text(const fs::path& p) {
  std::stringstream s;
  s << std::ifstream(p).rdbuf();
  return s.str();
}

nlohmann::json read_json(const fs::path& p) {
  return fs::exists(p) ? nlohmann::json::parse(std::ifstream(p)) : nlohmann::json();
}

/// Whether this machine lets us make a private network namespace with a multicast route.
bool namespaces_work(std::string& why) {
  const auto r = test::run_command(
      "unshare -n sh -c 'ip link set lo up && ip route add 239.0.0.0/8 dev lo' 2>&1");
  why = r.output;
  return r.exit_code == 0;
}

/// Runs one lcm_session.sh mode in a private network namespace (bounded to 90 s).
test::CommandResult session(const std::string& mode, const fs::path& dir) {
  const fs::path script = test::source_dir() / "tests" / "daemon" / "lcm_session.sh";
  return test::run_command("MILLWATCH_CLI=" + test::millwatch_cli() +
                           " MILLWATCH_DAEMON=" + kDaemon + " timeout 90 unshare -n " +
                           script.string() + " " + mode + " " + dir.string());
}

/// A 1 s cut at 50 kHz as a CSV + sidecar, and the daemon configuration monitoring it.
void prepare_cut(const fs::path& dir) {
  const nlohmann::json scenario = {
      {"recording", {{"sample_rate_hz", 50000.0}, {"duration_s", 1.0}, {"seed", 5}}},
      {"spindle", {{"actual_rpm", 25252.0}}},
      {"noise", {{"enabled", true}}}};
  std::ofstream(dir / "scenario.json") << scenario.dump();
  const auto r =
      test::run_command(test::millwatch_cli() + " simulate " + (dir / "scenario.json").string() +
                        " -o " + (dir / "cut.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json config = {{"monitor", {{"sample_rate_hz", 50000.0}}},
                                 {"source", {{"kind", "lcm"}}},
                                 {"status_period_s", 0.2}};
  std::ofstream(dir / "monitor.json") << config.dump(2);
}

/// Channel → events of an LCM log.
std::map<std::string, std::vector<std::vector<std::uint8_t>>> read_log(const fs::path& path) {
  std::map<std::string, std::vector<std::vector<std::uint8_t>>> out;
  lcm::LogFile log(path.string(), "r");
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    const auto* data = static_cast<const std::uint8_t*>(e->data);
    out[e->channel].emplace_back(data, data + e->datalen);
  }
  return out;
}

template <class Message>
std::vector<Message> decode_all(const std::vector<std::vector<std::uint8_t>>& events) {
  std::vector<Message> out;
  for (const auto& e : events) {
    Message m;
    if (m.decode(e.data(), 0, static_cast<int>(e.size())) == static_cast<int>(e.size())) {
      out.push_back(m);
    }
  }
  return out;
}

class MillwatchdSession : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    if (!namespaces_work(why)) {
      GTEST_SKIP() << "no private network namespace here (unshare -n): " << why;
    }
    dir_ = test::fresh_temp_dir();
    prepare_cut(dir_);
  }
  fs::path dir_;
};

// Issue 3 §3 and §5: lcm-logger records a live run's raw samples and the daemon's outputs; the
// recorded outputs decode; replaying the recorded raw channel gives the live run's results.
TEST_F(MillwatchdSession, LiveRunIsRecordedDecodedAndReplayedToTheSameResults) {
  const auto r = session("live", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.output << read_text(dir_ / "daemon.log");
  EXPECT_NE(r.output.find("daemon exit 0"), std::string::npos) << r.output;
  const nlohmann::json live = read_json(dir_ / "daemon.json");
  ASSERT_FALSE(live.is_null()) << read_text(dir_ / "daemon.log");
  EXPECT_EQ(live["samples"], 50000);
  EXPECT_EQ(live["dropped_samples"], 0);
  EXPECT_NEAR(live["spindle_rpm"].get<double>(), 25252.0, 0.0005 * 25252.0);
  const int revolutions = live["revolutions"].get<int>();
  EXPECT_GT(revolutions, 250);

  const auto log = read_log(dir_ / "live.lcmlog");
  ASSERT_EQ(log.count("MILLWATCH_FORCE_RAW"), 1u);
  EXPECT_EQ(log.at("MILLWATCH_FORCE_RAW").size(), 50u);  // 1000-sample blocks
  const auto periods = decode_all<tooth_periods_t>(log.at("MILLWATCH_TOOTH_PERIODS"));
  ASSERT_GE(periods.size(), static_cast<std::size_t>(0.95 * revolutions));
  for (std::size_t i = 1; i < periods.size(); ++i) {
    EXPECT_GT(periods[i].revolution, periods[i - 1].revolution);
    EXPECT_GT(periods[i].utime, periods[i - 1].utime);
  }
  EXPECT_EQ(periods.back().num_flutes, 2);
  EXPECT_NEAR(periods.back().alpha_mean_deg, live["alpha_deg"]["mean"].get<double>(), 0.5);
  double period_sum_s = 0.0;
  for (const auto& p : periods) {
    period_sum_s += p.period_s;
  }
  EXPECT_NEAR(period_sum_s / static_cast<double>(periods.size()), 60.0 / 25252.0, 1e-6);
  const auto spindle = decode_all<spindle_state_t>(log.at("MILLWATCH_SPINDLE"));
  ASSERT_FALSE(spindle.empty());
  EXPECT_NEAR(spindle.back().spindle_rpm_measured, 25252.0, 0.0005 * 25252.0);
  EXPECT_EQ(spindle.back().spindle_rpm_commanded, 25000.0);
  const auto status = decode_all<pipeline_status_t>(log.at("MILLWATCH_STATUS"));
  ASSERT_FALSE(status.empty());
  EXPECT_EQ(status.back().samples_in, 50000);  // the final status, published on SIGTERM
  EXPECT_EQ(status.back().samples_dropped, 0);

  // Offline, the recorded raw channel through the same configuration: the same results.
  const auto replay =
      test::run_command(test::millwatch_cli() + " replay " + (dir_ / "live.lcmlog").string() +
                        " --config " + (dir_ / "monitor.json").string() + " --summary " +
                        (dir_ / "replay.json").string() + " >/dev/null");
  ASSERT_EQ(replay.exit_code, 0) << replay.output;
  const nlohmann::json offline = read_json(dir_ / "replay.json");
  EXPECT_EQ(offline["samples"], live["samples"]);
  EXPECT_EQ(offline["revolutions"], live["revolutions"]);
  EXPECT_DOUBLE_EQ(offline["spindle_rpm"].get<double>(), live["spindle_rpm"].get<double>());
  EXPECT_DOUBLE_EQ(offline["alpha_deg"]["mean"].get<double>(),
                   live["alpha_deg"]["mean"].get<double>());
  EXPECT_DOUBLE_EQ(offline["delta_fy_N"].get<double>(), live["delta_fy_N"].get<double>());
  for (const char* axis : {"fx", "fy", "fz"}) {
    EXPECT_DOUBLE_EQ(offline["residual_rms_N"][axis].get<double>(),
                     live["residual_rms_N"][axis].get<double>());
  }

  // lcm-logplayer feeds the recorded raw log into a fresh daemon: the same results again.
  const auto played = session("logplayer", dir_);
  ASSERT_EQ(played.exit_code, 0) << played.output << read_text(dir_ / "played.log");
  const nlohmann::json again = read_json(dir_ / "played.json");
  EXPECT_EQ(again["samples"], 50000);
  EXPECT_EQ(again["revolutions"], live["revolutions"]);
  EXPECT_DOUBLE_EQ(again["alpha_deg"]["mean"].get<double>(),
                   live["alpha_deg"]["mean"].get<double>());
}

/// Writes events of `fx` blocks [from, to) of the cut (1000 samples each) into an LCM log.
void write_raw_log(const fs::path& path, const sim::Scenario& s, int from, int to) {
  sim::CutSimulator sim(s);
  lcm::LogFile log(path.string(), "w");
  std::vector<double> t(1000), fx(1000), fy(1000), fz(1000);
  for (int seq = 0; seq < to; ++seq) {
    const std::size_t n = sim.next_block(t, fx, fy, fz);
    if (seq < from || n == 0) {
      continue;
    }
    const force_block_t m = messaging::to_message({std::llround(t[0] * 1e6),
                                                   seq,
                                                   s.sample_rate_hz,
                                                   {fx.data(), n},
                                                   {fy.data(), n},
                                                   {fz.data(), n}});
    std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
    m.encode(buf.data(), 0, static_cast<int>(buf.size()));
    lcm::LogEvent e{seq, m.utime, "MILLWATCH_FORCE_RAW", static_cast<std::int32_t>(buf.size()),
                    buf.data()};
    log.writeEvent(&e);
  }
}

// Issue 3 §4 and §6: SIGHUP reloads without losing samples; a bad file on reload is reported
// by field and the running configuration kept; garbage on the raw channel is counted and
// survived; SIGTERM stops with the final summary.
TEST_F(MillwatchdSession, ReloadsKeepsRunningOnBadConfigAndCountsGarbage) {
  sim::Scenario s;
  s.sample_rate_hz = 50000.0;
  s.duration_s = 1.0;
  s.spindle.actual_rpm = 25252.0;
  write_raw_log(dir_ / "part1.lcmlog", s, 0, 25);
  write_raw_log(dir_ / "part2.lcmlog", s, 25, 50);
  {
    lcm::LogFile garbage((dir_ / "garbage.lcmlog").string(), "w");
    std::mt19937 rng(3);
    for (int i = 0; i < 5; ++i) {
      std::vector<std::uint8_t> bytes(100 + 50 * i);
      for (auto& b : bytes) {
        b = static_cast<std::uint8_t>(rng());
      }
      lcm::LogEvent e{i, 500000 + i, "MILLWATCH_FORCE_RAW", static_cast<std::int32_t>(bytes.size()),
                      bytes.data()};
      garbage.writeEvent(&e);
    }
  }
  nlohmann::json good = nlohmann::json::parse(std::ifstream(dir_ / "monitor.json"));
  std::ofstream(dir_ / "good.json") << good.dump();
  good["status_period_s"] = 0.5;
  nlohmann::json bad = good;
  bad["monitor"]["model"]["tool"]["flutes"] = "two";
  std::ofstream(dir_ / "good.json") << good.dump();
  std::ofstream(dir_ / "bad.json") << bad.dump();

  const auto r = session("reload", dir_);
  const std::string log = read_text(dir_ / "reload.log");
  ASSERT_EQ(r.exit_code, 0) << r.output << log;
  EXPECT_NE(r.output.find("daemon exit 0"), std::string::npos) << r.output;
  EXPECT_NE(log.find("configuration reloaded"), std::string::npos) << log;
  EXPECT_NE(log.find("monitor.model.tool.flutes"), std::string::npos) << log;
  EXPECT_NE(log.find("keeping the running configuration"), std::string::npos) << log;
  const nlohmann::json summary = read_json(dir_ / "reload.json");
  ASSERT_FALSE(summary.is_null()) << log;
  EXPECT_EQ(summary["samples"], 50000);  // every sample, across the reloads
  EXPECT_EQ(summary["counters"]["blocks_rejected"], 5) << summary.dump(2);  // the garbage
  EXPECT_GT(summary["revolutions"].get<int>(), 100);  // it kept measuring after all that
}

// Issue 3 §4: SIGTERM and SIGINT stop cleanly with a final summary (in-process LCM: no traffic).
TEST(Millwatchd, StopsCleanlyOnSigtermAndSigintWithAFinalSummary) {
  const fs::path dir = test::fresh_temp_dir();
  std::ofstream(dir / "d.json") << nlohmann::json{
      {"monitor",
       {{"sample_rate_hz", 50000.0}}}}.dump();
  for (const char* sig : {"TERM", "INT"}) {
    const fs::path summary = dir / (std::string(sig) + ".json");
    const auto r =
        test::run_command("timeout 30 sh -c '" + kDaemon + " -c " + (dir / "d.json").string() +
                          " --lcm-url memq:// --summary " + summary.string() +
                          " & pid=$!; sleep 0.5; kill -" + sig + " $pid; wait $pid; echo exit=$?'");
    EXPECT_NE(r.output.find("exit=0"), std::string::npos) << sig << ": " << r.output;
    EXPECT_NE(r.output.find("final summary"), std::string::npos) << r.output;
    const nlohmann::json j = read_json(summary);
    ASSERT_FALSE(j.is_null()) << r.output;
    EXPECT_EQ(j["samples"], 0);
    EXPECT_TRUE(j.contains("alerts"));
  }
}

// Issue 3 §6: a configuration with a mistyped, out-of-range, unknown or missing field is
// refused by --check (and at start) with the field named.
TEST(Millwatchd, CheckNamesTheBadFieldOfAConfiguration) {
  const fs::path dir = test::fresh_temp_dir();
  const fs::path shipped = test::source_dir() / "config" / "millwatchd.json";
  auto check = [&](const std::string& file) {
    return test::run_command(kDaemon + " --check -c " + file);
  };
  const auto ok = check(shipped.string());
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
  EXPECT_NE(ok.output.find("configuration is valid"), std::string::npos);

  const nlohmann::json base = nlohmann::json::parse(std::ifstream(shipped));
  struct Case {
    std::string name, pointer;
    nlohmann::json value;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {"type", "/monitor/model/tool/flutes", "two", "monitor.model.tool.flutes"},
      {"range", "/monitor/sample_rate_hz", -5.0, "monitor.sample_rate_hz: value -5"},
      {"unknown", "/monitor/filter/cutof_hz", 3300.0, "monitor.filter.cutof_hz: unknown key"},
      {"choice", "/source/kind", "serial", "source.kind"},
      {"url", "/lcm/url", 7, "lcm.url"},
  };
  for (const Case& c : cases) {
    nlohmann::json j = base;
    j[nlohmann::json::json_pointer(c.pointer)] = c.value;
    const fs::path file = dir / (c.name + ".json");
    std::ofstream(file) << j.dump();
    const auto r = check(file.string());
    EXPECT_NE(r.exit_code, 0) << c.name;
    EXPECT_NE(r.output.find(c.expected), std::string::npos) << c.name << ": " << r.output;
    EXPECT_NE(r.output.find(file.filename().string()), std::string::npos) << r.output;
  }
  // A Comedi source without its channel map: the missing field is named.
  nlohmann::json comedi = base;
  comedi["source"] = {{"kind", "comedi"}, {"device", "/dev/comedi9"}};
  std::ofstream(dir / "comedi.json") << comedi.dump();
  const auto r = check((dir / "comedi.json").string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("source.channels"), std::string::npos) << r.output;
  // Not JSON at all.
  std::ofstream(dir / "broken.json") << "{\"monitor\": ";
  const auto broken = check((dir / "broken.json").string());
  EXPECT_NE(broken.exit_code, 0);
  EXPECT_NE(broken.output.find("broken.json"), std::string::npos) << broken.output;
}

// Issue 3 §3(d): a DAQ that is not there is a clear error, not a crash.
TEST(Millwatchd, MissingComediDeviceIsAClearError) {
  const fs::path dir = test::fresh_temp_dir();
  nlohmann::json c =
      nlohmann::json::parse(std::ifstream(test::source_dir() / "config" / "millwatchd.json"));
  nlohmann::json channel = {{"daq_channel", 0}, {"range_N", 100.0}, {"full_scale_V", 10.0}};
  c["source"] = {
      {"kind", "comedi"}, {"device", "/dev/comedi9"}, {"channels", {channel, channel, channel}}};
  c["source"]["channels"][1]["daq_channel"] = 1;
  c["source"]["channels"][2]["daq_channel"] = 2;
  std::ofstream(dir / "daq.json") << c.dump();
  const auto r = test::run_command("timeout 30 " + kDaemon + " -c " + (dir / "daq.json").string() +
                                   " --lcm-url memq://");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(r.output.find("Segmentation"), std::string::npos);
  const bool named = r.output.find("/dev/comedi9") != std::string::npos;
  const bool not_built = r.output.find("Comedi") != std::string::npos;
  EXPECT_TRUE(named || not_built) << r.output;
}

}  // namespace
}  // namespace millwatch
