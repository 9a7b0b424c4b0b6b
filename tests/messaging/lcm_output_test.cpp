// In-process LCM (memq://): what the pipeline emits arrives as decodable messages.

#include "msgs/lcm_output.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>
#include <vector>

#include "core/sim/cut_simulator.hpp"
#include "msgs/lcm_convert.hpp"

namespace millwatch::messaging {
namespace {

struct Received {
  std::vector<tooth_periods2_t> periods;
  std::vector<flute_peaks2_t> peaks;
  std::vector<model_residual_t> residuals;
  std::vector<spindle_state2_t> spindle;
  std::vector<pipeline_status5_t> status;
  std::vector<tool_alert_t> alerts;
  std::vector<sync_average2_t> sync;
  void on_periods(const lcm::ReceiveBuffer*, const std::string&, const tooth_periods2_t* m) {
    periods.push_back(*m);
  }
  void on_peaks(const lcm::ReceiveBuffer*, const std::string&, const flute_peaks2_t* m) {
    peaks.push_back(*m);
  }
  void on_residual(const lcm::ReceiveBuffer*, const std::string&, const model_residual_t* m) {
    residuals.push_back(*m);
  }
  void on_spindle(const lcm::ReceiveBuffer*, const std::string&, const spindle_state2_t* m) {
    spindle.push_back(*m);
  }
  void on_status(const lcm::ReceiveBuffer*, const std::string&, const pipeline_status5_t* m) {
    status.push_back(*m);
  }
  void on_alert(const lcm::ReceiveBuffer*, const std::string&, const tool_alert_t* m) {
    alerts.push_back(*m);
  }
  void on_sync(const lcm::ReceiveBuffer*, const std::string&, const sync_average2_t* m) {
    sync.push_back(*m);
  }
};

/// Collects the records the sink saw directly, to compare with the messages.
struct Direct : monitor::PipelineSink {
  std::vector<monitor::RevolutionRecord> records;
  void on_revolution(const monitor::RevolutionRecord& r) override { records.push_back(r); }
};

/// The monitor's configuration for a simulated cut: its model and rate.
monitor::MonitorConfig monitor_config(const sim::Scenario& s) {
  monitor::MonitorConfig c;
  c.model = s.model;
  c.sample_rate_hz = s.sample_rate_hz;
  return c;
}

/// Simulates the cut `s` in blocks of `block` samples through a pipeline configured by `c` that
/// publishes into `out`, drained after each block (faster than real time: the publisher keeps
/// up, as it does at the machine's rate). False when a drain timed out; `status`: the pipeline's.
bool monitor_cut(LcmOutput& out, const sim::Scenario& s, const monitor::MonitorConfig& c,
                 std::size_t block, monitor::PipelineStatus& status) {
  sim::CutSimulator sim(s);
  monitor::Pipeline p(c, out);
  std::vector<double> t(block), fx(block), fy(block), fz(block);
  while (const std::size_t n = sim.next_block(t, fx, fy, fz)) {
    p.process({std::llround(t[0] * 1e6),
               0,
               s.sample_rate_hz,
               {fx.data(), n},
               {fy.data(), n},
               {fz.data(), n}});
    if (!out.drain()) {
      return false;
    }
  }
  status = p.status();
  return true;
}

TEST(LcmOutput, PublishesEveryOutputAsDecodableMessagesOnMemq) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  Received rx;
  const ChannelNames ch;
  lcm.subscribe(ch.tooth_periods, &Received::on_periods, &rx)->setQueueCapacity(100000);
  lcm.subscribe(ch.flute_peaks, &Received::on_peaks, &rx)->setQueueCapacity(100000);
  lcm.subscribe(ch.residual, &Received::on_residual, &rx)->setQueueCapacity(100000);
  lcm.subscribe(ch.spindle, &Received::on_spindle, &rx)->setQueueCapacity(100000);
  lcm.subscribe(ch.status, &Received::on_status, &rx)->setQueueCapacity(100000);
  lcm.subscribe(ch.alert, &Received::on_alert, &rx)->setQueueCapacity(100000);
  lcm.subscribe(ch.sync_average, &Received::on_sync, &rx)->setQueueCapacity(100000);

