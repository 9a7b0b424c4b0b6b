// Alerts from the identified estimates on simulated cuts with known truth, through the whole
// chain: the simulator (finer angle grid and more helix discs than the monitor's model, noise
// 0.015 N, 0.01 N quantisation, the dynamometer resonance, an actual speed 1 % below the
// commanded one), the monitoring pipeline, the window fit of every 30-revolution window
// (identify::WindowFitter, run synchronously), and an AlertEngine fed the revolutions and each
// window right after its last revolution (tests/support/identified_cut.hpp).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "core/model/flute_positions.hpp"
#include "core/model/model_config.hpp"
#include "core/monitor/alert_engine.hpp"
#include "tests/support/identified_cut.hpp"
#include "tests/support/realistic_cut.hpp"
#include "tests/support/recording.hpp"

namespace millwatch::monitor {
namespace {

/// A slot cut with the linear-edge law, runout and helix, measured through the whole chain.
sim::Scenario fine_cut(double duration_s, int flutes, double diameter_mm, double feed_um,
                       double rho_um, double gamma_rad) {
  return test::realistic_cut({.duration_s = duration_s,
                              .seed = 17,
                              .flutes = flutes,
                              .diameter_mm = diameter_mm,
                              .operation = model::Operation::kSlot,
                              .radial_depth_mm = diameter_mm,
                              .feed_um = feed_um,
                              .rho_um = rho_um,
                              .gamma_rad = gamma_rad});
}

/// What the monitor knows: the cut as commanded, coarser, runout unknown.
MonitorConfig monitor_of(const sim::Scenario& s) {
  MonitorConfig c = test::monitor_for(s);
  c.model.resolution.steps_per_rev = 720;
  c.model.effects.helix_lag.discs = 5;
  c.model.effects.runout.offset_um = 0.0;
  return c;
}

/// Runs the cut, prints what was raised, and returns it.
std::vector<Alert> alerts_of(const test::IdentifiedCut& cut, bool with_estimates = true) {
  AlertEngine engine;
  engine.expect_estimates(with_estimates);
  std::vector<Alert> alerts = test::replay_alerts(cut, engine, with_estimates);
  for (const Alert& a : alerts) {
    std::printf("  %s %s at revolution %lld: %s\n", a.active ? "raised" : "cleared",
                std::string(to_string(a.kind)).c_str(), static_cast<long long>(a.revolution),
                a.message.data());
  }
  return alerts;
}

int count(const std::vector<Alert>& alerts, AlertKind kind, AlertSeverity severity) {
  return static_cast<int>(std::count_if(alerts.begin(), alerts.end(), [&](const Alert& a) {
    return a.kind == kind && a.active && a.severity == severity;
  }));
}

const Alert* first(const std::vector<Alert>& alerts, AlertKind kind, AlertSeverity severity) {
  for (const Alert& a : alerts) {
    if (a.kind == kind && a.active && a.severity == severity) {
      return &a;
    }
  }
  return nullptr;
}

/// r_CE1 − r_CE2 of a two-flute tool with runout (ρ, γ): the truth, from the geometry.
double radius_difference_um(const sim::Scenario& s, double rho_um, double gamma_rad) {
  const auto pos =
      model::flute_positions(model::tool_radius_um(s.model),
                             model::flute_pitch_angles_rad(s.model.tool), rho_um, gamma_rad);
  return std::fabs(pos[0].radius_um - pos[1].radius_um);
}

/// The largest radius deficit per feed over the flute at pass n back, max (r_{j−n} − r_j)/n,
/// from the geometry, over the actual feed per tooth (the header's u).
double deficit_per_feed(const sim::Scenario& s) {
  const auto pos = model::flute_positions(
      model::tool_radius_um(s.model), model::flute_pitch_angles_rad(s.model.tool),
      s.model.effects.runout.offset_um, s.model.effects.runout.angle_rad);
  const int n_z = s.model.tool.flutes;
  double best = 0.0;
  for (int j = 0; j < n_z; ++j) {
    for (int n = 1; n < n_z; ++n) {
      const auto a = static_cast<std::size_t>((j - n + n_z) % n_z);
      best = std::max(best, (pos[a].radius_um - pos[static_cast<std::size_t>(j)].radius_um) / n);
    }
  }
  const double feed_um = s.model.process.feed_per_tooth_um * s.model.process.spindle_rpm /
                         sim::actual_rpm(s);  // the feed rate is fixed by the commanded speed
  return best / feed_um;
}

/// The monitor's revolution in which the simulator's runout changes: the last one that starts
/// at or before the first truth revolution with the new runout.
std::int64_t onset_revolution(const test::IdentifiedCut& cut, double offset_um) {
  double change_s = -1.0;
  for (const auto& t : cut.truth) {
    if (t.runout_offset_um == offset_um) {
      change_s = t.start_s;
      break;
    }
  }
  EXPECT_GT(change_s, 0.0);
  std::int64_t onset = -1;
  for (const auto& r : cut.revolutions) {
    if (static_cast<double>(r.utime_us) <= 1e6 * change_s + 1.0) {
      onset = r.revolution;
    }
  }
  return onset;
}

// Issue 7 §4: a runout step (ρ 0.5 → 2 µm at γ = 57°, 2-flute slot, f_t 3 µm: r_CE1 − r_CE2
// from 0.54 to 2.16 µm) is raised within 3 revolutions of its onset by the per-revolution flute
// shares, and the first window fitted wholly after it states the step in micrometres, before →
// after with σ, against the geometric truth. The runout is then high (2.16 µm is 71 % of the
// feed per tooth), not before.
TEST(AlertEstimates, RunoutStepIsRaisedWithinThreeRevolutionsAndStatedInMicrometres) {
  sim::Scenario s = fine_cut(2.2, 2, 0.4, 3.0, 0.5, 1.0);
  s.runout_change.enabled = true;
  s.runout_change.time_s = 1.7;  // after the flute-force baseline (500 revolutions)
  s.runout_change.offset_um = 2.0;
  s.runout_change.angle_rad = 1.0;
  const test::IdentifiedCut cut = test::identify_cut(s, monitor_of(s), identify::FitOptions{});
  const std::int64_t onset = onset_revolution(cut, 2.0);
  std::printf("%zu revolutions, %zu windows fitted in %.2f s; runout changes in revolution %lld\n",
              cut.revolutions.size(), cut.windows.size(), cut.fit_seconds,
              static_cast<long long>(onset));
  const std::vector<Alert> alerts = alerts_of(cut);

  ASSERT_EQ(count(alerts, AlertKind::kRunoutChange, AlertSeverity::kWarning), 1);
  const Alert& raised = *first(alerts, AlertKind::kRunoutChange, AlertSeverity::kWarning);
  EXPECT_GE(raised.revolution, onset);
  EXPECT_LE(raised.revolution, onset + 3);
  double before = NAN, after = NAN;
  ASSERT_EQ(std::sscanf(raised.message.data(), "runout change: flute imbalance %lf %% → %lf %%",
                        &before, &after),
            2)
      << raised.message.data();
  EXPECT_GT(after, before + 10.0);  // the long flute's share of the force grew
  EXPECT_NE(std::string(raised.message.data()).find("identified before: r_CE1 − r_CE2 0.5"),
            std::string::npos);

  // The follow-up: one info message after the raise, from a window wholly after the onset.
  ASSERT_EQ(count(alerts, AlertKind::kRunoutChange, AlertSeverity::kInfo), 1);
  const Alert& stated = *first(alerts, AlertKind::kRunoutChange, AlertSeverity::kInfo);
  EXPECT_GT(stated.revolution, raised.revolution);
  EXPECT_LE(stated.revolution, onset + 2 * 30 + 30);  // the second window after the onset
  const double truth_before = radius_difference_um(s, 0.5, 1.0);
  const double truth_after = radius_difference_um(s, 2.0, 1.0);
  std::printf("r_CE1 - r_CE2: %.3f -> %.3f um stated, truth %.3f -> %.3f um\n", stated.threshold,
              stated.value, truth_before, truth_after);
  EXPECT_NEAR(stated.threshold, truth_before, 0.1);  // issue 7 §2's accuracy of the radii
  EXPECT_NEAR(stated.value, truth_after, 0.1);
  double was = NAN, was_sigma = NAN, now = NAN, now_sigma = NAN;
  ASSERT_EQ(std::sscanf(stated.message.data(),
                        "runout change identified: r_CE1 − r_CE2 %lf ± %lf µm → %lf ± %lf µm", &was,
                        &was_sigma, &now, &now_sigma),
            4)
      << stated.message.data();
  EXPECT_NEAR(now, stated.value, 0.001);
  EXPECT_LT(std::fabs(now - truth_after), 3.0 * now_sigma + 0.01);  // honest σ

  const Alert* high = first(alerts, AlertKind::kRunout, AlertSeverity::kWarning);
  ASSERT_NE(high, nullptr);
  EXPECT_GT(high->revolution, onset);
  EXPECT_EQ(count(alerts, AlertKind::kRunout, AlertSeverity::kWarning), 1);
  EXPECT_EQ(count(alerts, AlertKind::kWearDrift, AlertSeverity::kWarning), 0);
  EXPECT_EQ(count(alerts, AlertKind::kBreakage, AlertSeverity::kAlarm), 0);

  // Without identification the same revolution raises it (the flute forces alone).
  const std::vector<Alert> forces = alerts_of(cut, false);
  const Alert* alone = first(forces, AlertKind::kRunoutChange, AlertSeverity::kWarning);
  ASSERT_NE(alone, nullptr);
  EXPECT_EQ(alone->revolution, raised.revolution);
}

// A step too small for single revolutions (ρ 0.5 → 0.7 µm: r_CE1 − r_CE2 0.54 → 0.76 µm, the
// long flute's share up by 3.5 % of the mean flute force, under the per-revolution 5 %) is still
// raised — by the block CUSUM of the shares or by the estimates' step test, whichever first — and
// stated in micrometres.
TEST(AlertEstimates, SmallRunoutStepIsRaisedAndStatedInMicrometres) {
  sim::Scenario s = fine_cut(2.2, 2, 0.4, 3.0, 0.5, 1.0);
  s.runout_change.enabled = true;
  s.runout_change.time_s = 1.5;
  s.runout_change.offset_um = 0.7;
  s.runout_change.angle_rad = 1.0;
  const test::IdentifiedCut cut = test::identify_cut(s, monitor_of(s), identify::FitOptions{});
  const std::int64_t onset = onset_revolution(cut, 0.7);
  std::printf("runout changes in revolution %lld\n", static_cast<long long>(onset));
  const std::vector<Alert> alerts = alerts_of(cut);
  ASSERT_EQ(count(alerts, AlertKind::kRunoutChange, AlertSeverity::kWarning), 1);
  const Alert& raised = *first(alerts, AlertKind::kRunoutChange, AlertSeverity::kWarning);
  EXPECT_GT(raised.revolution, onset);
  EXPECT_LT(raised.revolution, onset + 150);  // within 5 windows
  // Stated in µm: by the raise itself (estimates) or by the follow-up (flute forces).
  const Alert* stated = raised.quantity == "radius_difference_um"
                            ? &raised
                            : first(alerts, AlertKind::kRunoutChange, AlertSeverity::kInfo);
  ASSERT_NE(stated, nullptr);
  EXPECT_NEAR(stated->threshold, radius_difference_um(s, 0.5, 1.0), 0.1);
  EXPECT_NEAR(stated->value, radius_difference_um(s, 0.7, 1.0), 0.1);
  EXPECT_NE(std::string(stated->message.data()).find(" µm → "), std::string::npos);
  EXPECT_EQ(count(alerts, AlertKind::kRunout, AlertSeverity::kWarning), 0);  // 28 % of f_t
  EXPECT_EQ(count(alerts, AlertKind::kWearDrift, AlertSeverity::kWarning), 0);
  EXPECT_EQ(count(alerts, AlertKind::kBreakage, AlertSeverity::kAlarm), 0);
}

// Issue 7 §4: every force coefficient rising linearly by 20 % over the record (3 s, 1,236
// revolutions; the simulator's coefficient drift) raises wear drift before the end, once the
// identified coefficients' rise over their baseline (the first 10 windows) passes the 10 %
// limit — and not before the truth has risen that far. The flute-force detector (15 % rise of
// the mean flute force) has not raised by the end.
TEST(AlertEstimates, CoefficientDriftRaisesWearDriftBeforeTheEnd) {
  sim::Scenario s = fine_cut(3.0, 2, 0.4, 3.0, 0.5, 0.5);
  s.coefficient_drift.enabled = true;
  s.coefficient_drift.end_factor = 1.2;
  const test::IdentifiedCut cut = test::identify_cut(s, monitor_of(s), identify::FitOptions{});
  std::printf("%zu revolutions, %zu windows fitted in %.2f s\n", cut.revolutions.size(),
              cut.windows.size(), cut.fit_seconds);
  const std::vector<Alert> alerts = alerts_of(cut);
  ASSERT_EQ(count(alerts, AlertKind::kWearDrift, AlertSeverity::kWarning), 1);
  const Alert& wear = *first(alerts, AlertKind::kWearDrift, AlertSeverity::kWarning);
  EXPECT_LT(wear.revolution, cut.revolutions.back().revolution);
  EXPECT_GT(wear.value, AlertConfig{}.coefficient_increase);
  EXPECT_EQ(wear.threshold, AlertConfig{}.coefficient_increase);
  // The truth's rise at the alert over its value in the baseline's middle window (the
  // baseline is the median of the first 10 windows, revolutions 0–299).
  auto factor_at = [&](std::int64_t revolution) {
    const double t_s =
        1e-6 * static_cast<double>(cut.revolutions[static_cast<std::size_t>(revolution)].utime_us);
    return 1.0 + 0.2 * t_s / s.duration_s;
  };
  const double truth_rise = factor_at(wear.revolution) / factor_at(150) - 1.0;
  std::printf(
      "raised at revolution %lld of %lld: true rise over the baseline %.1f %%, stated "
      "%.1f %%\n",
      static_cast<long long>(wear.revolution),
      static_cast<long long>(cut.revolutions.back().revolution), 100.0 * truth_rise,
      100.0 * wear.value);
  EXPECT_GT(truth_rise, AlertConfig{}.coefficient_increase);
  char symbol[16];
  double before = NAN, after = NAN;
  ASSERT_EQ(
      std::sscanf(wear.message.data(), "wear drift: %15s %lf %*s → %lf", symbol, &before, &after),
      3)
      << wear.message.data();
  EXPECT_NEAR(after / before - 1.0, wear.value, 0.002);
  EXPECT_EQ(count(alerts, AlertKind::kRunoutChange, AlertSeverity::kWarning), 0);
  EXPECT_EQ(count(alerts, AlertKind::kRunout, AlertSeverity::kWarning), 0);
  EXPECT_EQ(count(alerts, AlertKind::kBreakage, AlertSeverity::kAlarm), 0);

  const std::vector<Alert> forces = alerts_of(cut, false);
  EXPECT_EQ(count(forces, AlertKind::kWearDrift, AlertSeverity::kWarning), 0);
}

// Runout high: raised where the radius deficit per feed approaches the feed per tooth (2 flutes:
// r_CE1 − r_CE2 = 2.87 µm at f_t 3.03 µm; 4 flutes: flute 2 is 2.5 µm inside flute 1, 83 %),
// with the statistic u within 0.05 of the geometric truth; not where it is well below (2
// flutes, ρ = 0.3 µm: 19 %).
TEST(AlertEstimates, RunoutHighNearTheFeedPerToothNotWellBelow) {
  struct Case {
    const char* name;
    int flutes;
    double diameter_mm, rho_um, gamma_rad;
  };
  for (const Case& k : {Case{"2 flutes, rho 1.5 um at 17 deg", 2, 0.4, 1.5, 0.3},
                        Case{"4 flutes, rho 2.0 um at 17 deg", 4, 1.0, 2.0, 0.3},
                        Case{"2 flutes, rho 0.3 um at 17 deg", 2, 0.4, 0.3, 0.3}}) {
    SCOPED_TRACE(k.name);
    const sim::Scenario s = fine_cut(0.4, k.flutes, k.diameter_mm, 3.0, k.rho_um, k.gamma_rad);
    const double truth = deficit_per_feed(s);
    std::printf("%s: u = %.3f (truth)\n", k.name, truth);
    const test::IdentifiedCut cut = test::identify_cut(s, monitor_of(s), identify::FitOptions{});
    ASSERT_GE(cut.windows.size(), 4u);
    const std::vector<Alert> alerts = alerts_of(cut);
    const int raised = count(alerts, AlertKind::kRunout, AlertSeverity::kWarning);
    if (truth < 0.5) {
      EXPECT_EQ(raised, 0);
      continue;
    }
    ASSERT_EQ(raised, 1);
    const Alert& a = *first(alerts, AlertKind::kRunout, AlertSeverity::kWarning);
    EXPECT_NEAR(a.value, truth, 0.05);
    EXPECT_EQ(a.threshold, AlertConfig{}.runout_feed_fraction);
    EXPECT_EQ(a.quantity, "radius_deficit_per_feed");
    // Raised on the second window (estimate_windows = 2).
    EXPECT_EQ(a.revolution, cut.windows[1].revolution);
    EXPECT_NE(std::string(a.message.data()).find("runout high: r_CE"), std::string::npos);
  }
}

}  // namespace
}  // namespace millwatch::monitor
