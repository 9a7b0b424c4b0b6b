// The summary's verdict on an identified model uses the test the model in lockstep applies
// before it takes a fit (identification.max_unexplained, a fraction of the force's variance):
// a fit the model took is not called poor, one it refused is.

#include "core/monitor/run_summary.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

namespace millwatch::monitor {
namespace {

/// The warnings of a summary whose last fit left `rms_fraction` of the force's RMS unexplained.
nlohmann::json warnings_for(double rms_fraction) {
  MonitorConfig config;
  config.identification.max_unexplained = 0.2;
  RunSummary summary(config);
  summary.set_identification(
      {{"runout", {{"rho_um", 1.8}}}, {"fit", {{"unexplained_fraction", rms_fraction}}}});
  return summary.to_json()["warnings"];
}

bool warns_model_does_not_fit(const nlohmann::json& warnings) {
  for (const auto& w : warnings) {
    if (w["kind"] == "model does not fit") {
      return true;
    }
  }
  return false;
}

TEST(RunSummary, CallsAFitPoorOnlyWhereTheModelInLockstepRefusesIt) {
  // 30 % of the RMS is 9 % of the variance: taken (≤ 20 %), not poor.
  EXPECT_FALSE(warns_model_does_not_fit(warnings_for(0.30))) << warnings_for(0.30).dump();
  // 50 % of the RMS is 25 % of the variance: refused, and said.
  const nlohmann::json refused = warnings_for(0.50);
  ASSERT_TRUE(warns_model_does_not_fit(refused)) << refused.dump();
  for (const auto& w : refused) {
    if (w["kind"] == "model does not fit") {
      EXPECT_NE(w["detail"].get<std::string>().find("50 % of the measured force unexplained (RMS; "
                                                    "25 % of its variance"),
                std::string::npos)
          << w["detail"];
    }
  }
}

// A warning's samples are samples: "no steady tooth-passing signal" counts tracker windows,
// which go into its text instead.
TEST(RunSummary, AWarningCountsSamplesNotWindows) {
  MonitorConfig config;
  RunSummary summary(config);
  PipelineEvent e;
  e.kind = PipelineEventKind::kNoSteadySignal;
  e.count = 20;  // windows
  e.detail = "weak or irregular cutting";
  summary.add(e);
  const nlohmann::json w = summary.to_json()["warnings"];
  ASSERT_EQ(w.size(), 2u) << w.dump();  // and "no identification"
  EXPECT_EQ(w[0]["samples"], 0);
  EXPECT_EQ(w[0]["detail"], "20 tracker windows: weak or irregular cutting");
}

}  // namespace
}  // namespace millwatch::monitor