  sim::Scenario s;
  s.sample_rate_hz = 50000.0;
  s.duration_s = 0.6;
  s.spindle.actual_rpm = 25252.0;
  Direct direct;
  monitor::PipelineStatus status;
  {
    LcmOutput out(lcm, ch, &direct);
    ASSERT_TRUE(monitor_cut(out, s, monitor_config(s), 1000, status));
    out.publish_status(status);
    ASSERT_TRUE(out.drain());
    EXPECT_EQ(out.dropped(), 0);
  }
  while (lcm.handleTimeout(10) > 0) {
  }
  ASSERT_FALSE(direct.records.empty());
  ASSERT_EQ(rx.periods.size(), direct.records.size());
  const auto bounded = std::count_if(direct.records.begin(), direct.records.end(),
                                     [](const auto& r) { return r.measured.bounded; });
  ASSERT_EQ(static_cast<std::ptrdiff_t>(rx.peaks.size()), bounded);
  ASSERT_EQ(rx.peaks.size(), direct.records.size());  // a steady cut: every revolution bounded
  for (std::size_t i = 0; i < direct.records.size(); ++i) {
    const auto& r = direct.records[i];
    EXPECT_EQ(rx.periods[i].revolution, r.revolution);
    EXPECT_EQ(rx.periods[i].utime, r.utime_us);
    EXPECT_EQ(rx.periods[i].num_flutes, 2);
    EXPECT_EQ(rx.periods[i].flute_period_s.size(), 2u);
    EXPECT_DOUBLE_EQ(rx.periods[i].alpha_deg, r.measured.alpha_deg);
    EXPECT_DOUBLE_EQ(rx.peaks[i].delta_fy_N, r.measured.delta_fy_N);
    EXPECT_DOUBLE_EQ(rx.peaks[i].peak_fy_N[1], r.measured.peak_N[1][1]);
    EXPECT_DOUBLE_EQ(rx.periods[i].spindle_rpm, r.spindle_rpm);
    EXPECT_EQ(rx.periods[i].valid, r.measured.valid);
    EXPECT_EQ(rx.periods[i].event_kind, tooth_periods2_t::EVENT_VALLEY);
    EXPECT_EQ(rx.peaks[i].range_fx_N.size(), 2u);
    // No message carries a NaN: absent model values are 0 with the flag down.
    EXPECT_TRUE(std::isfinite(rx.periods[i].model_alpha_deg));
    if (!rx.periods[i].model_valid) {
      EXPECT_EQ(rx.periods[i].model_alpha_deg, 0.0);
    }
    for (const double v : rx.peaks[i].model_peak_resultant_N) {
      EXPECT_TRUE(std::isfinite(v));
    }
  }
  for (const auto& u : rx.spindle) {
    EXPECT_TRUE(std::isfinite(u.spindle_rpm_measured));
    EXPECT_TRUE(std::isfinite(u.spindle_rpm_uncertainty));
    if (!u.valid) {
      EXPECT_EQ(u.spindle_rpm_measured, 0.0);
    } else {
      EXPECT_TRUE(u.consistent || u.speed_agreement <= 0.01);
      EXPECT_NEAR(u.spindle_rpm_measured, 25252.0, 0.002 * 25252.0);
    }
  }
  EXPECT_FALSE(rx.residuals.empty());
  EXPECT_FALSE(rx.spindle.empty());
  ASSERT_FALSE(rx.status.empty());
  EXPECT_EQ(rx.status.back().samples_processed, 30000);
  EXPECT_EQ(rx.status.back().state, "measuring");
  EXPECT_EQ(rx.status.back().alert_held_revolutions, status.alert_held_revolutions);
  EXPECT_EQ(rx.status.back().identifications_taken, status.identifications_taken);
  EXPECT_FALSE(rx.alerts.empty());  // [000]'s runout is strong: a runout alert
  EXPECT_EQ(rx.alerts[0].kind, tool_alert_t::KIND_RUNOUT);
}

// The synchronous average goes out on every bin the configuration allows (up to 4,096), the
// model on the same grid: with 2,048 bins it was cut to the first 1,024, labelled a revolution.
TEST(LcmOutput, TheSyncAverageCarriesEveryConfiguredBin) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  Received rx;
  const ChannelNames ch;
  lcm.subscribe(ch.sync_average, &Received::on_sync, &rx)->setQueueCapacity(100);
  sim::Scenario s;
  s.sample_rate_hz = 333300.0;
  s.duration_s = 0.3;
  s.spindle.actual_rpm = 25252.0;
  monitor::MonitorConfig c = monitor_config(s);
  c.sync_bins = 2048;
  {
    LcmOutput out(lcm, ch);
    monitor::PipelineStatus status;
    ASSERT_TRUE(monitor_cut(out, s, c, 3333, status));
  }
  while (lcm.handleTimeout(10) > 0) {
  }
  ASSERT_FALSE(rx.sync.empty());
  const sync_average2_t& a = rx.sync.back();
  ASSERT_EQ(a.num_bins, 2048);
  ASSERT_TRUE(a.model_valid);
  double measured = 0.0, difference = 0.0;
  for (std::size_t b = 0; b < 2048; ++b) {
    measured += a.fx_N[b] * a.fx_N[b];
    difference += (a.fx_N[b] - a.model_fx_N[b]) * (a.fx_N[b] - a.model_fx_N[b]);
  }
  EXPECT_LT(std::sqrt(difference), 0.1 * std::sqrt(measured));  // the same angles
}

