// The daemon's configuration names every channel it publishes on: two spindles' daemons on one
// network keep their results apart, the identified force coefficients included. A reload names
// and keeps what takes a restart; source.receive is read and checked.

#include "daemon/daemon_config.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

namespace millwatch::daemon {
namespace {

TEST(DaemonConfig, EveryPublishedChannelCanBeNamed) {
  const nlohmann::json j = {{"source", {{"kind", "lcm"}, {"channel", "S2_FORCE_RAW"}}},
                            {"lcm",
                             {{"channels",
                               {{"spindle", "S2_SPINDLE"},
                                {"tooth_periods", "S2_TOOTH_PERIODS"},
                                {"flute_peaks", "S2_FLUTE_PEAKS"},
                                {"residual", "S2_RESIDUAL"},
                                {"sync_average", "S2_SYNC_AVERAGE"},
                                {"runout", "S2_RUNOUT"},
                                {"coefficients", "S2_COEFFICIENTS"},
                                {"alert", "S2_ALERT"},
                                {"status", "S2_STATUS"}}}}}};
  const DaemonConfig c = daemon_config_from_json(j);
  EXPECT_EQ(c.channels.raw, "S2_FORCE_RAW");
  EXPECT_EQ(c.channels.runout, "S2_RUNOUT");
  EXPECT_EQ(c.channels.coefficients, "S2_COEFFICIENTS");
  EXPECT_EQ(c.channels.status, "S2_STATUS");
  EXPECT_EQ(daemon_config_from_json({{"source", {{"kind", "lcm"}}}}).channels.coefficients,
            "MILLWATCH_COEFFICIENTS");
}

// A reload takes the monitor's settings; what a running daemon cannot change (its source, its
// LCM set-up, a Comedi board's scan rate) is named for the warning and kept at its running value.
TEST(DaemonConfig, AReloadKeepsWhatTakesARestartAndNamesIt) {
  DaemonConfig running;
  running.monitor.sample_rate_hz = 333300.0;
  DaemonConfig next = running;
  next.monitor.sample_rate_hz = 100000.0;
  next.monitor.model.process.spindle_rpm = 30000.0;
  // An LCM source: each block carries its rate, so the new one is the DAQ bridge's to send.
  EXPECT_EQ(fields_needing_restart(running, next), "");
  EXPECT_EQ(as_reload_of(running, next).monitor.sample_rate_hz, 100000.0);

  // A Comedi board keeps scanning at the rate it was started with.
  running.source.kind = SourceConfig::Kind::kComedi;
  next.source.kind = SourceConfig::Kind::kComedi;
  EXPECT_EQ(fields_needing_restart(running, next),
            "monitor.sample_rate_hz (the Comedi board's scan rate)");
  // Its channels saturate at their amplifiers' range (the running ones: a new range_N takes a
  // restart).
  running.monitor.saturation_N = {500.0, 500.0, 1000.0};
  next.monitor.saturation_N = {100.0, 100.0, 100.0};
  next.source.channels[0].range_N = running.source.channels[0].range_N + 100.0;
  EXPECT_EQ(fields_needing_restart(running, next),
            "monitor.sample_rate_hz (the Comedi board's scan rate), source.channels");
  const DaemonConfig comedi = as_reload_of(running, next);
  EXPECT_EQ(comedi.monitor.saturation_N, running.monitor.saturation_N);
  EXPECT_EQ(comedi.monitor.sample_rate_hz, 333300.0);
  EXPECT_EQ(comedi.monitor.model.process.spindle_rpm, 30000.0);  // the rest is taken

  // A file that switches an LCM source to a Comedi board: the LCM source runs on, with the
  // saturation its blocks were checked against.
  DaemonConfig lcm;
  DaemonConfig to_comedi = lcm;
  to_comedi.source.kind = SourceConfig::Kind::kComedi;
  to_comedi.monitor.saturation_N = {100.0, 100.0, 100.0};
  EXPECT_EQ(fields_needing_restart(lcm, to_comedi), "source.kind");
  EXPECT_EQ(as_reload_of(lcm, to_comedi).monitor.saturation_N, lcm.monitor.saturation_N);

  // The source and the LCM set-up.
  next = running;
  next.source.device = "/dev/comedi1";
  next.lcm_output_url = "udpm://239.255.76.67:7669?ttl=0";
  next.channels.alert = "S2_ALERT";
  EXPECT_EQ(fields_needing_restart(running, next), "source.device, lcm.output_url, lcm.channels");
  const DaemonConfig kept = as_reload_of(running, next);
  EXPECT_EQ(kept.source.device, running.source.device);
  EXPECT_EQ(kept.lcm_output_url, running.lcm_output_url);
  EXPECT_EQ(kept.channels.alert, running.channels.alert);
}

// How an LCM source reads a udpm group: batched by default, LCM's receive thread when asked; a
// value of neither is an error naming the field. The socket is opened once: a restart.
TEST(DaemonConfig, TheReceiveIsBatchedUnlessLcmsIsAskedFor) {
  EXPECT_EQ(daemon_config_from_json(nlohmann::json::object()).source.receive,
            SourceConfig::Receive::kBatched);
  EXPECT_EQ(daemon_config_from_json({{"source", {{"receive", "lcm"}}}}).source.receive,
            SourceConfig::Receive::kLcm);
  std::string error;
  try {
    daemon_config_from_json({{"source", {{"receive", "thread"}}}});
  } catch (const std::exception& e) {
    error = e.what();
  }
  EXPECT_NE(error.find("source.receive"), std::string::npos) << error;
  EXPECT_NE(error.find("thread"), std::string::npos) << error;
  DaemonConfig running;
  DaemonConfig next = running;
  next.source.receive = SourceConfig::Receive::kLcm;
  EXPECT_EQ(fields_needing_restart(running, next), "source.receive");
  EXPECT_EQ(as_reload_of(running, next).source.receive, SourceConfig::Receive::kBatched);
}

}  // namespace
}  // namespace millwatch::daemon
