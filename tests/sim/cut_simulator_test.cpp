#include "core/sim/cut_simulator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "core/config/json_reader.hpp"
#include "core/model/steady_state.hpp"

namespace millwatch::sim {
namespace {

constexpr double kPi = std::numbers::pi;

struct Record {
  std::vector<double> t, fx, fy, fz;
};

Record run(CutSimulator& s) {
  Record r;
  const auto n = static_cast<std::size_t>(s.total_samples());
  r.t.resize(n);
  r.fx.resize(n);
  r.fy.resize(n);
  r.fz.resize(n);
  std::size_t done = 0;
  while (done < n) {
    const std::size_t k =
        s.next_block(std::span(r.t).subspan(done, std::min<std::size_t>(1000, n - done)),
                     std::span(r.fx).subspan(done), std::span(r.fy).subspan(done),
                     std::span(r.fz).subspan(done));
    if (k == 0) {
      break;
    }
    done += k;
  }
  EXPECT_EQ(done, n);
  return r;
}

Scenario quiet_scenario() {
  Scenario s;
  s.sample_rate_hz = 50000.0;
  s.duration_s = 0.1;
  s.model.effects.dynamometer.enabled = false;
  return s;
}

// A dynamometer under the workpiece reads minus the force on the tool (default axis map).
TEST(CutSimulator, RecordsMinusTheForceOnTheToolWithoutMeasurementErrors) {
  Scenario s = quiet_scenario();
  CutSimulator sim(s);
  std::vector<double> t(1), fx(1), fy(1), fz(1);
  double peak = 0.0;
  for (int i = 0; i < 2000; ++i) {
    ASSERT_EQ(sim.next_block(t, fx, fy, fz), 1u);
    const auto& clean = sim.last_clean_force_N();
    EXPECT_DOUBLE_EQ(fx[0], -clean[0]);
    EXPECT_DOUBLE_EQ(fy[0], -clean[1]);
    EXPECT_DOUBLE_EQ(fz[0], -clean[2]);
    peak = std::max(peak, std::hypot(fx[0], fy[0]));
  }
  EXPECT_GT(peak, 0.5);
}

// The recording runs at the actual speed; the fixed feed rate makes the actual chip thinner when
// the spindle runs fast ([000]: 25,252 rpm measured at 25,000 commanded).
TEST(CutSimulator, RunsAtTheActualSpeedWithTheCommandedFeedRate) {
  Scenario s = quiet_scenario();
  s.spindle.actual_rpm = 25252.0;
  CutSimulator sim(s);
  run(sim);
  const auto& truth = sim.truth();
  ASSERT_GT(truth.size(), 30u);
  const double period = (truth[30].start_s - truth[10].start_s) / 20.0;
  EXPECT_NEAR(period, 60.0 / 25252.0, 1.0 / s.sample_rate_hz);
  EXPECT_NEAR(truth[5].feed_per_tooth_um, 4.0 * 25000.0 / 25252.0, 1e-12);
}

// Force is periodic with the actual revolution: one revolution later the clean force repeats.
// (The minimum-chip switch is off: with deflection, the jump of [000] eq 5's normal force at
// h_min makes chips near h_min wander from pass to pass, not revolution-periodic.)
TEST(CutSimulator, CleanForceRepeatsEveryActualRevolution) {
  Scenario s = quiet_scenario();
  s.spindle.actual_rpm = 24000.0;  // 2.5 ms per revolution = 125 samples at 50 kHz
  s.model.effects.accumulation.enabled = false;
  s.model.effects.min_chip.enabled = false;
  CutSimulator sim(s);
  const Record r = run(sim);
  double peak = 0.0, diff = 0.0;
  for (std::size_t i = 1000; i + 125 < r.fx.size(); ++i) {
    peak = std::max(peak, std::fabs(r.fx[i]));
    diff = std::max(diff, std::fabs(r.fx[i] - r.fx[i + 125]));
  }
  EXPECT_LT(diff, 1e-6 * peak);
}

TEST(CutSimulator, NoiseHasTheConfiguredSpreadAndQuantisationItsStep) {
  Scenario s = quiet_scenario();
  s.spindle.profile = SpindleProfileKind::kStopStart;  // a feed hold: nothing but the chain
  s.spindle.stop_s = 0.0;
  s.spindle.stop_ramp_s = 0.01;
  s.spindle.stop_hold_s = 1.0;
  s.noise.enabled = true;
  s.noise.sigma_N = {0.02, 0.05, 0.01};
  s.quantisation.enabled = true;
  s.quantisation.bits = 12;
  s.quantisation.range_N = {10.0, 10.0, 10.0};
  CutSimulator sim(s);
  const Record r = run(sim);
  const double step = 20.0 / 4096.0;
  double sum2x = 0.0, sum2y = 0.0;
  for (std::size_t i = 0; i < r.fx.size(); ++i) {
    EXPECT_NEAR(std::remainder(r.fx[i], step), 0.0, 1e-9);
    sum2x += r.fx[i] * r.fx[i];
    sum2y += r.fy[i] * r.fy[i];
  }
  const double n = static_cast<double>(r.fx.size());
  // σ² of rounding noise adds step²/12.
  EXPECT_NEAR(std::sqrt(sum2x / n), std::sqrt(0.02 * 0.02 + step * step / 12), 0.03 * 0.02);
  EXPECT_NEAR(std::sqrt(sum2y / n), std::sqrt(0.05 * 0.05 + step * step / 12), 0.03 * 0.05);
}

TEST(CutSimulator, SaturatesAtTheAdcRange) {
  Scenario s = quiet_scenario();
  s.quantisation.enabled = true;
  s.quantisation.range_N = {0.5, 0.5, 0.5};
  CutSimulator sim(s);
  const Record r = run(sim);
  double lo = 1e9, hi = -1e9;
  for (double v : r.fx) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  EXPECT_DOUBLE_EQ(lo, -0.5);
  EXPECT_LT(hi, 0.5);
  EXPECT_GT(hi, 0.49);
}

// Mains hum is a line of the configured amplitude at the configured frequency; drift a ramp.
TEST(CutSimulator, HumAndDriftHaveTheirConfiguredSize) {
  Scenario s = quiet_scenario();
  s.duration_s = 0.5;
  s.spindle.profile = SpindleProfileKind::kStopStart;
  s.spindle.stop_s = 0.0;
  s.spindle.stop_ramp_s = 0.01;
  s.spindle.stop_hold_s = 10.0;
  s.hum.enabled = true;
  s.hum.frequency_hz = 60.0;
  s.hum.amplitude_N = {0.1, 0.0, 0.0};
  s.drift.enabled = true;
  s.drift.rate_N_per_s = {0.0, 0.4, 0.0};
  CutSimulator sim(s);
  const Record r = run(sim);
  double c = 0.0, q = 0.0;
  for (std::size_t i = 0; i < r.fx.size(); ++i) {
    c += r.fx[i] * std::cos(2 * kPi * 60.0 * r.t[i]);
    q += r.fx[i] * std::sin(2 * kPi * 60.0 * r.t[i]);
  }
  const double n = static_cast<double>(r.fx.size());
  EXPECT_NEAR(2.0 * std::hypot(c, q) / n, 0.1, 1e-3);
  EXPECT_NEAR(r.fy.back(), 0.4 * r.t.back(), 1e-9);
}

TEST(CutSimulator, StopStartHoldsTheCutAndResumes) {
  Scenario s = quiet_scenario();
  s.duration_s = 0.3;
  s.spindle.profile = SpindleProfileKind::kStopStart;
  s.spindle.stop_s = 0.1;
  s.spindle.stop_ramp_s = 0.02;
  s.spindle.stop_hold_s = 0.05;
  CutSimulator sim(s);
  const Record r = run(sim);
  double during = 0.0, before = 0.0, after = 0.0;
  for (std::size_t i = 0; i < r.t.size(); ++i) {
    const double f = std::hypot(r.fx[i], r.fy[i]);
    if (r.t[i] >= 0.1 && r.t[i] < 0.19) {
      during = std::max(during, f);
    } else if (r.t[i] < 0.1) {
      before = std::max(before, f);
    } else if (r.t[i] > 0.2) {
      after = std::max(after, f);
    }
  }
  EXPECT_EQ(during, 0.0);
  EXPECT_GT(before, 0.5);
  EXPECT_NEAR(after, before, 0.05 * before);
}

TEST(CutSimulator, RampChangesTheRevolutionPeriod) {
  Scenario s = quiet_scenario();
  s.duration_s = 0.4;
  s.spindle.profile = SpindleProfileKind::kRamp;
  s.spindle.ramp_start_s = 0.1;
  s.spindle.ramp_end_s = 0.3;
  s.spindle.ramp_end_rpm = 20000.0;
  CutSimulator sim(s);
  run(sim);
  const auto& truth = sim.truth();
  const auto& last = truth[truth.size() - 3];
  EXPECT_NEAR(last.spindle_rpm, 20000.0, 1e-6);
  EXPECT_NEAR(truth[truth.size() - 3].start_s - truth[truth.size() - 4].start_s, 60.0 / 20000.0,
              1.0 / s.sample_rate_hz);
  EXPECT_NEAR(last.feed_per_tooth_um, 4.0 * 25000.0 / 20000.0, 1e-9);
}

TEST(CutSimulator, RunoutChangeAndWearShowInTruthAndForce) {
  Scenario s = quiet_scenario();
  s.duration_s = 0.2;
  s.runout_change.enabled = true;
  s.runout_change.time_s = 0.1;
  s.runout_change.offset_um = 4.0;
  s.runout_change.angle_rad = 0.0;
  s.wear.enabled = true;
  s.wear.start_um = {0.0};
  s.wear.end_um = {20.0};
  CutSimulator sim(s);
  const Record r = run(sim);
  const auto& truth = sim.truth();
  bool seen_before = false, seen_after = false;
  for (const auto& t : truth) {
    if (t.start_s < 0.099) {
      EXPECT_DOUBLE_EQ(t.runout_offset_um, 1.82);
      seen_before = true;
    } else if (t.start_s > 0.101 && t.start_s < 0.2) {
      EXPECT_DOUBLE_EQ(t.runout_offset_um, 4.0);
      seen_after = true;
    }
    EXPECT_NEAR(t.wear_um[0], 20.0 * std::clamp(t.start_s / 0.2, 0.0, 1.0), 0.6);
  }
  EXPECT_TRUE(seen_before && seen_after);
}

// Each revolution is the model's steady state at that revolution's conditions: after a runout
// change the clean force is the evaluator's revolution for the new runout at the actual speed
// with the commanded feed rate, interpolated at each sample's spindle angle.
TEST(CutSimulator, EachRevolutionIsTheSteadyStateOfItsConditions) {
  Scenario s = quiet_scenario();
  s.duration_s = 0.05;
  s.spindle.actual_rpm = 24000.0;  // 125 samples per revolution at 50 kHz
  s.runout_change.enabled = true;
  s.runout_change.time_s = 0.02;
  s.runout_change.offset_um = 3.0;
  s.runout_change.angle_rad = -0.4;
  s.model.effects.accumulation.enabled = false;  // a one-revolution steady state: no skipped
  s.model.effects.min_chip.enabled = false;      // passes, no deflection cycles at h_min
  model::ModelConfig after = model::at_actual_speed(s.model, 24000.0);
  after.effects.runout.offset_um = 3.0;
  after.effects.runout.angle_rad = -0.4;
  model::SteadyStateWorkspace ws;
  const int steps = after.resolution.steps_per_rev;
  const model::SteadyState& expected = model::evaluate_steady_state(after, 24000.0, steps, ws);
  ASSERT_EQ(expected.cycle_revolutions, 1);
  CutSimulator sim(s);
  std::vector<double> t(1), fx(1), fy(1), fz(1);
  int compared = 0;
  while (sim.next_block(t, fx, fy, fz) == 1) {
    if (t[0] < 0.0225) {  // the revolution in progress at the change keeps the old runout
      continue;
    }
    const double revs = t[0] * 24000.0 / 60.0;
    const double pos = (revs - std::floor(revs)) * steps;
    const auto k0 = static_cast<std::size_t>(pos);
    const std::size_t k1 = (k0 + 1) % static_cast<std::size_t>(steps);
    const double w = pos - static_cast<double>(k0);
    const auto& f = expected.mean;
    ASSERT_NEAR(sim.last_clean_force_N()[0], f.fx_N[k0] + w * (f.fx_N[k1] - f.fx_N[k0]), 1e-9);
    ASSERT_NEAR(sim.last_clean_force_N()[1], f.fy_N[k0] + w * (f.fy_N[k1] - f.fy_N[k0]), 1e-9);
    ++compared;
  }
  EXPECT_GT(compared, 1000);
}

// Accumulation that skips passes makes a force that repeats only every L revolutions; the
// record plays the cycle's revolutions in turn, so revolution n + L repeats revolution n while
// neighbouring revolutions differ.
TEST(CutSimulator, PlaysTheAccumulationCycleRevolutionByRevolution) {
  Scenario s = quiet_scenario();
  s.spindle.actual_rpm = 24000.0;  // 125 samples per revolution
  s.model = model::without_effects(s.model);
  for (const char* e : {"runout", "trochoidal", "multi_pass", "accumulation", "helix_lag"}) {
    model::set_effect(s.model, e, true);
  }
  s.model.effects.helix_lag.discs = 4;
  model::SteadyStateWorkspace ws;
  const model::SteadyState& state = model::evaluate_steady_state(
      model::at_actual_speed(s.model, 24000.0), 24000.0, s.model.resolution.steps_per_rev, ws);
  ASSERT_TRUE(state.cycle_exact);
  const auto cycle = static_cast<std::size_t>(state.cycle_revolutions);
  ASSERT_GT(cycle, 1u);
  CutSimulator sim(s);
  const Record r = run(sim);
  double repeat = 0.0, neighbour = 0.0, peak = 0.0;
  for (std::size_t i = 0; i + cycle * 125 < r.fy.size(); ++i) {
    peak = std::max(peak, std::fabs(r.fy[i]));
    repeat = std::max(repeat, std::fabs(r.fy[i] - r.fy[i + cycle * 125]));
    neighbour = std::max(neighbour, std::fabs(r.fy[i] - r.fy[i + 125]));
  }
  EXPECT_LT(repeat, 1e-9 * peak);
  EXPECT_GT(neighbour, 1e-3 * peak);
}

TEST(Scenario, BadFieldsAreNamedWithValueAndRange) {
  auto error_of = [](const nlohmann::json& j) {
    try {
      scenario_from_json(j);
    } catch (const config::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(error_of({{"model", {{"tool", {{"diameter_mm", -1.0}}}}}}),
            "model.tool.diameter_mm: value -1 is out of range (0, 50] mm");
  EXPECT_EQ(error_of({{"model", {{"tool", {{"flutes", 0}}}}}}),
            "model.tool.flutes: value 0 is out of range [1, 8]");
  EXPECT_EQ(error_of({{"recording", {{"sample_rate_hz", "fast"}}}}),
            "recording.sample_rate_hz: expected a number, got string \"fast\"");
  EXPECT_EQ(error_of({{"noize", {{"enabled", true}}}}).rfind("noize: unknown key", 0), 0u);
  EXPECT_EQ(error_of({{"noise", {{"sigma_N", {0.1, 0.1}}}}}),
            "noise.sigma_N: array has 2 elements; allowed 3 to 3");
  EXPECT_EQ(error_of({{"axis_map", {{"x", "-fy"}, {"y", "-fy"}}}}),
            "axis_map.y: channel \"fy\" is already mapped to another axis");
  EXPECT_NE(error_of({{"spindle", {{"profile", "ramp"}, {"ramp_end_s", 0.0}}}}).find("ramp_end_s"),
            std::string::npos);
  EXPECT_EQ(error_of(nlohmann::json::object()), "");
}

TEST(Scenario, JsonRoundTrip) {
  Scenario s;
  s.noise.enabled = true;
  s.spindle.profile = SpindleProfileKind::kRamp;
  s.spindle.ramp_start_s = 0.1;
  s.spindle.ramp_end_s = 0.2;
  s.spindle.ramp_end_rpm = 24000.0;
  s.axis_map.sign = {1.0, -1.0, 1.0};
  const auto j = to_json(s);
  EXPECT_EQ(to_json(scenario_from_json(j)), j);
}

}  // namespace
}  // namespace millwatch::sim
