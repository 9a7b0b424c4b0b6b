// millwatchd as it runs beside the machine: multi-process LCM sessions inside a private network
// namespace (tests/daemon/lcm_session.sh: `millwatch record` — lcm-logger's log without its
// 30-message queue —, lcm-logplayer, `millwatch publish`) whose
// recordings are decoded here, the signals (SIGTERM, SIGINT, SIGHUP), garbage on the raw
// channel, bad configurations (in the file, or refused by the pipeline's stages), a missing DAQ,
// udpm:// without a multicast route. Single-process tests use memq://. Tests that need
// `unshare -n` are skipped, saying why, where it is not permitted.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "core/sim/scenario.hpp"
#include "millwatch/flute_peaks2_t.hpp"
#include "millwatch/model_residual_t.hpp"
#include "millwatch/pipeline_status5_t.hpp"
#include "millwatch/spindle_state2_t.hpp"
#include "millwatch/sync_average2_t.hpp"
#include "millwatch/tool_alert_t.hpp"
#include "millwatch/tooth_periods2_t.hpp"
#include "msgs/lcm_convert.hpp"
#include "tests/support/force_log.hpp"
#include "tests/support/private_network.hpp"
#include "tests/support/run_command.hpp"
#include "tests/support/test_paths.hpp"

namespace millwatch {
namespace {

namespace fs = std::filesystem;

const std::string kDaemon = MILLWATCH_DAEMON;

nlohmann::json read_json(const fs::path& p) {
  return fs::exists(p) ? nlohmann::json::parse(std::ifstream(p)) : nlohmann::json();
}

/// Runs one lcm_session.sh mode in a private network namespace (bounded to 90 s; the script
/// kills its own stragglers).
test::CommandResult session(const std::string& mode, const fs::path& dir) {
  const fs::path script = test::source_dir() / "tests" / "daemon" / "lcm_session.sh";
  return test::run_command("MILLWATCH_CLI=" + test::millwatch_cli() +
                           " MILLWATCH_DAEMON=" + kDaemon + " timeout -k 5 90 unshare -n " +
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
  // No CPU budget (identification.cpu_budget 1): the live worker fits every window it gets to,
  // so that the live run can agree with the replay exactly.
  const nlohmann::json config = {
      {"monitor", {{"sample_rate_hz", 50000.0}, {"identification", {{"cpu_budget", 1.0}}}}},
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

/// Every event of a channel, decoded; an event that does not decode exactly is a failure.
template <class Message>
std::vector<Message> decode_all(const std::vector<std::vector<std::uint8_t>>& events) {
  std::vector<Message> out;
  for (const auto& e : events) {
    Message m;
    if (m.decode(e.data(), 0, static_cast<int>(e.size())) == static_cast<int>(e.size())) {
      out.push_back(m);
    } else {
      ADD_FAILURE() << "an event of " << e.size() << " bytes does not decode as "
                    << Message::getTypeName();
    }
  }
  return out;
}

/// The events of `channel` in `log` (none if it is absent).
const std::vector<std::vector<std::uint8_t>>& events(
    const std::map<std::string, std::vector<std::vector<std::uint8_t>>>& log,
    const std::string& channel) {
  static const std::vector<std::vector<std::uint8_t>> kNone;
  const auto it = log.find(channel);
  return it == log.end() ? kNone : it->second;
}

class MillwatchdSession : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    if (!test::private_network_works(why)) {
      GTEST_SKIP() << "no private network namespace here (unshare -n): " << why;
    }
    dir_ = test::fresh_temp_dir();
    prepare_cut(dir_);
  }
  fs::path dir_;
};

// Issue 10: with lcm.output_url (here --lcm-output-url) the results go to their own URL and the
// input URL carries the raw blocks only — the daemon's LCM receive thread no longer reads back its
// own outputs; every sample is still monitored and every result arrives where it was sent.
TEST_F(MillwatchdSession, PublishesItsResultsOnTheOutputUrlOnly) {
  sim::Scenario s;
  s.sample_rate_hz = 50000.0;
  s.duration_s = 1.0;
  s.spindle.actual_rpm = 25252.0;
  test::write_force_log(dir_ / "cut.lcmlog", s, 250, 0, 200);
  const auto r = session("split", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.output << test::read_text(dir_ / "split.log");
  EXPECT_NE(r.output.find("daemon exit 0"), std::string::npos) << r.output;
  const nlohmann::json summary = read_json(dir_ / "split.json");
  ASSERT_FALSE(summary.is_null()) << test::read_text(dir_ / "split.log");
  EXPECT_EQ(summary["samples"], 50000);
  EXPECT_EQ(summary["dropped_samples"], 0);
  const int revolutions = summary["revolutions"].get<int>();
  EXPECT_GT(revolutions, 250);

  const auto in = read_log(dir_ / "in.lcmlog");
  EXPECT_EQ(events(in, "MILLWATCH_FORCE_RAW").size(), 200u);
  for (const auto& [channel, e] : in) {  // LCM's own LCM_SELF_TEST aside
    EXPECT_TRUE(channel == "MILLWATCH_FORCE_RAW" || channel == "LCM_SELF_TEST")
        << channel << " on the input URL";
  }
  const auto out = read_log(dir_ / "out.lcmlog");
  EXPECT_EQ(out.count("MILLWATCH_FORCE_RAW"), 0u);
  // Who lost what, if any is short: the daemon's log ends with the messages it published and
  // dropped, then the loggers' and the kernel's side.
  const std::string loggers = test::read_text(dir_ / "split.log") +
                              "\nthe recorders said: " + test::read_text(dir_ / "logger.out") +
                              "\nthe namespace's UDP counters:\n" +
                              test::read_text(dir_ / "udp_stats.txt");
  const auto periods = decode_all<tooth_periods2_t>(events(out, "MILLWATCH_TOOTH_PERIODS"));
  EXPECT_GE(periods.size(), static_cast<std::size_t>(0.95 * revolutions)) << loggers;
  EXPECT_GE(decode_all<flute_peaks2_t>(events(out, "MILLWATCH_FLUTE_PEAKS")).size(),
            static_cast<std::size_t>(0.95 * revolutions))
      << loggers;
  const auto status = decode_all<pipeline_status5_t>(events(out, "MILLWATCH_STATUS"));
  ASSERT_FALSE(status.empty());
  EXPECT_EQ(status.back().samples_in, 50000);  // the final status, published on SIGTERM
  EXPECT_EQ(status.back().revolutions, revolutions);
}

// Issue 3 §3 and §5: a live run's raw samples and the daemon's outputs are recorded in
// lcm-logger's format (two recorders, the raw channel on its own, as the README advises for
// lcm-logger); the recorded outputs decode; replaying the recorded raw channel (lcm-logplayer)
// gives the live run's results.
TEST_F(MillwatchdSession, LiveRunIsRecordedDecodedAndReplayedToTheSameResults) {
  const auto r = session("live", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.output << test::read_text(dir_ / "daemon.log");
  EXPECT_NE(r.output.find("daemon exit 0"), std::string::npos) << r.output;
  const nlohmann::json live = read_json(dir_ / "daemon.json");
  ASSERT_FALSE(live.is_null()) << test::read_text(dir_ / "daemon.log");
  EXPECT_EQ(live["samples"], 50000);
  EXPECT_EQ(live["dropped_samples"], 0);
  EXPECT_NEAR(live["spindle_rpm"].get<double>(), 25252.0, 0.0005 * 25252.0);
  const int revolutions = live["revolutions"].get<int>();
  EXPECT_GT(revolutions, 250);

  // The raw channel on a logger of its own (live.lcmlog), the results on another.
  const auto raw = read_log(dir_ / "live.lcmlog");
  const std::string loggers = "the recorders said: " + test::read_text(dir_ / "logger.out") +
                              "\nthe namespace's UDP counters:\n" +
                              test::read_text(dir_ / "udp_stats.txt");
  ASSERT_EQ(raw.size(), 1u) << loggers;                                   // the raw channel alone
  EXPECT_EQ(events(raw, "MILLWATCH_FORCE_RAW").size(), 200u) << loggers;  // 250-sample blocks
  const auto log = read_log(dir_ / "outputs.lcmlog");
  EXPECT_EQ(log.count("MILLWATCH_FORCE_RAW"), 0u);
  // Every channel the daemon publishes on was recorded, and every event decodes.
  for (const char* channel :
       {"MILLWATCH_SPINDLE", "MILLWATCH_TOOTH_PERIODS", "MILLWATCH_FLUTE_PEAKS",
        "MILLWATCH_RESIDUAL", "MILLWATCH_SYNC_AVERAGE", "MILLWATCH_ALERT", "MILLWATCH_STATUS"}) {
    EXPECT_FALSE(events(log, channel).empty()) << channel << " was not recorded";
  }
  const auto periods = decode_all<tooth_periods2_t>(events(log, "MILLWATCH_TOOTH_PERIODS"));
  ASSERT_GE(periods.size(), static_cast<std::size_t>(0.95 * revolutions));
  for (std::size_t i = 1; i < periods.size(); ++i) {
    EXPECT_GT(periods[i].revolution, periods[i - 1].revolution);
    EXPECT_GT(periods[i].utime, periods[i - 1].utime);
  }
  EXPECT_EQ(periods.back().num_flutes, 2);
  EXPECT_EQ(periods.back().flute_period_s.size(), 2u);
  EXPECT_NEAR(periods.back().alpha_mean_deg, live["alpha_deg"]["mean"].get<double>(), 0.5);
  double period_sum_s = 0.0;
  for (const auto& p : periods) {
    period_sum_s += p.period_s;
  }
  EXPECT_NEAR(period_sum_s / static_cast<double>(periods.size()), 60.0 / 25252.0, 1e-6);
  const auto spindle = decode_all<spindle_state2_t>(events(log, "MILLWATCH_SPINDLE"));
  ASSERT_FALSE(spindle.empty());
  EXPECT_TRUE(spindle.back().valid);
  EXPECT_TRUE(spindle.back().cutting);
  EXPECT_NEAR(spindle.back().spindle_rpm_measured, 25252.0, 0.001 * 25252.0);
  for (const auto& u : spindle) {  // no NaN: an absent speed is 0 with valid down
    EXPECT_TRUE(std::isfinite(u.spindle_rpm_measured));
    EXPECT_TRUE(u.valid || u.spindle_rpm_measured == 0.0);
  }
  EXPECT_EQ(spindle.back().spindle_rpm_commanded, 25000.0);
  for (std::size_t i = 1; i < spindle.size(); ++i) {
    EXPECT_GT(spindle[i].seq, spindle[i - 1].seq);
    EXPECT_GE(spindle[i].revolution, spindle[i - 1].revolution);
  }

  // Per revolution: peaks and residuals (the logger may miss a message on a busy machine).
  const auto peaks = decode_all<flute_peaks2_t>(events(log, "MILLWATCH_FLUTE_PEAKS"));
  ASSERT_GE(peaks.size(), static_cast<std::size_t>(0.95 * revolutions));
  std::array<double, 2> resultant_sum{};
  for (std::size_t i = 0; i < peaks.size(); ++i) {
    if (i > 0) {
      EXPECT_GT(peaks[i].revolution, peaks[i - 1].revolution);
    }
    ASSERT_EQ(peaks[i].num_flutes, 2);
    for (std::size_t j = 0; j < 2; ++j) {
      EXPECT_GT(peaks[i].peak_resultant_N[j], 0.0);
      resultant_sum[j] += peaks[i].peak_resultant_N[j];
    }
  }
  for (std::size_t j = 0; j < 2; ++j) {
    EXPECT_NEAR(resultant_sum[j] / static_cast<double>(peaks.size()),
                live["peak_force_N"]["resultant"][j].get<double>(),
                0.02 * live["peak_force_N"]["resultant"][j].get<double>())
        << "flute " << j;
  }
  const auto residuals = decode_all<model_residual_t>(events(log, "MILLWATCH_RESIDUAL"));
  ASSERT_GE(residuals.size(), static_cast<std::size_t>(0.9 * revolutions));
  double fx_sq = 0.0;
  double fx_sq_max = 0.0;
  for (std::size_t i = 0; i < residuals.size(); ++i) {
    if (i > 0) {
      EXPECT_GT(residuals[i].revolution, residuals[i - 1].revolution);
    }
    EXPECT_EQ(residuals[i].num_flutes, 2);
    EXPECT_EQ(residuals[i].num_sectors, 12);
    EXPECT_TRUE(std::isfinite(residuals[i].rms_fx_N));
    EXPECT_LT(residuals[i].rms_fx_N, residuals[i].measured_rms_N);  // the model explains the cut
    fx_sq += residuals[i].rms_fx_N * residuals[i].rms_fx_N;
    fx_sq_max = std::max(fx_sq_max, residuals[i].rms_fx_N * residuals[i].rms_fx_N);
  }
  // The summary's Fx residual is the RMS over every revolution; the recorded messages' squares
  // sum to it within 4 % (2 % in RMS). The logger can lose a few messages of the burst when
  // measuring starts (revolutions still on the nominal model, with 10× the later residual): the
  // lost revolutions may then account for the rest, up to the largest recorded square each.
  const double all_fx_sq = std::pow(live["residual_rms_N"]["fx"].get<double>(), 2) * revolutions;
  const auto lost = static_cast<double>(revolutions) - static_cast<double>(residuals.size());
  EXPECT_LE(fx_sq, 1.04 * all_fx_sq);
  EXPECT_GE(fx_sq + 1.04 * lost * fx_sq_max, 0.96 * all_fx_sq)
      << lost << " residual messages lost by the logger";

  // The synchronous average every 30 revolutions, measured and model on 256 bins.
  const auto sync = decode_all<sync_average2_t>(events(log, "MILLWATCH_SYNC_AVERAGE"));
  ASSERT_GE(sync.size(), 5u);
  for (std::size_t i = 0; i < sync.size(); ++i) {
    if (i > 0) {
      EXPECT_GT(sync[i].revolution, sync[i - 1].revolution);
    }
    ASSERT_EQ(sync[i].num_bins, 256);
    EXPECT_EQ(sync[i].window_revolutions, 30);
    EXPECT_TRUE(sync[i].model_valid);
  }
  double peak_fy = 0.0;
  double peak_model_fy = 0.0;
  for (int k = 0; k < 256; ++k) {
    peak_fy = std::max(peak_fy, std::fabs(sync.back().fy_N[static_cast<std::size_t>(k)]));
    peak_model_fy =
        std::max(peak_model_fy, std::fabs(sync.back().model_fy_N[static_cast<std::size_t>(k)]));
  }
  EXPECT_GT(peak_fy, 1.0);
  EXPECT_NEAR(peak_model_fy, peak_fy, 0.3 * peak_fy);

  // The alerts on LCM are the summary's.
  const auto alerts = decode_all<tool_alert_t>(events(log, "MILLWATCH_ALERT"));
  ASSERT_EQ(alerts.size(), live["alerts"].size());
  for (std::size_t i = 0; i < alerts.size(); ++i) {
    EXPECT_EQ(alerts[i].revolution, live["alerts"][i]["revolution"].get<std::int64_t>());
    EXPECT_EQ(alerts[i].active, live["alerts"][i]["active"].get<bool>());
    EXPECT_EQ(alerts[i].quantity, live["alerts"][i]["quantity"].get<std::string>());
  }

  const auto status = decode_all<pipeline_status5_t>(events(log, "MILLWATCH_STATUS"));
  ASSERT_FALSE(status.empty());
  for (std::size_t i = 1; i < status.size(); ++i) {
    EXPECT_GT(status[i].seq, status[i - 1].seq);
    EXPECT_GE(status[i].samples_in, status[i - 1].samples_in);
  }
  EXPECT_EQ(status.back().samples_in, 50000);  // the final status, published on SIGTERM
  EXPECT_EQ(status.back().samples_dropped, 0);
  EXPECT_EQ(status.back().blocks_rejected, 0);
  EXPECT_EQ(status.back().revolutions, revolutions);

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
  // The residuals are against the model with the identified parameters, taken at each result's
  // due revolution: the replay waits for every fit, the live run never does. They agree exactly
  // when the live identifier kept up (no window dropped, no result late); on a machine too busy
  // for that, the live run said so in its summary and the residuals agree to a few percent.
  ASSERT_TRUE(live.contains("fit")) << live.dump(2);
  const bool kept_up = live["fit"]["windows_dropped"].get<int>() == 0 &&
                       live["fit"]["results_late"].get<int>() == 0 &&
                       live["fit"]["windows_skipped_for_budget"].get<int>() == 0;
  EXPECT_GT(offline["model"]["identified_parameters_taken"].get<int>(), 0) << offline.dump(2);
  EXPECT_EQ(offline["fit"]["windows_dropped"].get<int>(), 0);
  EXPECT_EQ(offline["fit"]["results_late"].get<int>(), 0);
  EXPECT_EQ(offline["fit"]["windows_skipped_for_budget"].get<int>(), 0);  // a replay: no budget
  for (const char* axis : {"fx", "fy", "fz"}) {
    const double a = offline["residual_rms_N"][axis].get<double>();
    const double b = live["residual_rms_N"][axis].get<double>();
    if (kept_up) {
      EXPECT_DOUBLE_EQ(a, b) << axis;
    } else {
      EXPECT_NEAR(a, b, 0.05 * b) << axis << ": the live identifier fell behind";
    }
  }

  // The live daemon read the group itself, in rounds (source.receive's default).
  const std::string rounds = "the udpm group read in rounds by the sample thread";
  EXPECT_NE(test::read_text(dir_ / "daemon.log").find(rounds), std::string::npos);

  // lcm-logplayer feeds the recorded raw log into a fresh daemon taking its blocks from LCM's
  // receive thread (source.receive "lcm"), stopped by SIGINT this time: the same results again.
  nlohmann::json lcm_receive = read_json(dir_ / "monitor.json");
  lcm_receive["source"]["receive"] = "lcm";
  std::ofstream(dir_ / "monitor_lcm_receive.json") << lcm_receive.dump(2);
  const auto played = session("logplayer", dir_);
  ASSERT_EQ(played.exit_code, 0) << played.output << test::read_text(dir_ / "played.log");
  EXPECT_NE(played.output.find("daemon exit 0"), std::string::npos) << played.output;
  EXPECT_NE(test::read_text(dir_ / "played.log").find("SIGINT: stopping"), std::string::npos);
  EXPECT_EQ(test::read_text(dir_ / "played.log").find(rounds), std::string::npos);
  const nlohmann::json again = read_json(dir_ / "played.json");
  ASSERT_FALSE(again.is_null()) << test::read_text(dir_ / "played.log");
  EXPECT_EQ(again["samples"], 50000);
  EXPECT_EQ(again["dropped_samples"], 0);
  EXPECT_EQ(again["revolutions"], live["revolutions"]);
  EXPECT_DOUBLE_EQ(again["alpha_deg"]["mean"].get<double>(),
                   live["alpha_deg"]["mean"].get<double>());
}

// Issue 3 §4 and §6: SIGHUP reloads without losing samples and the new configuration is in
// effect (commanded speed on MILLWATCH_SPINDLE, status period); a bad file on reload is reported
// by field and the running configuration kept; garbage on the raw channel — random bytes,
// force_block_t messages whose sample count is malformed (one that wraps lcm-gen's size check
// and made its decode read past the datagram, a negative one that made it throw) and blocks
// that decode but cannot be used — is counted in the status and the summary and survived;
// SIGTERM stops with the final summary.
TEST_F(MillwatchdSession, ReloadsKeepsRunningOnBadConfigAndCountsGarbage) {
  sim::Scenario s;
  s.sample_rate_hz = 50000.0;
  s.duration_s = 1.0;
  s.spindle.actual_rpm = 25252.0;
  // Blocks of 250 samples: the daemon's messages of a block fit the logger's queue.
  test::write_force_log(dir_ / "part1.lcmlog", s, 250, 0, 100);
  test::write_force_log(dir_ / "part2.lcmlog", s, 250, 100, 200);
  constexpr int kRandomMessages = 5;
  constexpr int kMalformedMessages = 2;
  constexpr int kWrongRateSamples = 1000;
  {
    lcm::LogFile garbage((dir_ / "garbage.lcmlog").string(), "w");
    std::mt19937 rng(3);
    for (int i = 0; i < kRandomMessages; ++i) {
      std::vector<std::uint8_t> bytes(static_cast<std::size_t>(100 + 50 * i));
      for (auto& b : bytes) {
        b = static_cast<std::uint8_t>(rng());
      }
      lcm::LogEvent e{i, 500000 + i, "MILLWATCH_FORCE_RAW", static_cast<std::int32_t>(bytes.size()),
                      bytes.data()};
      garbage.writeEvent(&e);
    }
    // Whole-looking blocks of 40 samples whose num_samples (big-endian at byte 32) is 2²⁸ + 1,
    // then −1.
    for (const std::uint32_t count : {(1u << 28) + 1, 0xFFFFFFFFu}) {
      const std::vector<double> forty(40, 1.0);
      const force_block_t m = messaging::to_message({500000, 999, 50000.0, forty, forty, forty});
      std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
      m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
      for (int i = 0; i < 4; ++i) {
        bytes[static_cast<std::size_t>(32 + i)] = static_cast<std::uint8_t>(count >> (24 - 8 * i));
      }
      lcm::LogEvent e{kRandomMessages, 500000, "MILLWATCH_FORCE_RAW",
                      static_cast<std::int32_t>(bytes.size()), bytes.data()};
      garbage.writeEvent(&e);
    }
    // Blocks that decode but are no use: empty, and at a sample rate not the configured one.
    force_block_t empty{};
    empty.utime = 500000;
    empty.seq = 1000;
    empty.sample_rate_hz = 50000.0;
    test::write_force_event(garbage, kRandomMessages, empty);
    const std::vector<double> zeros(kWrongRateSamples, 0.0);
    test::write_force_event(garbage, kRandomMessages + 1,
                            messaging::to_message({500000, 1001, 20000.0, zeros, zeros, zeros}));
  }
  // After the last block, one the daemon drops (more samples than source.max_block_samples):
  // no block after it shows the gap, yet its samples count as dropped. Before the first, a block
  // the pipeline rejects (not the configured rate) and one the source drops: the pipeline takes
  // the first good block without timing, so no gap shows those either.
  constexpr int kOversizedSamples = 2500;
  constexpr int kHeadWrongRateSamples = 500;
  {
    lcm::LogFile tail((dir_ / "tail.lcmlog").string(), "w");
    const std::vector<double> zeros(kOversizedSamples, 0.0);
    test::write_force_event(tail, 0,
                            messaging::to_message({1'000'000, 200, 50000.0, zeros, zeros, zeros}));
    lcm::LogFile head((dir_ / "head.lcmlog").string(), "w");
    const std::vector<double> few(kHeadWrongRateSamples, 0.0);
    test::write_force_event(head, 0, messaging::to_message({-100'000, -2, 20000.0, few, few, few}));
    test::write_force_event(head, 1,
                            messaging::to_message({-50'000, -1, 50000.0, zeros, zeros, zeros}));
  }
  // Start: status every 0.05 s of samples, commanded 25,000 rpm. Good reload: every 10 s and
  // 25,100 rpm. Bad reload: a mistyped field (and 26,000 rpm, which must not be taken).
  nlohmann::json initial = nlohmann::json::parse(std::ifstream(dir_ / "monitor.json"));
  initial["status_period_s"] = 0.05;
  initial["source"]["max_block_samples"] = 2000;  // blocks of up to 1,000 samples below
  nlohmann::json good = initial;
  good["status_period_s"] = 10.0;
  good["monitor"]["model"]["process"]["spindle_rpm"] = 25100.0;
  nlohmann::json bad = good;
  bad["monitor"]["model"]["tool"]["flutes"] = "two";
  bad["monitor"]["model"]["process"]["spindle_rpm"] = 26000.0;
  std::ofstream(dir_ / "initial.json") << initial.dump();
  std::ofstream(dir_ / "good.json") << good.dump();
  std::ofstream(dir_ / "bad.json") << bad.dump();

  const auto r = session("reload", dir_);
  const std::string log = test::read_text(dir_ / "reload.log");
  ASSERT_EQ(r.exit_code, 0) << r.output << log;
  EXPECT_NE(r.output.find("daemon exit 0"), std::string::npos) << r.output;
  EXPECT_NE(log.find("configuration reloaded after 25500 samples"), std::string::npos) << log;
  EXPECT_NE(log.find("monitor.model.tool.flutes"), std::string::npos) << log;
  EXPECT_NE(log.find("keeping the running configuration"), std::string::npos) << log;
  EXPECT_NE(log.find("does not decode"), std::string::npos) << log;
  EXPECT_NE(log.find("(36 + 24 x 268435457 = 6442451004 bytes expected for num_samples "
                     "268435457, got 996); dropped"),
            std::string::npos)
      << log;
  EXPECT_NE(log.find("(num_samples -1 is negative); dropped"), std::string::npos) << log;
  EXPECT_NE(log.find("final summary"), std::string::npos) << log;
  const nlohmann::json summary = read_json(dir_ / "reload.json");
  ASSERT_FALSE(summary.is_null()) << log;
  const std::int64_t unusable = 2;
  EXPECT_EQ(summary["samples"], 50000);  // every sample, across the reloads
  EXPECT_EQ(summary["counters"]["samples_in"], 50000 + kWrongRateSamples + kHeadWrongRateSamples);
  // The unusable blocks' and the oversized ones'.
  const int dropped = kWrongRateSamples + kHeadWrongRateSamples + 2 * kOversizedSamples;
  EXPECT_EQ(summary["dropped_samples"], dropped);
  EXPECT_EQ(summary["counters"]["blocks_rejected"],
            kRandomMessages + kMalformedMessages + unusable + 3)  // and the head's and the tail's
      << summary.dump(2);
  EXPECT_GT(summary["revolutions"].get<int>(), 100);  // it kept measuring after all that

  // What the daemon said on LCM meanwhile.
  const auto recorded = read_log(dir_ / "reload.lcmlog");
  const auto status = decode_all<pipeline_status5_t>(events(recorded, "MILLWATCH_STATUS"));
  ASSERT_FALSE(status.empty());
  int before_reload = 0;
  int late_in_part2 = 0;
  for (std::size_t i = 0; i < status.size(); ++i) {
    if (i > 0) {  // samples_in keeps counting through the reloads
      EXPECT_GE(status[i].samples_in, status[i - 1].samples_in) << "status " << status[i].seq;
    }
    before_reload += status[i].utime > 0 && status[i].utime < 500000 ? 1 : 0;
    late_in_part2 += status[i].utime > 600000 && status[i].utime < 950000 ? 1 : 0;
  }
  EXPECT_GE(before_reload, 5);  // every 0.05 s of samples before the reload,
  EXPECT_EQ(late_in_part2, 0);  // every 10 s after it
  EXPECT_EQ(status.back().samples_in,
            50000 + kWrongRateSamples + kHeadWrongRateSamples);  // the final status
  EXPECT_EQ(status.back().samples_processed, 50000);
  EXPECT_EQ(status.back().blocks_rejected, kRandomMessages + kMalformedMessages + unusable + 3);
  EXPECT_EQ(status.back().samples_dropped, dropped);
  EXPECT_EQ(status.back().revolutions, summary["revolutions"].get<std::int64_t>());  // both parts

  // The commanded speed of the good reload is in effect after it; the bad one's never is.
  const auto spindle = decode_all<spindle_state2_t>(events(recorded, "MILLWATCH_SPINDLE"));
  std::size_t first_new = spindle.size();
  for (std::size_t i = 0; i < spindle.size(); ++i) {
    EXPECT_NE(spindle[i].spindle_rpm_commanded, 26000.0);
    if (spindle[i].spindle_rpm_commanded == 25100.0 && first_new == spindle.size()) {
      first_new = i;
    }
    if (first_new < i) {
      EXPECT_EQ(spindle[i].spindle_rpm_commanded, 25100.0) << "update " << spindle[i].seq;
    }
  }
  ASSERT_GT(first_new, 0u) << "no spindle update before the reload";
  ASSERT_LT(first_new, spindle.size()) << "no spindle update after the reload";
  EXPECT_EQ(spindle.front().spindle_rpm_commanded, 25000.0);
  EXPECT_TRUE(spindle.back().valid);
  EXPECT_NEAR(spindle.back().spindle_rpm_measured, 25252.0, 0.001 * 25252.0);
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
    // Its nulls with their reason (it had said only "no identification").
    bool said = false;
    for (const auto& w : j["warnings"]) {
      said = said ||
             (w["kind"] == "no samples" &&
              w["detail"].get<std::string>().find(
                  "0 message(s) on channel MILLWATCH_FORCE_RAW from memq://") != std::string::npos);
    }
    EXPECT_TRUE(said) << j["warnings"];
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
  // A summary that cannot be written on exit is said at once, by --check too (it had run the
  // whole session and failed at its end).
  const auto no_summary = test::run_command(kDaemon + " --check -c " + shipped.string() +
                                            " --summary /proc/no_such_folder/s.json 2>&1");
  EXPECT_EQ(no_summary.exit_code, 2) << no_summary.output;
  EXPECT_NE(no_summary.output.find(
                "--summary /proc/no_such_folder/s.json: no folder /proc/no_such_folder"),
            std::string::npos)
      << no_summary.output;

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
      {"output_url", "/lcm/output_url", 7, "lcm.output_url"},
      {"output_url_form", "/lcm/output_url", "239.255.76.67:7668",
       "lcm.output_url: \"239.255.76.67:7668\" is not an LCM URL"},
      // A provider LCM does not have had passed --check and failed only at start.
      {"url_provider", "/lcm/url", "bogus://x",
       "lcm.url: \"bogus://x\": no LCM provider \"bogus\" (LCM 1.3.1 has udpm, tcpq, file and "
       "memq)"},
      {"max_block", "/source/max_block_samples", 5000,
       "source.max_block_samples: value 5000 is out of range [1, 4096]"},
      {"wake_period", "/source/wake_period_s", 0.5,
       "source.wake_period_s: value 0.5 is out of range [0, 0.1]"},
      // A Comedi block must fit the queue's slots (4096 samples; 8192 used to be accepted).
      {"block", "/source/block_samples", 8192,
       "source.block_samples: value 8192 is out of range [16, 4096]"},
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

// Issue 3 §6: a file that reads well but that the pipeline's stages refuse (a spindle window
// shorter than 5 revolutions at the commanded speed) is a clear error at --check, at start and on
// SIGHUP — never a crash of the sample thread. A reload that changes what only a restart can
// change says so. (In-process LCM: no traffic.)
TEST(Millwatchd, ConfigurationTheStagesRefuseIsAnErrorNotACrash) {
  const fs::path dir = test::fresh_temp_dir();
  const nlohmann::json good = {{"monitor", {{"sample_rate_hz", 50000.0}}}};
  nlohmann::json refused = good;
  refused["monitor"]["spindle"]["window_s"] = 0.1;
  refused["monitor"]["model"]["process"]["spindle_rpm"] = 2000.0;  // 3.3 revolutions
  nlohmann::json restart = good;
  restart["source"]["channel"] = "OTHER_RAW";
  std::ofstream(dir / "good.json") << good.dump();
  std::ofstream(dir / "refused.json") << refused.dump();
  std::ofstream(dir / "restart.json") << restart.dump();
  const std::string expected = "refused.json: monitor.spindle.window_s";

  const auto check = test::run_command(kDaemon + " --check -c " + (dir / "refused.json").string());
  EXPECT_EQ(check.exit_code, 2) << check.output;
  EXPECT_NE(check.output.find(expected), std::string::npos) << check.output;
  const auto start = test::run_command("timeout -k 5 20 " + kDaemon + " -c " +
                                       (dir / "refused.json").string() + " --lcm-url memq://");
  EXPECT_EQ(start.exit_code, 2) << start.output;
  EXPECT_NE(start.output.find(expected), std::string::npos) << start.output;

  const fs::path running = dir / "running.json";
  fs::copy_file(dir / "good.json", running);
  const fs::path summary = dir / "summary.json";
  const auto r = test::run_command(
      "cd " + dir.string() + " && timeout -k 5 30 sh -c '" + kDaemon +
      " -c running.json --lcm-url memq:// --summary summary.json 2>daemon.log & pid=$!; "
      "sleep 0.5; cp restart.json running.json; kill -HUP $pid; sleep 0.3; "
      "cp refused.json running.json; kill -HUP $pid; sleep 0.3; "
      "kill -TERM $pid; wait $pid; echo exit=$?'");
  const std::string log = test::read_text(dir / "daemon.log");
  EXPECT_NE(r.output.find("exit=0"), std::string::npos) << r.output << log;
  EXPECT_NE(log.find("source.channel changed; that takes a restart"), std::string::npos) << log;
  EXPECT_NE(log.find("configuration reloaded"), std::string::npos) << log;
  EXPECT_NE(log.find("monitor.spindle.window_s"), std::string::npos) << log;
  EXPECT_NE(log.find("keeping the running configuration"), std::string::npos) << log;
  EXPECT_TRUE(fs::exists(summary)) << log;
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
  const auto check = test::run_command(kDaemon + " --check -c " + (dir / "daq.json").string());
  EXPECT_EQ(check.exit_code, 0) << check.output;  // the file is fine; the device is not there
  const auto r = test::run_command("timeout -k 5 30 " + kDaemon + " -c " +
                                   (dir / "daq.json").string() + " --lcm-url memq://");
  EXPECT_EQ(r.exit_code, 2) << r.output;  // an error exit, not a signal or a timeout
  EXPECT_NE(r.output.find("/dev/comedi9"), std::string::npos) << r.output;
  if (r.output.find("built without comedilib") != std::string::npos) {
    GTEST_SKIP() << "millwatchd was built without comedilib (libcomedi-dev): " << r.output;
  }
  EXPECT_NE(r.output.find("/dev/comedi9: cannot open Comedi device"), std::string::npos)
      << r.output;
}

// Issue 3 §5: udpm:// without a multicast route (a private network namespace without one) is a
// clear error at once, not a daemon that hears nothing.
TEST(Millwatchd, UdpmWithoutAMulticastRouteFailsAtOnce) {
  std::string why;
  if (!test::private_network_works(why)) {
    GTEST_SKIP() << "no private network namespace here (unshare -n): " << why;
  }
  const fs::path dir = test::fresh_temp_dir();
  std::ofstream(dir / "d.json") << nlohmann::json{
      {"monitor",
       {{"sample_rate_hz", 50000.0}}}}.dump();
  const auto r = test::run_command("timeout -k 5 20 unshare -n sh -c 'ip link set lo up; " +
                                   kDaemon + " -c " + (dir / "d.json").string() +
                                   " --lcm-url \"udpm://239.255.76.67:7667?ttl=0\"; echo exit=$?'");
  EXPECT_NE(r.output.find("exit=2"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("cannot open LCM at udpm://239.255.76.67:7667?ttl=0"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("multicast route"), std::string::npos) << r.output;
}

// A file:// source that is not there gets the file provider's reason, not udpm's route hint;
// a log read as the output (--lcm-url alone) is said to drop every result.
TEST(Millwatchd, AFileUrlSaysWhatIsWrongWithTheLog) {
  const fs::path dir = test::fresh_temp_dir();
  std::ofstream(dir / "d.json") << nlohmann::json{
      {"monitor",
       {{"sample_rate_hz", 50000.0}}}}.dump();
  const auto missing =
      test::run_command("timeout 20 " + kDaemon + " -c " + (dir / "d.json").string() +
                        " --lcm-url file://" + (dir / "none.lcmlog").string() + " 2>&1");
  EXPECT_EQ(missing.exit_code, 2) << missing.output;
  EXPECT_NE(
      missing.output.find(
          "none.lcmlog (lcm.url, or its option --lcm-url): the log is not there or cannot be read"),
      std::string::npos)
      << missing.output;
  EXPECT_EQ(missing.output.find("multicast"), std::string::npos) << missing.output;
  // A log to read, as input and (unsaid) output: the warning.
  const auto published = test::run_command(test::millwatch_cli() + " publish " +
                                           (test::source_dir() / "config" / "demo.json").string() +
                                           " --duration 0.01 --speed 0 --url 'file://" +
                                           (dir / "demo.lcmlog").string() + "?mode=w' 2>&1");
  ASSERT_EQ(published.exit_code, 0) << published.output;
  const auto read_out =
      test::run_command("timeout 20 sh -c '" + kDaemon + " -c " + (dir / "d.json").string() +
                        " --lcm-url \"file://" + (dir / "demo.lcmlog").string() +
                        "?speed=0\" & pid=$!; sleep 0.5; kill -TERM $pid; wait $pid' 2>&1");
  EXPECT_NE(read_out.output.find("is a log opened for reading: every result published is dropped"),
            std::string::npos)
      << read_out.output;
}

}  // namespace
}  // namespace millwatch
