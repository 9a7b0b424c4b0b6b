// The monitoring run both shells share: status cadence on LCM (memq://), counts carried across
// a pipeline replaced by a reload, the source's losses in the status and the summary.

#include "shell/monitor_run.hpp"

#include <gtest/gtest.h>

#include <lcm/lcm-cpp.hpp>
#include <vector>

#include "millwatch/pipeline_status2_t.hpp"

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

struct StatusLog {
  std::vector<pipeline_status2_t> messages;
  void on_status(const lcm::ReceiveBuffer*, const std::string&, const pipeline_status2_t* m) {
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

}  // namespace
}  // namespace millwatch::shell