TEST(LcmConvert, ForceBlockRoundTripKeepsEverySample) {
  const std::vector<double> fx = {1.0, 2.0, 3.0}, fy = {-1.0, 0.5, 0.25}, fz = {0.0, 0.1, 0.2};
  const monitor::SampleBlock b{123456, 7, 50000.0, fx, fy, fz};
  const force_block_t m = to_message(b);
  EXPECT_EQ(m.num_samples, 3);
  std::vector<uint8_t> buffer(static_cast<std::size_t>(m.getEncodedSize()));
  ASSERT_EQ(m.encode(buffer.data(), 0, static_cast<int>(buffer.size())),
            static_cast<int>(buffer.size()));
  force_block_t back;
  ASSERT_EQ(back.decode(buffer.data(), 0, static_cast<int>(buffer.size())),
            static_cast<int>(buffer.size()));
  const monitor::SampleBlock v = to_block(back);
  EXPECT_EQ(v.utime_us, 123456);
  EXPECT_EQ(v.seq, 7);
  EXPECT_EQ(std::vector<double>(v.fy_N.begin(), v.fy_N.end()), fy);
}

// Flute peaks are published where they were measured: a revolution whose CE1 events were not
// both found has no flute windows (its peaks would be zeros); one whose CE1 events bound it has
// them even when a flute between left no event (a broken flute: valid false, its low peak kept).
TEST(LcmOutput, FlutePeaksOnlyForRevolutionsWhoseFluteWindowsAreKnown) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  Received rx;
  const ChannelNames ch;
  lcm.subscribe(ch.tooth_periods, &Received::on_periods, &rx)->setQueueCapacity(100);
  lcm.subscribe(ch.flute_peaks, &Received::on_peaks, &rx)->setQueueCapacity(100);
  {
    LcmOutput out(lcm, ch);
    monitor::RevolutionRecord r;
    r.measured.flutes = 2;
    r.spindle_rpm = 25000.0;
    r.revolution = 0;  // not bounded: nothing measured
    out.on_revolution(r);
    r.revolution = 1;  // bounded, flute 2 left no event
    r.measured.bounded = true;
    r.measured.peak_resultant_N = {1.2, 0.05};
    out.on_revolution(r);
    r.revolution = 2;  // every event found
    r.measured.valid = true;
    r.measured.peak_resultant_N = {1.2, 1.1};
    out.on_revolution(r);
    ASSERT_TRUE(out.drain());
  }
  while (lcm.handleTimeout(10) > 0) {
  }
  ASSERT_EQ(rx.periods.size(), 3u);  // every revolution
  EXPECT_FALSE(rx.periods[0].valid);
  ASSERT_EQ(rx.peaks.size(), 2u);
  EXPECT_EQ(rx.peaks[0].revolution, 1);
  EXPECT_FALSE(rx.peaks[0].valid);
  EXPECT_DOUBLE_EQ(rx.peaks[0].peak_resultant_N[1], 0.05);
  EXPECT_EQ(rx.peaks[1].revolution, 2);
  EXPECT_TRUE(rx.peaks[1].valid);
}

}  // namespace
}  // namespace millwatch::messaging
