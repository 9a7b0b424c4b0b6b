#include "core/sim/cut_simulator.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <vector>

#include "core/config/json_reader.hpp"
#include "core/model/steady_state.hpp"
#include "tests/support/test_paths.hpp"

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

/// The force on the tool (x, y) of the analytic two-flute slot: circular path with runout radii
/// r_j = √(R² + ρ² + 2Rρ·cos(γ + ψ_j)) ([001] eq 1 form), rigid tool, one disc, chip against the
/// envelope of the previous two passes h_j = min_m (m·f_t·sin θ + r_j − r_{j−m}), the power law of
/// [000] eq 5 (cutting coefficients only) plus flank-wear rubbing K_w·VB per engaged flute, and
/// [000] eq 7.
std::array<double, 2> analytic_slot_force_N(const model::ModelConfig& c, double phi_rad,
                                            double rho_um, double gamma_rad, double ft_um,
                                            double wear_um) {
  const double radius_um = 500.0 * c.tool.diameter_mm;
  const double ap = c.process.axial_depth_mm;
  const auto& pl = c.material.power_law;
  const auto& w = c.effects.flank_wear;
  std::array<double, 2> r{};
  for (int j = 0; j < 2; ++j) {
    r[static_cast<std::size_t>(j)] =
        std::sqrt(radius_um * radius_um + rho_um * rho_um +
                  2.0 * radius_um * rho_um * std::cos(gamma_rad + j * kPi));
  }
  std::array<double, 2> f{};
  for (int j = 0; j < 2; ++j) {
    const double theta = std::fmod(phi_rad - j * kPi + 4.0 * kPi, 2.0 * kPi);
    if (theta > kPi) {
      continue;
    }
    const double other = r[static_cast<std::size_t>(1 - j)];
    const double self = r[static_cast<std::size_t>(j)];
    const double h_um =
        std::min(ft_um * std::sin(theta) + self - other, 2.0 * ft_um * std::sin(theta));
    if (h_um <= 1e-9) {  // what is left at θ = π is the rounding of sin π
      continue;
    }
    const double h_mm = 1e-3 * h_um;
    const double ft =
        pl.k_tc_Nmm * std::pow(h_mm, pl.a_tc) * ap + w.k_wt_N_per_mm2 * 1e-3 * wear_um * ap;
    const double fn =
        pl.k_nc_Nmm * std::pow(h_mm, pl.a_nc) * ap + w.k_wn_N_per_mm2 * 1e-3 * wear_um * ap;
    f[0] += -ft * std::cos(theta) - fn * std::sin(theta);
    f[1] += ft * std::sin(theta) - fn * std::cos(theta);
  }
  return f;
}

