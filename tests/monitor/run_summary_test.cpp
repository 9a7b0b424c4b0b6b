// The summary's verdict on an identified model uses the test the model in lockstep applies
// before it takes a fit (identification.max_unexplained, a fraction of the force's variance):
// a fit the model took is not called poor, one it refused is.

#include "core/monitor/run_summary.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "tests/support/recording.hpp"

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

/// Revolution n of a 2-flute cut at `rpm`, both CE1 events found (bounded), valid as told, α 180°.
RevolutionRecord revolution(int n, double rpm = 25000.0, bool valid = true) {
  RevolutionRecord r;
  r.revolution = n;
  r.spindle_rpm = rpm;
  r.measured.bounded = true;
  r.measured.valid = valid;
  r.measured.alpha_deg = 180.0;
  return r;
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

// Revolutions the alerts held for another speed are counted and said, with the tolerance and the
// new baseline's length; none held, nothing said.
TEST(RunSummary, SaysHowManyRevolutionsTheAlertsHeldForAnotherSpeed) {
  const auto summary_with = [](std::int64_t held) {
    MonitorConfig config;
    config.alerts.conditions_tolerance = 0.02;
    RunSummary summary(config);
    PipelineStatus status;
    status.alert_held_revolutions = held;
    summary.finish(status);
    return summary.to_json();
  };
  const nlohmann::json held = summary_with(312);
  EXPECT_EQ(held["counters"]["alert_held_revolutions"], 312);
  const std::string detail = test::warning_detail(held["warnings"], "alerts held");
  EXPECT_NE(detail.find("312 revolutions ran more than alerts.conditions_tolerance (2 %)"),
            std::string::npos)
      << held["warnings"].dump();
  EXPECT_NE(detail.find("once the speed holds for 500 revolutions"), std::string::npos) << detail;
  const nlohmann::json none = summary_with(0);  // kept: a range over a temporary's member dangles
  for (const auto& w : none["warnings"]) {
    EXPECT_NE(w["kind"], "alerts held");
  }
}

// Where successive windows' runout scatters beyond one window's σ (the shell widens the σ to it,
// identify::WindowScatter), the summary says so with the scatter; where ρ drifts while the radii
// hold (the σ widened to the drift), it says that, with the drifts; where neither, nothing.
TEST(RunSummary, SaysWhenTheWindowsRunoutScattersOrDriftsBeyondItsSigma) {
  const auto warnings_with = [](bool widened, bool drift) {
    MonitorConfig config;
    RunSummary summary(config);
    summary.set_identification({{"runout", {{"rho_um", 5.98}, {"rho_std_um", 1.278}}},
                                {"fit",
                                 {{"unexplained_fraction", 0.05},
                                  {"window_scatter",
                                   {{"windows", 16},
                                    {"rho_std_um", 1.278},
                                    {"gamma_std_deg", 29.7},
                                    {"widened", widened},
                                    {"rho_drift_um", 2.219},
                                    {"gamma_drift_deg", -101.9},
                                    {"radius_drift_um", 0.030},
                                    {"widened_by_drift", drift}}}}}});
    return summary.to_json()["warnings"];
  };
  const std::string scatter = test::warning_detail(warnings_with(true, false), "runout scatters");
  EXPECT_NE(scatter.find("ρ by 1.278 µm, γ by 29.7° from window to window over 16 windows"),
            std::string::npos)
      << scatter;
  EXPECT_EQ(test::warning_detail(warnings_with(true, false), "runout drifts"), "");
  const std::string drift = test::warning_detail(warnings_with(false, true), "runout drifts");
  EXPECT_NE(drift.find("ρ moved by +2.219 µm (γ by -101.9°) from the oldest quarter of the last "
                       "16 windows to the newest, while the radius differences moved by 0.030 µm "
                       "at most"),
            std::string::npos)
      << drift;
  EXPECT_EQ(test::warning_detail(warnings_with(false, true), "runout scatters"), "");
  EXPECT_TRUE(warnings_with(false, false).empty());
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

// "spindle speed outside the search" says where the line is and what speeds it means, against
// the commanded speed and the search: a 583.3 Hz line with a line at its spindle frequency
// (2 flutes, 25,000 rpm commanded) is 17,500 rpm read as tooth passing, first, or 35,000 rpm;
// without one, the reading nearer the commanded speed comes first. Its windows are no samples.
TEST(RunSummary, ASpeedOutsideTheSearchNamesTheSpeedsItsLineMeans) {
  MonitorConfig config;
  config.model.tool.flutes = 2;
  config.model.process.spindle_rpm = 25000.0;
  config.spindle.search_fraction = 0.15;
  for (const bool spindle_line : {true, false}) {
    RunSummary summary(config);
    PipelineEvent e;
    e.kind = PipelineEventKind::kSpeedOutOfRange;
    e.count = 4;
    e.value = 583.3333;
    e.detail = spindle_line ? kLineWithSpindleLine : "a strongest line outside the search";
    summary.add(e);
    const nlohmann::json w = summary.to_json()["warnings"];
    ASSERT_GE(w.size(), 1u) << w.dump();
    EXPECT_EQ(w[0]["kind"], "spindle speed outside the search");
    EXPECT_EQ(w[0]["samples"], 0);
    const std::string d = w[0]["detail"];
    EXPECT_EQ(d.rfind("the strongest spectral line, 583 Hz, lies outside the spindle tracker's "
                      "search (25000 rpm commanded, ± 15 %), so no speed is stated: the spindle "
                      "ran at ",
                      0),
              0u)
        << d;
    const std::size_t tooth = d.find("17500 rpm (-30 %) if it is the tooth-passing frequency");
    const std::size_t spindle = d.find("35000 rpm (+40 %) if it is the spindle frequency");
    ASSERT_NE(tooth, std::string::npos) << d;
    ASSERT_NE(spindle, std::string::npos) << d;
    // ln(35,000/25,000) = 0.34 against ln(25,000/17,500) = 0.36: nearer, without the line.
    EXPECT_EQ(tooth < spindle, spindle_line) << d;
    EXPECT_NE(d.find("set process.spindle_rpm"), std::string::npos) << d;
  }
}

/// A summary of `count` valid revolutions of a `flutes`-flute tool whose flutes share the turn.
nlohmann::json valid_revolutions(int flutes, int count) {
  MonitorConfig config;
  config.model.tool.flutes = flutes;
  RunSummary summary(config);
  for (int n = 0; n < count; ++n) {
    RevolutionRecord r;
    r.revolution = n;
    r.spindle_rpm = 25000.0;
    r.measured.flutes = flutes;
    r.measured.bounded = true;
    r.measured.valid = true;
    r.measured.alpha_deg = 360.0 / flutes + (n % 2 == 0 ? 0.5 : -0.5);
    r.measured.delta_fy_N = flutes > 1 ? 0.1 : 0.0;
    for (int j = 0; j < flutes; ++j) {
      r.measured.flute_period_s[static_cast<std::size_t>(j)] = 60.0 / 25000.0 / flutes;
    }
    summary.add(r);
  }
  return summary.to_json();
}

// α and ΔFy compare two cutting edges: for a one-flute tool they are 360° and 0 by definition
// and tell nothing; the summary gives none, with the reason (a warning, as every null has), and
// no "short window" for them.
TEST(RunSummary, AOneFluteToolHasNoAlphaOrDeltaFyAndSaysWhy) {
  const nlohmann::json one = valid_revolutions(1, 5);
  EXPECT_TRUE(one["alpha_deg"]["mean"].is_null()) << one["alpha_deg"];
  EXPECT_TRUE(one["alpha_deg"]["std"].is_null()) << one["alpha_deg"];
  EXPECT_TRUE(one["delta_fy_N"].is_null());
  EXPECT_TRUE(one["model"]["alpha_deg"].is_null());
  EXPECT_NEAR(one["tooth_period_s"][0].get<double>(), 60.0 / 25000.0, 1e-12);  // still measured
  int no_alpha = 0;
  for (const auto& w : one["warnings"]) {  // every null with its reason
    EXPECT_NE(w["kind"], "short window") << w.dump();
    if (w["kind"] == "no alpha") {
      ++no_alpha;
      EXPECT_EQ(w["detail"], "one flute: α and ΔFy compare two cutting edges");
    }
  }
  EXPECT_EQ(no_alpha, 1) << one["warnings"].dump();
  const nlohmann::json two = valid_revolutions(2, 5);
  EXPECT_NEAR(two["alpha_deg"]["mean"].get<double>(), 180.1, 1e-9);
  for (const auto& w : two["warnings"]) {
    EXPECT_NE(w["kind"], "no alpha") << w.dump();
  }
  EXPECT_NEAR(two["delta_fy_N"].get<double>(), 0.1, 1e-12);
}

// A model in lockstep whose tooth events are never found (a preset with a negative coefficient
// on a real cut) leaves its α and ΔFy null: the summary says why, as for every null, and says
// nothing when they are there.
TEST(RunSummary, SaysWhyTheModelsAlphaIsAbsent) {
  const auto summary_with = [](bool model_events) {
    MonitorConfig config;
    config.lockstep = true;
    RunSummary summary(config);
    for (int i = 0; i < 20; ++i) {
      RevolutionRecord r = revolution(i);
      r.model_valid = true;  // aligned: residuals computed
      r.model.valid = model_events;
      r.model.alpha_deg = 179.0;
      summary.add(r);
    }
    summary.finish(PipelineStatus{});
    return summary.to_json();
  };
  const nlohmann::json without = summary_with(false);
  EXPECT_TRUE(without["model"]["alpha_deg"].is_null());
  EXPECT_EQ(test::warning_detail(without["warnings"], "no model alpha")
                .rfind("the lockstep model's tooth events were found on none of the 20 "
                       "revolutions measured: its α and ΔFy are absent",
                       0),
            0u)
      << without["warnings"].dump();
  const nlohmann::json with = summary_with(true);
  EXPECT_NEAR(with["model"]["alpha_deg"].get<double>(), 179.0, 1e-12);
  EXPECT_EQ(test::warning_detail(with["warnings"], "no model alpha"), "");
}

// Revolutions that lost a tooth event count in peaks but not in α: the summary warns once more
// than a tenth of them did (a 6-flute cut after a speed ramp lost one in five with no warning,
// the threshold being half), and not for a few.
TEST(RunSummary, WarnsWhenMoreThanATenthOfTheRevolutionsLostAnEvent) {
  const auto warnings_with = [](int lost) {
    MonitorConfig config;
    RunSummary summary(config);
    for (int i = 0; i < 100; ++i) {
      summary.add(revolution(i, 25000.0, i >= lost));
    }
    summary.finish(PipelineStatus{});
    return summary.to_json()["warnings"];
  };
  EXPECT_EQ(test::warning_detail(warnings_with(10), "flute events missing"), "");
  const std::string twenty = test::warning_detail(warnings_with(20), "flute events missing");
  EXPECT_EQ(twenty.rfind("20 of 100 revolutions had a flute without its tooth event", 0), 0u)
      << twenty;
}

// The summary's speed is the mean of the revolutions' measured speeds: a revolution that coasted
// (its closing CE1 missed) states none (0) and does not pull the mean towards 0.
TEST(RunSummary, SpeedIsTheMeanOfTheMeasuredSpeedsAlone) {
  MonitorConfig config;
  RunSummary summary(config);
  for (int i = 0; i < 10; ++i) {
    RevolutionRecord r =
        revolution(i, i < 3 ? 0.0 : 25000.0 + 10.0 * (i % 2 == 0 ? 1.0 : -1.0), i >= 3);
    r.measured.bounded = i >= 3;
    summary.add(r);
  }
  summary.finish(PipelineStatus{});
  const nlohmann::json j = summary.to_json();
  EXPECT_NEAR(j["spindle_rpm"].get<double>(), 25000.0 - 10.0 / 7.0, 1e-9);
  EXPECT_LT(j["spindle_rpm_std"].get<double>(), 11.0);
  EXPECT_EQ(j["spindle_rpm_source"], "revolutions");
}

// More revolutions measured than the spindle turned between the first and the last, at the
// tracker's speed, is said: the tooth events followed something else (PHM cut 315 with its Fy
// dead once stated 20 of ~16 with no word). The turns heard while cutting are no measure: on a
// weak cut the events measure on through windows the tracker does not call cutting.
TEST(RunSummary, SaysWhenMoreRevolutionsWereMeasuredThanTurned) {
  const auto warned = [](int measured) {
    MonitorConfig config;
    RunSummary summary(config);
    SpindleUpdate u;
    u.estimate.valid = true;
    u.estimate.spindle_rpm = 6000.0;  // 100 turns a second
    summary.add(u);
    for (int i = 0; i < measured; ++i) {  // over 1 s: 101 turns from the first to the last
      RevolutionRecord r;
      r.revolution = i;
      r.utime_us = 1000000LL * i / (measured - 1);
      r.spindle_rpm = 6000.0 * measured / 101.0;  // what the events state: beside the point
      summary.add(r);
    }
    PipelineStatus status;
    status.cutting_revolutions = 60.0;  // a weak cut: the tracker heard cutting for 0.6 s
    summary.finish(status);
    const nlohmann::json j = summary.to_json();
    return !test::warning_detail(j["warnings"], "revolutions over-counted").empty();
  };
  EXPECT_FALSE(warned(101));
  EXPECT_TRUE(warned(120));
}

// ΔFy comes with its spread over the revolutions (as α and the speed do): real cut 315 states
// 3.951 N ± 1.450, which a bare 3.951 hid.
TEST(RunSummary, DeltaFyComesWithItsSpread) {
  MonitorConfig config;
  RunSummary summary(config);
  for (int i = 0; i < 3; ++i) {
    RevolutionRecord r = revolution(i);
    r.measured.delta_fy_N = 1.0 + i;
    summary.add(r);
  }
  summary.finish(PipelineStatus{});
  const nlohmann::json j = summary.to_json();
  EXPECT_DOUBLE_EQ(j["delta_fy_N"].get<double>(), 2.0);
  EXPECT_DOUBLE_EQ(j["delta_fy_N_std"].get<double>(), 1.0);
}

// Each flute's tooth period and peaks come with their spread from revolution to revolution too
// (the sample standard deviation, as α's and ΔFy's; null for a single revolution).
TEST(RunSummary, FlutePeriodsAndPeaksComeWithTheirSpread) {
  MonitorConfig config;
  RunSummary summary(config);
  for (int i = 0; i < 3; ++i) {
    RevolutionRecord r = revolution(i);
    r.measured.flute_period_s = {1.0e-3 + 2e-6 * i, 1.4e-3 - 2e-6 * i};
    r.measured.peak_N[0] = {-1.0 - 0.1 * i, 2.0, 0.5};
    r.measured.peak_N[1] = {-0.5, 1.0 + 0.2 * i, 0.25};
    r.measured.peak_resultant_N = {3.0 + 0.3 * i, 1.5};
    summary.add(r);
  }
  summary.finish(PipelineStatus{});
  const nlohmann::json j = summary.to_json();
  EXPECT_NEAR(j["tooth_period_s"][0].get<double>(), 1.002e-3, 1e-15);
  EXPECT_NEAR(j["tooth_period_s_std"][0].get<double>(), 2e-6, 1e-12);
  EXPECT_NEAR(j["tooth_period_s_std"][1].get<double>(), 2e-6, 1e-12);
  EXPECT_NEAR(j["peak_force_N_std"]["fx"][0].get<double>(), 0.1, 1e-12);
  EXPECT_DOUBLE_EQ(j["peak_force_N_std"]["fx"][1].get<double>(), 0.0);
  EXPECT_NEAR(j["peak_force_N_std"]["fy"][1].get<double>(), 0.2, 1e-12);
  EXPECT_NEAR(j["peak_force_N_std"]["resultant"][0].get<double>(), 0.3, 1e-12);
  EXPECT_NEAR(j["peak_force_N"]["resultant"][0].get<double>(), 3.3, 1e-12);

  RunSummary one(config);
  one.add(revolution(0));
  one.finish(PipelineStatus{});
  EXPECT_TRUE(one.to_json()["tooth_period_s_std"][0].is_null());
}

// Flute 0 is CE1, the flute with the largest force at the lock. Over a record where another
// flute holds clearly more (here 1.6 against 0.9 N: the lock's revolutions were unlike the
// cut), the summary says that α and ΔFy come from another edge; flutes within the 10 % margin
// (1.0 against 0.95 N: they may trade places as the tool wears) or a flute that leads only in a
// few revolutions are no reason.
TEST(RunSummary, SaysWhenAnotherFluteThanCE1HoldsTheLargerForce) {
  const auto warnings = [](double ce1_N, double other_N, int revolutions) {
    MonitorConfig config;
    RunSummary summary(config);
    for (int n = 0; n < revolutions; ++n) {
      RevolutionRecord r = revolution(n);
      r.measured.peak_resultant_N[0] = ce1_N;
      r.measured.peak_resultant_N[1] = other_N;
      summary.add(r);
    }
    return summary.to_json()["warnings"];
  };
  const std::string swapped = test::warning_detail(warnings(0.9, 1.6, 40), "flute labelling");
  EXPECT_NE(swapped.find("flute 2's period holds a larger force than flute 1's"), std::string::npos)
      << swapped;
  EXPECT_NE(swapped.find("1.6 N against 0.9 N"), std::string::npos) << swapped;
  EXPECT_NE(swapped.find("360° − α and −ΔFy"), std::string::npos) << swapped;
  EXPECT_EQ(test::warning_detail(warnings(0.95, 1.0, 40), "flute labelling"), "");
  EXPECT_EQ(test::warning_detail(warnings(1.6, 0.9, 40), "flute labelling"), "");
  EXPECT_EQ(test::warning_detail(warnings(0.9, 1.6, 5), "flute labelling"), "");
}

// A relabelling (kFlutesRelabelled) leaves out the revolutions of its lock, named from the
// other CE1, and keeps those of the locks before: a good lock (α 150°, 50 revolutions), one that
// locked on a knock (α 210°, 30), relabelled, and its relabelling's lock (α 150°, 40). The
// warning counts no samples, and says how many revolutions were left out.
TEST(RunSummary, ARelabellingLeavesOutItsLockAloneAndCountsNoSamples) {
  MonitorConfig config;
  RunSummary summary(config);
  int n = 0;
  const auto lock = [&](PipelineEventKind kind) {
    PipelineEvent e;
    e.kind = kind;
    e.utime_us = n;
    e.count = kind == PipelineEventKind::kFlutesRelabelled ? 2 : 0;
    e.value = kind == PipelineEventKind::kFlutesRelabelled ? 1.6 : 25000.0;
    e.detail = "test";
    summary.add(e);
  };
  const auto revolutions = [&](int count, double alpha_deg, double ce1_N, double other_N) {
    for (int i = 0; i < count; ++i, ++n) {
      RevolutionRecord r = revolution(n);
      r.measured.alpha_deg = alpha_deg;
      r.measured.peak_resultant_N[0] = ce1_N;
      r.measured.peak_resultant_N[1] = other_N;
      summary.add(r);
    }
  };
  lock(PipelineEventKind::kLockAcquired);
  revolutions(50, 150.0, 1.6, 0.9);
  lock(PipelineEventKind::kLockLost);
  lock(PipelineEventKind::kLockAcquired);
  revolutions(30, 210.0, 0.9, 1.6);
  lock(PipelineEventKind::kFlutesRelabelled);
  lock(PipelineEventKind::kLockAcquired);
  revolutions(40, 150.0, 1.6, 0.9);
  const nlohmann::json j = summary.to_json();
  EXPECT_DOUBLE_EQ(j["alpha_deg"]["mean"].get<double>(), 150.0) << j["alpha_deg"];
  EXPECT_EQ(j["alpha_deg"]["revolutions"], 90);
  EXPECT_EQ(j["revolutions"], 120);
  EXPECT_DOUBLE_EQ(j["peak_force_N"]["resultant"][0].get<double>(), 1.6);
  const std::string detail = test::warning_detail(j["warnings"], "flutes relabelled");
  EXPECT_NE(detail.find("flute 2 held 1.60 times"), std::string::npos) << detail;
  EXPECT_NE(detail.find("(30 valid revolutions in all so far)"), std::string::npos) << detail;
  EXPECT_EQ(test::warning_detail(j["warnings"], "flute labelling"), "");
  for (const auto& w : j["warnings"]) {
    if (w["kind"] == "flutes relabelled") {
      EXPECT_EQ(w["samples"], 0);
    }
  }
}

}  // namespace
}  // namespace millwatch::monitor
