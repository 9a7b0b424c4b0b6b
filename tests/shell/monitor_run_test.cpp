// The monitoring run both shells share: status cadence on LCM (memq://), counts carried across
// a pipeline replaced by a reload, the source's losses in the status and the summary.

#include "shell/monitor_run.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/model/flute_positions.hpp"
#include "core/sim/scenario.hpp"
#include "millwatch/force_coefficients_t.hpp"
#include "millwatch/pipeline_status5_t.hpp"
#include "millwatch/runout_estimate_t.hpp"
#include "tests/support/recording.hpp"

namespace millwatch::shell {
namespace {

constexpr double kRate_hz = 50000.0;
constexpr std::size_t kBlock = 1000;  // 20 ms

monitor::MonitorConfig config() {
  monitor::MonitorConfig c;
  c.sample_rate_hz = kRate_hz;
  return c;
}

/// Block k of a quiet stream (20 ms per block, from t = 0).
struct Blocks {
  std::vector<double> zeros = std::vector<double>(kBlock, 0.0);
  monitor::SampleBlock operator()(std::int64_t k) const {
    return {k * 20'000, k, kRate_hz, zeros, zeros, zeros};
  }
};

/// Block k of a recording (kBlock samples, 20 ms), stamped `from_us` later, numbered `seq`
/// (default: k).
monitor::SampleBlock block_of(const test::Recording& r, std::size_t k, std::int64_t from_us = 0,
                              std::int64_t seq = -1) {
  const std::size_t from = k * kBlock;
  return {from_us + std::llround(r.t[from] * 1e6),
          seq < 0 ? static_cast<std::int64_t>(k) : seq,
          kRate_hz,
          std::span<const double>(r.fx).subspan(from, kBlock),
          std::span<const double>(r.fy).subspan(from, kBlock),
          std::span<const double>(r.fz).subspan(from, kBlock)};
}

/// The default 2-flute cut for `duration_s`, its spindle at 25,252 rpm (1 % above the
/// commanded 25,000).
sim::Scenario two_flute_cut(double duration_s) {
  sim::Scenario s;
  s.sample_rate_hz = kRate_hz;
  s.duration_s = duration_s;
  s.spindle.actual_rpm = 25252.0;
  return s;
}

/// A run without identification: its alerts follow the flute forces.
MonitorRun::Options without_identification() {
  MonitorRun::Options options;
  options.identify = false;
  return options;
}

struct StatusLog {
  std::vector<pipeline_status5_t> messages;
  void on_status(const lcm::ReceiveBuffer*, const std::string&, const pipeline_status5_t* m) {
    messages.push_back(*m);
  }
};

TEST(MonitorRun, PublishesAStatusEveryPeriodOfSampleTimeAndAFinalOne) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  StatusLog rx;
  lcm.subscribe("MILLWATCH_STATUS", &StatusLog::on_status, &rx)->setQueueCapacity(1000);
  MonitorRun::Options options;
  options.lcm = &lcm;
  options.status_period_s = 0.2;
  MonitorRun run(config(), options);
  const Blocks blocks;
  for (std::int64_t k = 0; k < 50; ++k) {  // 1 s
    run.process(blocks(k));
  }
  run.finish();
  run.drain();
  while (lcm.handleTimeout(50) > 0) {
  }
  // At 0, 0.2, 0.4, 0.6 and 0.8 s of sample time, and the final status.
  ASSERT_EQ(rx.messages.size(), 6u);
  EXPECT_EQ(rx.messages[0].samples_in, 1000);
  EXPECT_EQ(rx.messages[1].samples_in, 11000);
  EXPECT_EQ(rx.messages[4].samples_in, 41000);
  EXPECT_EQ(rx.messages[5].samples_in, 50000);
  EXPECT_EQ(run.summary()["counters"]["samples_in"], 50000);
}

TEST(MonitorRun, ReplacedPipelinesAndSourceLossesAreCounted) {
  MonitorRun::Options options;
  options.source_losses = [](monitor::PipelineStatus& s) {
    s.input.samples_dropped += 7;
    s.input.blocks_rejected += 2;
  };
  MonitorRun run(config(), options);
  const Blocks blocks;
  for (std::int64_t k = 0; k < 10; ++k) {
    run.process(blocks(k));
  }
  run.process(blocks(3));  // out of order: rejected by the first pipeline
  auto old = run.replace_pipeline(std::make_unique<monitor::Pipeline>(config(), run.sink()));
  ASSERT_NE(old, nullptr);
  EXPECT_EQ(old->status().input.samples_in, 11000);
  EXPECT_EQ(run.carried_samples_in(), 11000);
  for (std::int64_t k = 10; k < 20; ++k) {
    run.process(blocks(k));
  }
  const monitor::PipelineStatus s = run.status();
  EXPECT_EQ(s.input.samples_in, 21000);
  EXPECT_EQ(s.input.samples_accepted, 20000);
  EXPECT_EQ(s.input.samples_dropped, 1000 + 7);
  EXPECT_EQ(s.input.out_of_order_blocks, 1);
  EXPECT_EQ(s.input.blocks_rejected, 1 + 2);
  run.finish();
  const nlohmann::json j = run.summary();
  EXPECT_EQ(j["samples"], 20000);
  EXPECT_EQ(j["dropped_samples"], 1007);
  EXPECT_EQ(j["counters"]["blocks_rejected"], 3);
}

// Samples lost across a reload (a block the source dropped as the configuration changed) are a
// gap of the stream: counted as dropped, as without the reload — through reloads that saw no
// block too — and a reload without a loss adds none.
TEST(MonitorRun, AGapAcrossAReloadIsCountedAsDropped) {
  const Blocks blocks;
  const auto run_with = [&](std::int64_t reloads, std::int64_t lost) {
    const MonitorRun::Options options = without_identification();
    MonitorRun run(config(), options);
    for (std::int64_t k = 0; k < 10; ++k) {
      run.process(blocks(k));
    }
    for (std::int64_t i = 0; i < reloads; ++i) {
      run.replace_pipeline(std::make_unique<monitor::Pipeline>(config(), run.sink()));
    }
    for (std::int64_t k = 10 + lost; k < 20; ++k) {
      run.process(blocks(k));
    }
    return run.status().input;
  };
  EXPECT_EQ(run_with(1, 0).samples_dropped, 0);
  EXPECT_EQ(run_with(1, 0).gaps, 0);
  EXPECT_EQ(run_with(0, 1).samples_dropped, 1000);  // the same loss without a reload
  EXPECT_EQ(run_with(1, 1).samples_dropped, 1000);
  EXPECT_EQ(run_with(1, 1).gaps, 1);
  EXPECT_EQ(run_with(2, 2).samples_dropped, 2000);
  EXPECT_EQ(run_with(2, 2).samples_accepted, 18000);
}

// The sender goes to 25 kHz before the configuration follows: the old pipeline rejects the new
// blocks (counted), and the new one starts on the first it takes without counting that time
// again as a gap.
TEST(MonitorRun, AReloadToANewRateCountsTheRejectedBlocksOnce) {
  const MonitorRun::Options options = without_identification();
  MonitorRun run(config(), options);
  const Blocks blocks;
  for (std::int64_t k = 0; k < 10; ++k) {
    run.process(blocks(k));  // 50 kHz, 20 ms each: 0 to 200 ms
  }
  monitor::MonitorConfig slow = config();
  slow.sample_rate_hz = 25000.0;
  const std::vector<double> zeros(kBlock, 0.0);
  const auto slow_block = [&](std::int64_t k) {  // 25 kHz, 40 ms each, from 200 ms on
    return monitor::SampleBlock{200'000 + k * 40'000, 10 + k, 25000.0, zeros, zeros, zeros};
  };
  for (std::int64_t k = 0; k < 5; ++k) {
    run.process(slow_block(k));  // rejected: not the configured rate
  }
  run.replace_pipeline(std::make_unique<monitor::Pipeline>(slow, run.sink()));
  const std::int64_t reached_us = run.status().utime_us;  // the old pipeline's last
  EXPECT_GE(reached_us, 9 * 20'000 + 999 * 20);
  run.process(blocks(10));                       // one more at 50 kHz: the new pipeline rejects it
  EXPECT_EQ(run.status().utime_us, reached_us);  // nothing taken yet: the stream's time stays
  for (std::int64_t k = 5; k < 10; ++k) {
    run.process(slow_block(k));
  }
  const monitor::InputCounters c = run.status().input;
  EXPECT_EQ(c.samples_dropped, 6 * 1000);
  EXPECT_EQ(c.samples_accepted, 15 * 1000);
  EXPECT_EQ(c.blocks_rejected, 6);
  // The summary's duration: 10,000 samples at 50 kHz and 5,000 at 25 kHz, 0.4 s (the total at
  // the new rate alone had read 0.6 s), and the change said.
  run.finish();
  const nlohmann::json j = run.summary();
  EXPECT_DOUBLE_EQ(j["duration_s"].get<double>(), 0.4) << j["duration_s"];
  EXPECT_EQ(j["sample_rate_hz"], 25000.0);
  bool said = false;
  for (const auto& w : j["warnings"]) {
    said = said || (w["kind"] == "rate changed" &&
                    w["detail"].get<std::string>().rfind(
                        "sample_rate_hz 50000 → 25000 Hz on a reload", 0) == 0);
  }
  EXPECT_TRUE(said) << j["warnings"];
}

// A reload mid-cut: the run's counts go on from where the replaced pipeline left them — the
// revolutions turned while cutting and the model builds too, not only the samples.
TEST(MonitorRun, AReloadMidCutCarriesEveryCount) {
  const sim::Scenario s = two_flute_cut(1.0);
  const test::Recording r = test::record(s);
  const MonitorRun::Options options = without_identification();
  MonitorRun run(test::monitor_for(s), options);
  for (std::size_t k = 0; k < 25; ++k) {
    run.process(block_of(r, k));
  }
  auto next = std::make_unique<monitor::Pipeline>(test::monitor_for(s), run.sink());
  const monitor::Pipeline& second = *next;
  const auto old = run.replace_pipeline(std::move(next));
  const monitor::PipelineStatus before = old->status();  // finished: the tail heard counted
  ASSERT_GT(before.cutting_revolutions, 150.0);
  ASSERT_GT(before.model_builds, 0);
  for (std::size_t k = 25; k < 50; ++k) {
    run.process(block_of(r, k));
  }
  const monitor::PipelineStatus after = run.status();
  const monitor::PipelineStatus last = second.status();
  EXPECT_EQ(after.model_builds, before.model_builds + last.model_builds);
  EXPECT_NEAR(after.cutting_revolutions, before.cutting_revolutions + last.cutting_revolutions,
              1e-9);
  // The whole second heard cutting, within the revolutions a restarted tracker needs to hear.
  EXPECT_NEAR(after.cutting_revolutions, 25252.0 / 60.0, 5.0);
}

// The flutes' relabellings across a reload: a knock (the samples half a turn on, the flutes'
// forces swapped, over revolutions 60–180) relabels the first pipeline's flutes; the pipeline a
// reload puts in its place mid-knock locks on its own, and relabels when the knock is over. The
// run counts both, and its last relabelling's first revolution is the newest, numbered on from
// the replaced pipeline's revolutions.
TEST(MonitorRun, AReloadCarriesTheFlutesRelabellings) {
  const sim::Scenario s = two_flute_cut(1.0);
  const test::Recording r = test::knocked_record(s, 120.0, 60.0);
  MonitorRun run(test::monitor_for(s), without_identification());
  constexpr std::size_t kReloadBlock = 18;  // 0.36 s: revolution 151
  for (std::size_t k = 0; k < kReloadBlock; ++k) {
    run.process(block_of(r, k));
  }
  auto next = std::make_unique<monitor::Pipeline>(test::monitor_for(s), run.sink());
  const monitor::Pipeline& second = *next;
  const auto old = run.replace_pipeline(std::move(next));
  const monitor::PipelineStatus before = old->status();
  ASSERT_EQ(before.flutes_relabelled, 1);  // once into the knock
  EXPECT_GT(before.relabelled_from_revolution, 60);
  EXPECT_LT(before.relabelled_from_revolution, 151);
  const monitor::PipelineStatus reloaded = run.status();
  EXPECT_EQ(reloaded.flutes_relabelled, 1);
  EXPECT_EQ(reloaded.relabelled_from_revolution, before.relabelled_from_revolution);
  for (std::size_t k = kReloadBlock; k < r.t.size() / kBlock; ++k) {
    run.process(block_of(r, k));
  }
  const monitor::PipelineStatus last = second.status();
  ASSERT_EQ(last.flutes_relabelled, 1);  // once out of it
  EXPECT_GT(last.relabelled_from_revolution, 180);
  const monitor::PipelineStatus after = run.status();
  EXPECT_EQ(after.flutes_relabelled, 2);
  EXPECT_EQ(after.relabelled_from_revolution, last.relabelled_from_revolution);
  std::printf("relabelled from revolution %lld, and after the reload from %lld\n",
              static_cast<long long>(before.relabelled_from_revolution),
              static_cast<long long>(after.relabelled_from_revolution));
}

// A reload clears the replaced pipeline's alerts (with the figures they were raised on): its
// successor starts with none raised and raises again what still holds, so no alert stays raised
// on LCM and in the summary without an engine behind it. Until the new pipeline's first block
// the status keeps the stream's time, and a pipeline replaced after a short stretch does not
// call the record too short.
TEST(MonitorRun, AReloadClearsTheReplacedPipelinesAlertsAndKeepsTheTime) {
  const sim::Scenario s = two_flute_cut(1.0);
  const test::Recording r = test::record(s);
  // Runout from the flute forces: [000]'s runout raises it.
  const MonitorRun::Options options = without_identification();
  MonitorRun run(test::monitor_for(s), options);
  run.process(block_of(r, 0));  // 20 ms, then a reload: not a record too short
  run.replace_pipeline(std::make_unique<monitor::Pipeline>(test::monitor_for(s), run.sink()));
  for (std::size_t k = 1; k < 25; ++k) {
    run.process(block_of(r, k));
  }
  run.replace_pipeline(std::make_unique<monitor::Pipeline>(test::monitor_for(s), run.sink()));
  EXPECT_EQ(run.status().utime_us, 24 * 20'000 + 999 * 20);  // the stream's newest sample
  for (std::size_t k = 25; k < 50; ++k) {
    run.process(block_of(r, k));
  }
  run.finish();
  const nlohmann::json j = run.summary();
  std::vector<nlohmann::json> raised, cleared;
  for (const auto& a : j["alerts"]) {
    if (a["kind"] == "runout") {
      (a["active"].get<bool>() ? raised : cleared).push_back(a);
    }
  }
  ASSERT_EQ(raised.size(), 2u) << j["alerts"].dump(1);  // before the reload, and after it again
  ASSERT_EQ(cleared.size(), 1u) << j["alerts"].dump(1);
  EXPECT_NE(cleared[0]["message"].get<std::string>().find("runout cleared: configuration reloaded"),
            std::string::npos)
      << cleared[0]["message"];
  EXPECT_EQ(cleared[0]["value"], raised[0]["value"]);
  EXPECT_EQ(cleared[0]["threshold"], raised[0]["threshold"]);
  EXPECT_LT(cleared[0]["revolution"].get<double>(), 0.5 * 25252.0 / 60.0);  // the first half's
  // The numbers go on across the reload: the second raise comes after the clear.
  EXPECT_GT(raised[1]["revolution"].get<std::int64_t>(),
            cleared[0]["revolution"].get<std::int64_t>());
  for (const auto& w : j["warnings"]) {
    EXPECT_NE(w["kind"], "record too short") << w.dump();
    EXPECT_NE(w["kind"], "no steady tooth-passing signal") << w.dump();
  }
}

// Sensor trouble in the first block after a reload, before the new pipeline has measured a
// revolution: the alert names the last revolution the stream reported (the numbers go on), not
// "before the first revolution".
TEST(MonitorRun, ASensorAlertRightAfterAReloadNamesTheStreamsLastRevolution) {
  const sim::Scenario s = two_flute_cut(0.54);
  test::Recording r = test::record(s);
  for (std::size_t i = 25 * kBlock; i < 26 * kBlock; ++i) {
    r.fx[i] = std::numeric_limits<double>::quiet_NaN();  // the block after the reload
  }
  const MonitorRun::Options options = without_identification();
  MonitorRun run(test::monitor_for(s), options);
  for (std::size_t k = 0; k < 25; ++k) {
    run.process(block_of(r, k));
  }
  run.replace_pipeline(std::make_unique<monitor::Pipeline>(test::monitor_for(s), run.sink()));
  const std::int64_t last = run.status().revolutions - 1;  // numbered from 0
  ASSERT_GT(last, 100);  // half a second of a 2-flute cut measured before the reload
  for (std::size_t k = 25; k < 27; ++k) {  // 40 ms: the new pipeline measures no revolution
    run.process(block_of(r, k));
  }
  // Another reload: the input since the last health check (half of it not finite) raises the
  // alert, and the hand-over clears it.
  run.replace_pipeline(std::make_unique<monitor::Pipeline>(test::monitor_for(s), run.sink()));
  run.finish();
  const nlohmann::json j = run.summary();
  std::vector<nlohmann::json> raised, cleared;
  for (const auto& a : j["alerts"]) {
    if (a["kind"] == "sensor") {
      (a["active"].get<bool>() ? raised : cleared).push_back(a);
    }
  }
  ASSERT_EQ(raised.size(), 1u) << j["alerts"].dump(1);
  ASSERT_EQ(cleared.size(), 1u) << j["alerts"].dump(1);
  EXPECT_EQ(raised[0]["revolution"].get<std::int64_t>(), last) << raised[0].dump();
  EXPECT_EQ(cleared[0]["revolution"].get<std::int64_t>(), last) << cleared[0].dump();
  // Both at the stream's newest sample, not at 0 for want of a revolution.
  EXPECT_EQ(raised[0]["utime"].get<std::int64_t>(), 26 * 20'000 + 999 * 20);
  EXPECT_EQ(cleared[0]["utime"].get<std::int64_t>(), 26 * 20'000 + 999 * 20);
}

struct IdentityLog {
  std::vector<runout_estimate_t> runout;
  std::vector<force_coefficients_t> coefficients;
  void on_runout(const lcm::ReceiveBuffer*, const std::string&, const runout_estimate_t* m) {
    runout.push_back(*m);
  }
  void on_coefficients(const lcm::ReceiveBuffer*, const std::string&,
                       const force_coefficients_t* m) {
    coefficients.push_back(*m);
  }
};

struct MessageCount {
  std::int64_t messages = 0;
  void on_message(const lcm::ReceiveBuffer*, const std::string&) { ++messages; }
};

/// The monitor's configuration for it: no runout and K_tc 30 % low.
monitor::MonitorConfig config_without_runout(const sim::Scenario& s) {
  monitor::MonitorConfig c = test::monitor_for(s);
  c.model.resolution.steps_per_rev = 720;
  c.model.effects.runout.offset_um = 0.0;
  c.model.material.linear_edge.k_tc_N_per_mm2 *= 0.7;
  return c;
}

void feed(MonitorRun& run, const test::Recording& r) {
  for (std::size_t from = 0; from < r.t.size(); from += kBlock) {
    const std::size_t n = std::min(kBlock, r.t.size() - from);
    run.process({std::llround(r.t[from] * 1e6), static_cast<std::int64_t>(from / kBlock), kRate_hz,
                 std::span<const double>(r.fx).subspan(from, n),
                 std::span<const double>(r.fy).subspan(from, n),
                 std::span<const double>(r.fz).subspan(from, n)});
  }
  run.finish();
}

// A reload onto another tool (2 flutes → 3): the summary states the new cut, and α, the periods
// and the peaks are the new tool's alone, with a warning saying from where.
TEST(MonitorRun, AReloadOntoAnotherToolSummarisesTheNewTool) {
  const sim::Scenario two = two_flute_cut(0.5);
  const sim::Scenario three = test::three_flute_cut_with_runout();
  const MonitorRun::Options options = without_identification();
  MonitorRun run(test::monitor_for(two), options);
  std::int64_t seq = 0;
  const auto play = [&](const test::Recording& r, std::int64_t from_us) {
    for (std::size_t k = 0; (k + 1) * kBlock <= r.t.size(); ++k) {
      run.process(block_of(r, k, from_us, seq++));
    }
  };
  play(test::record(two), 0);
  run.replace_pipeline(std::make_unique<monitor::Pipeline>(test::monitor_for(three), run.sink()));
  play(test::record(three), 500'000);
  run.finish();
  const nlohmann::json j = run.summary();
  // The same as monitoring the 3-flute cut alone.
  MonitorRun alone_run(test::monitor_for(three), options);
  feed(alone_run, test::record(three));
  const nlohmann::json alone = alone_run.summary();
  ASSERT_EQ(j["tooth_period_s"].size(), 3u) << j.dump(1);
  for (std::size_t f = 0; f < 3; ++f) {
    EXPECT_NEAR(j["tooth_period_s"][f].get<double>(), alone["tooth_period_s"][f].get<double>(),
                1e-6)
        << f;
    EXPECT_NEAR(j["peak_force_N"]["resultant"][f].get<double>(),
                alone["peak_force_N"]["resultant"][f].get<double>(), 0.01)
        << f;
  }
  EXPECT_NEAR(j["alpha_deg"]["mean"].get<double>(), alone["alpha_deg"]["mean"].get<double>(), 0.1);
  EXPECT_EQ(j["spindle_rpm_commanded"], three.model.process.spindle_rpm);
  int changed = 0;
  for (const auto& w : j["warnings"]) {
    if (w["kind"] == "tool changed") {
      ++changed;
      EXPECT_NE(w["detail"].get<std::string>().find("flutes 2 → 3 on a reload"), std::string::npos)
          << w["detail"];
    }
  }
  EXPECT_EQ(changed, 1) << j["warnings"].dump(1);
}

// A simulated 3-flute cut with known runout (noise, quantisation, a finer truth, the actual speed
// 1 % below the commanded one): the run identifies it in its worker thread, publishes each
// window on LCM and puts the last one in the summary.
TEST(MonitorRun, IdentifiesRunoutAndCoefficientsPublishesThemAndSummarises) {
  const sim::Scenario s = test::three_flute_cut_with_runout();
  const model::ModelConfig& m = s.model;
  const monitor::MonitorConfig c = config_without_runout(s);

  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  IdentityLog rx;
  lcm.subscribe("MILLWATCH_RUNOUT", &IdentityLog::on_runout, &rx)->setQueueCapacity(1000);
  lcm.subscribe("MILLWATCH_COEFFICIENTS", &IdentityLog::on_coefficients, &rx)
      ->setQueueCapacity(1000);
  MessageCount every;
  lcm.subscribe(".*", &MessageCount::on_message, &every)->setQueueCapacity(100000);
  MonitorRun::Options options;
  options.lcm = &lcm;
  const test::Recording r = test::record(s);
  std::int64_t published = 0, dropped = 0;
  {
    MonitorRun run(c, options);
    feed(run, r);
    run.drain();
    const nlohmann::json summary = run.summary();
    ASSERT_TRUE(summary["runout"].is_object()) << summary.dump(1);
    const auto truth =
        model::flute_positions(300.0, model::flute_pitch_angles_rad(m.tool), 1.2, 0.5);
    // Up to the labelling: the identified radii relative to CE1 are the truth's from some flute.
    double best = 1e9;
    for (int sh = 0; sh < 3; ++sh) {
      double worst = 0.0;
      for (int j = 0; j < 3; ++j) {
        const double t = truth[static_cast<std::size_t>((j + sh) % 3)].radius_um -
                         truth[static_cast<std::size_t>(sh)].radius_um;
        worst =
            std::max(worst, std::fabs(summary["runout"]["r_minus_r_ce1_um"][j].get<double>() - t));
      }
      best = std::min(best, worst);
    }
    EXPECT_LT(best, 0.1);
    EXPECT_NEAR(summary["runout"]["rho_um"].get<double>(), 1.2,
                std::max(0.2, 2.0 * summary["runout"]["rho_std_um"].get<double>()));
    const double ktc = summary["coefficients"]["k_tc_N_per_mm2"]["value"].get<double>();
    EXPECT_NEAR(ktc, m.material.linear_edge.k_tc_N_per_mm2,
                0.05 * m.material.linear_edge.k_tc_N_per_mm2);
    EXPECT_GT(summary["coefficients"]["k_tc_N_per_mm2"]["std"].get<double>(), 0.0);
    EXPECT_LT(summary["fit"]["unexplained_fraction"].get<double>(), 0.05);
    EXPECT_GE(summary["fit"]["revolutions"].get<int>(), 1);
    published = run.output()->published();
    dropped = run.output()->dropped();
  }
  while (lcm.handleTimeout(50) > 0) {
  }
  // The run's count of messages published is every message on the bus, the estimates too.
  EXPECT_EQ(published, every.messages);
  EXPECT_EQ(dropped, 0);
  ASSERT_FALSE(rx.runout.empty());
  EXPECT_EQ(rx.runout.size(), rx.coefficients.size());
  EXPECT_TRUE(rx.runout.back().valid);
  EXPECT_NEAR(rx.runout.back().offset_um, 1.2,
              std::max(0.2, 2.0 * rx.runout.back().offset_sigma_um));
  EXPECT_GE(rx.coefficients.back().num_coefficients, 4);
}

/// Every revolution's residual.
struct ResidualLog : monitor::PipelineSink {
  std::vector<double> fx_N;
  void on_revolution(const monitor::RevolutionRecord& r) override {
    fx_N.push_back(r.residual_rms_N[0]);
  }
};

double mean(std::span<const double> x) {
  double sum = 0.0;
  for (double v : x) {
    sum += v;
  }
  return sum / static_cast<double>(x.size());
}

// The configured model lacks the runout and has K_tc 30 % low: its residual is large until the
// first identified window is due, then the model in lockstep takes the identified parameters and
// the residual falls to what the noise leaves. Offline (HandOver::kWait) a run is reproducible
// to the last bit whatever the fits cost.
TEST(MonitorRun, TheModelInLockstepTakesTheIdentifiedParametersReproducibly) {
  const sim::Scenario s = test::three_flute_cut_with_runout();
  const monitor::MonitorConfig c = config_without_runout(s);
  const test::Recording r = test::record(s);
  MonitorRun::Options options;
  options.hand_over = identify::HandOver::kWait;
  ResidualLog first, second;
  nlohmann::json summaries[2];
  for (int k = 0; k < 2; ++k) {
    options.observer = k == 0 ? &first : &second;
    MonitorRun run(c, options);
    feed(run, r);
    summaries[k] = run.summary();
  }
  ASSERT_GT(summaries[0]["model"]["identified_parameters_taken"].get<int>(), 0)
      << summaries[0].dump(1);
  EXPECT_EQ(summaries[0]["model"]["identified_parameters_rejected"].get<int>(), 0);
  EXPECT_EQ(summaries[0]["fit"]["results_late"].get<int>(), 0);
  EXPECT_EQ(summaries[0]["residual_rms_N"], summaries[1]["residual_rms_N"]);
  EXPECT_EQ(first.fx_N, second.fx_N);

  // Window 1 ends at revolution 29 (or a little later: windows are reported after a block) and
  // is due a window later, at about revolution 60.
  const auto n = first.fx_N.size();
  ASSERT_GT(n, 150u);
  const double before = mean(std::span(first.fx_N).subspan(5, 50));
  const double after = mean(std::span(first.fx_N).subspan(70, n - 70));
  std::printf("residual fx before %.4f N, after %.4f N\n", before, after);
  EXPECT_LT(after, 0.3 * before);
  EXPECT_LT(after, 0.03);  // the noise 0.015 N per axis, low-passed
}

// An optional parameter named in the configuration (identification.extra_parameters) is fitted
// on every window and reported with the coefficients: the minimum chip thickness of [000]'s
// cp-Ti law on a 2-flute slot at f_t 2 µm, simulated finer than the monitor's model and with its
// measurement chain (noise, quantisation, speed 1 % low); the configuration starts at twice it.
TEST(MonitorRun, FitsTheOptionalParametersTheConfigurationNames) {
  sim::Scenario s;
  s.sample_rate_hz = kRate_hz;
  s.duration_s = 0.4;
  s.seed = 5;
  auto& m = s.model;
  m = model::without_effects(m);  // [000]'s power law
  m.process.feed_per_tooth_um = 2.0;
  model::set_effect(m, "runout", true);
  m.effects.runout.offset_um = 0.4;
  m.effects.runout.angle_rad = 0.5;
  model::set_effect(m, "min_chip", true);
  m.effects.min_chip.h_min_um = 0.6;
  test::as_measured(s);
  m.resolution.steps_per_rev = 2880;
  monitor::MonitorConfig c = test::monitor_for(s);
  c.model.resolution.steps_per_rev = 720;
  c.model.effects.runout.offset_um = 0.0;
  c.model.effects.min_chip.h_min_um = 1.2;
  c.identification.extra_parameters = {"h_min_um"};
  MonitorRun::Options options;
  options.hand_over = identify::HandOver::kWait;
  MonitorRun run(c, options);
  feed(run, test::record(s));
  const nlohmann::json summary = run.summary();
  ASSERT_TRUE(summary["coefficients"].contains("h_min_um")) << summary.dump(1);
  const double h_min = summary["coefficients"]["h_min_um"]["value"].get<double>();
  const double sigma = summary["coefficients"]["h_min_um"]["std"].get<double>();
  std::printf("h_min %.3f ± %.3f um (truth 0.6)\n", h_min, sigma);
  EXPECT_GT(sigma, 0.0);
  EXPECT_NEAR(h_min, 0.6, 2.0 * sigma);
  EXPECT_NEAR(h_min, 0.6, 0.1);
}

}  // namespace
}  // namespace millwatch::shell