// The runout becomes ρ = 4 µm at γ = 0 after 0.1 s while the flank wear grows from 0 to 20 µm.
// Every clean sample is the analytic slot force of its revolution's conditions (the model with
// only runout and multi-pass on, so that the force has a closed form). In particular: before
// the change both flutes cut (f_t = 4 µm > 2ρ·cos γ = 3.03 µm), after it flute 1 never does
// (f_t < 2ρ = 8 µm, [000] Sect. 2.1) and flute 1's half-revolution is silent; and within
// each runout the peak grows with the wear's rubbing force.
TEST(CutSimulator, RunoutChangeAndWearShowInTruthAndForce) {
  Scenario s = quiet_scenario();
  s.duration_s = 0.2;
  s.model = model::without_effects(s.model);
  s.model.effects.runout.enabled = true;  // 1.82 µm at 0.58 rad
  s.model.effects.multi_pass.enabled = true;
  s.runout_change.enabled = true;
  s.runout_change.time_s = 0.1;
  s.runout_change.offset_um = 4.0;
  s.runout_change.angle_rad = 0.0;
  s.wear.enabled = true;
  s.wear.start_um = {0.0};
  s.wear.end_um = {20.0};
  CutSimulator sim(s);
  const double rpm = s.model.process.spindle_rpm;  // 120 samples a revolution, on the 720 grid

  std::vector<double> t(1), fx(1), fy(1), fz(1);
  // Per revolution: peak resultant in flute 0's and flute 1's own half (outside the other's).
  std::vector<std::array<double, 2>> peaks;
  int compared = 0;
  while (sim.next_block(t, fx, fy, fz) == 1) {
    const double revs = t[0] * rpm / 60.0;
    const auto rev = static_cast<std::size_t>(std::floor(revs + 1e-9));
    const RevolutionTruth& truth = sim.truth()[rev];
    const double phi = 2.0 * kPi * (revs - std::floor(revs + 1e-9));
    const auto expected =
        analytic_slot_force_N(s.model, phi, truth.runout_offset_um, truth.runout_angle_rad,
                              truth.feed_per_tooth_um, truth.wear_um[0]);
    const auto& clean = sim.last_clean_force_N();
    ASSERT_NEAR(clean[0], expected[0], 1e-9) << "t " << t[0];
    ASSERT_NEAR(clean[1], expected[1], 1e-9) << "t " << t[0];
    ++compared;
    if (peaks.size() <= rev) {
      peaks.resize(rev + 1, {0.0, 0.0});
    }
    const double resultant = std::hypot(clean[0], clean[1]);
    auto& p = peaks[rev][phi < kPi ? 0 : 1];
    p = std::max(p, resultant);
  }
  EXPECT_EQ(compared, 10000);

  bool seen_before = false, seen_after = false;
  std::size_t first_after = 0;                          // the first revolution with the new runout
  for (std::size_t n = 0; n + 1 < peaks.size(); ++n) {  // the last one may be cut short
    const auto& truth = sim.truth()[n];
    EXPECT_NEAR(truth.wear_um[0], 20.0 * std::clamp(truth.start_s / 0.2, 0.0, 1.0), 0.6);
    if (truth.start_s < 0.099) {
      EXPECT_DOUBLE_EQ(truth.runout_offset_um, 1.82);
      seen_before = true;
    } else if (truth.start_s > 0.101) {
      EXPECT_DOUBLE_EQ(truth.runout_offset_um, 4.0);
      seen_after = true;
    }
    if (truth.runout_offset_um == 1.82) {
      EXPECT_GT(peaks[n][1], 0.3) << "revolution " << n << ": flute 1 cuts before the change";
      EXPECT_GT(peaks[n][0], peaks[n][1]) << n;  // flute 0 is the long one (cos 0.58 > 0)
    } else {
      EXPECT_EQ(peaks[n][1], 0.0) << "revolution " << n << ": flute 1 must be out of the cut";
      first_after = first_after == 0 ? n : first_after;
    }
  }
  ASSERT_TRUE(seen_before && seen_after);
  ASSERT_GT(first_after, 0u);
  // Wear: flute 0's peak grows from revolution to revolution within each runout.
  for (std::size_t n = 0; n + 2 < peaks.size(); ++n) {
    if (n + 1 != first_after) {
      EXPECT_GT(peaks[n + 1][0], peaks[n][0]) << "revolution " << n;
    }
  }
  // Flute 0's chip grows from f_t + 2ρ·cos γ = 7.0 µm to 2·f_t = 8 µm at the change; with
  // F ∝ h^0.32…h^0.53 (Table 2) its peak jumps by 4-7 %.
  EXPECT_GT(peaks[first_after][0], 1.03 * peaks[first_after - 1][0]);
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

// Coefficient drift: revolution n is the steady state with every force coefficient times the
// factor of its start, 1 + (t/T)·(end − 1). Without deflection the simulator scales the force of
// the undrifted model; with deflection (not linear in the coefficients: the tool bends by more
// under a larger force) it evaluates the drifted model. Both are compared with the evaluator run
// on independently scaled coefficients.
TEST(CutSimulator, CoefficientDriftScalesEveryCoefficientOverTheRecord) {
  for (const bool deflection : {false, true}) {
    SCOPED_TRACE(deflection ? "deflection on" : "deflection off");
    Scenario s = quiet_scenario();
    s.duration_s = 0.05;
    s.spindle.actual_rpm = 24000.0;  // 125 samples per revolution at 50 kHz, 20 revolutions
    s.model.effects.accumulation.enabled = false;  // one-revolution steady states
    s.model.effects.min_chip.enabled = false;
    s.model.effects.deflection.enabled = deflection;
    s.coefficient_drift.enabled = true;
    s.coefficient_drift.end_factor = 1.5;
    CutSimulator sim(s);
    std::vector<double> t(1), fx(1), fy(1), fz(1);
    model::SteadyStateWorkspace ws;
    const int steps = s.model.resolution.steps_per_rev;
    long evaluated = -1;
    std::vector<double> ex, ey;
    int compared = 0;
    double largest_change = 0.0;
    while (sim.next_block(t, fx, fy, fz) == 1) {
      const double revs = t[0] * 24000.0 / 60.0;
      const auto n = static_cast<long>(std::floor(revs + 1e-9));
      if (n != 4 && n != 17) {
        continue;
      }
      if (n != evaluated) {
        const RevolutionTruth& truth = sim.truth()[static_cast<std::size_t>(n)];
        const double factor = 1.0 + 0.5 * std::clamp(truth.start_s / s.duration_s, 0.0, 1.0);
        EXPECT_NEAR(truth.coefficient_factor, factor, 0.5 * 0.0025 / s.duration_s + 1e-12);
        model::ModelConfig drifted = model::at_actual_speed(s.model, 24000.0);
        auto& k = drifted.material.power_law;
        for (double* c :
             {&k.k_tc_Nmm, &k.k_nc_Nmm, &k.k_tp_Nmm, &k.k_np_Nmm, &k.k_ac_Nmm, &k.k_ap_Nmm}) {
          *c *= truth.coefficient_factor;
        }
        const model::SteadyState& e = model::evaluate_steady_state(drifted, 24000.0, steps, ws);
        ASSERT_EQ(e.cycle_revolutions, 1);
        ex = e.mean.fx_N;
        ey = e.mean.fy_N;
        evaluated = n;
        largest_change = std::max(largest_change, truth.coefficient_factor - 1.0);
      }
      const double pos = (revs - std::floor(revs + 1e-9)) * steps;
      const auto k0 = std::min(static_cast<std::size_t>(pos), static_cast<std::size_t>(steps - 1));
      const std::size_t k1 = (k0 + 1) % static_cast<std::size_t>(steps);
      const double w = pos - static_cast<double>(k0);
      ASSERT_NEAR(sim.last_clean_force_N()[0], ex[k0] + w * (ex[k1] - ex[k0]), 1e-9) << n;
      ASSERT_NEAR(sim.last_clean_force_N()[1], ey[k0] + w * (ey[k1] - ey[k0]), 1e-9) << n;
      ++compared;
    }
    EXPECT_GT(compared, 200);
    EXPECT_GT(largest_change, 0.4);  // revolution 17 of 20: the factor near its end value
  }
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
  // Played as it is: the whole cycle, exactly.
  const PlayedSteadyStates& played = sim.played_steady_states();
  EXPECT_EQ(played.evaluations, 1);
  EXPECT_EQ(played.cycles_cut, 0);
  EXPECT_TRUE(std::none_of(sim.truth().begin(), sim.truth().end(),
                           [](const RevolutionTruth& t) { return t.round_again; }));
  EXPECT_EQ(played.longest_cycle_revolutions, state.cycle_revolutions);
  EXPECT_EQ(played.unsettled_slots, 0);
}

// The cp-Ti preset's cut ([000]'s slot: deflection, h_min's accumulation, 10 helix discs): its
// slots' periods have a least common multiple beyond kMaxCycleRevolutions, and the record plays
// the first 64 revolutions round again. The simulator says so (PlayedSteadyStates, which
// `millwatch simulate` writes into the truth and prints), and the record shows it: each sample
// is the one 64 revolutions before, where the next revolution's is not.
TEST(CutSimulator, SaysWhenTheModelsCycleIsPlayedRoundAgain) {
  std::ifstream preset(test::source_dir() / "config" / "presets" / "cpti_masrani2023.json");
  Scenario s = scenario_from_json(nlohmann::json::parse(preset));
  s.sample_rate_hz = 20000.0;
  s.duration_s = 0.25;
  s.spindle.actual_rpm = 25000.0;  // 48 samples a revolution
  s.noise.enabled = false;
  s.quantisation.enabled = false;
  s.hum.enabled = false;
  s.drift.enabled = false;
  CutSimulator sim(s);
  const Record r = run(sim);
  const PlayedSteadyStates& played = sim.played_steady_states();
  EXPECT_EQ(played.evaluations, 1);
  EXPECT_EQ(played.cycles_cut, 1);
  // Revolutions 64 … 104 (and the one prepared ahead) of 0.25 s at 25,000 rpm, each marked.
  long round_again = 0;
  for (std::size_t n = 0; n < sim.truth().size(); ++n) {
    EXPECT_EQ(sim.truth()[n].round_again, n >= model::kMaxCycleRevolutions) << n;
    round_again += sim.truth()[n].round_again ? 1 : 0;
  }
  EXPECT_GE(round_again, 40);
  EXPECT_EQ(played.longest_cycle_revolutions, model::kMaxCycleRevolutions);
  EXPECT_EQ(played.unsettled_slots, 0);
  const std::size_t revolution = 48;
  const std::size_t round = revolution * static_cast<std::size_t>(model::kMaxCycleRevolutions);
  ASSERT_GT(r.fy.size(), round + 10 * revolution);
  double repeat = 0.0, neighbour = 0.0, peak = 0.0;
  for (std::size_t i = 0; i + round < r.fy.size(); ++i) {
    peak = std::max(peak, std::fabs(r.fy[i]));
    repeat = std::max(repeat, std::fabs(r.fy[i] - r.fy[i + round]));
    neighbour = std::max(neighbour, std::fabs(r.fy[i] - r.fy[i + revolution]));
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
  EXPECT_EQ(error_of({{"recording", {{"duration_s", 0.1}}},
                      {"runout_change", {{"enabled", true}, {"time_s", 0.2}}}}),
            "runout_change.time_s: value 0.2 s is after the recording's end "
            "(recording.duration_s 0.1 s): the change would not show");
  // Enabled without a time: the default (0.25 s) is after a 0.1 s recording's end too.
  EXPECT_NE(error_of({{"recording", {{"duration_s", 0.1}}}, {"runout_change", {{"enabled", true}}}})
                .find("runout_change.time_s"),
            std::string::npos);
  EXPECT_EQ(error_of(nlohmann::json::object()), "");
}

// Found by fuzz_scenario: a 0.1 s recording with the runout change disabled read well, but
// to_json() wrote the default change time (0.25 s) back, which the reader then refused against
// the duration. A disabled change's time is not checked against it.
TEST(Scenario, AShortRecordingWithoutARunoutChangeWritesBackWhatItReads) {
  const nlohmann::json j = {{"recording", {{"sample_rate_hz", 50000.0}, {"duration_s", 0.1}}}};
  const nlohmann::json written = to_json(scenario_from_json(j));
  EXPECT_EQ(written["runout_change"]["time_s"], 0.25);
  EXPECT_EQ(to_json(scenario_from_json(written)), written);
}

TEST(Scenario, JsonRoundTrip) {
  Scenario s;
  s.noise.enabled = true;
  s.spindle.profile = SpindleProfileKind::kRamp;
  s.spindle.ramp_start_s = 0.1;
  s.spindle.ramp_end_s = 0.2;
  s.spindle.ramp_end_rpm = 24000.0;
  s.axis_map.sign = {1.0, -1.0, 1.0};
  s.coefficient_drift.enabled = true;
  s.coefficient_drift.end_factor = 1.25;
  const auto j = to_json(s);
  EXPECT_EQ(to_json(scenario_from_json(j)), j);
}

}  // namespace
}  // namespace millwatch::sim
