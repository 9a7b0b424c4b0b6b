// The daemon's configuration names every channel it publishes on: two spindles' daemons on one
// network keep their results apart, the identified force coefficients included.

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

}  // namespace
}  // namespace millwatch::daemon
