// Batch calibration on simulated feed sweeps with known truth. Each cut differs from the fitted
// model as a real cut would (noise 0.015 N rms, 0.01 N quantisation, the dynamometer resonance,
// 0.125° and 20 helix discs against the fitter's 0.5° and 5, actual speed 1 % below the
// commanded) and is seen only through the monitor's synchronous-average windows.

#include "core/identify/calibration.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include "core/model/flute_positions.hpp"
#include "core/sim/cut_simulator.hpp"
#include "tests/support/monitored_cut.hpp"
#include "tests/support/realistic_cut.hpp"

namespace millwatch::identify {
namespace {

constexpr double kPi = std::numbers::pi;

double wrap_pi(double a) {
  return a - 2.0 * kPi * std::round(a / (2.0 * kPi));
}

struct Sweep {
  const char* name;
  int flutes;
  double diameter_mm;
  model::Operation operation;
  double radial_depth_mm;
  std::vector<double> feeds_um;
  double rho_um;
  double gamma_rad;
};

/// The true cut at one feed: linear-edge law ([002] eq 18, the model's default coefficients).
sim::Scenario scenario(const Sweep& k, double feed_um, std::uint64_t seed) {
  return test::realistic_cut({.duration_s = 0.4,
                              .seed = seed,
                              .flutes = k.flutes,
                              .diameter_mm = k.diameter_mm,
                              .operation = k.operation,
                              .radial_depth_mm = k.radial_depth_mm,
                              .feed_um = feed_um,
                              .rho_um = k.rho_um,
                              .gamma_rad = k.gamma_rad});
}

/// What the monitor knows of a cut: as commanded, coarser, runout unknown, coefficients off.
monitor::MonitorConfig commanded(const sim::Scenario& s) {
  monitor::MonitorConfig c;
  c.model = s.model;
  c.sample_rate_hz = s.sample_rate_hz;
  c.lockstep = false;
  c.model.resolution.steps_per_rev = 720;
  c.model.effects.helix_lag.discs = 5;
  c.model.effects.runout.offset_um = 0.0;
  c.model.material.linear_edge.k_tc_N_per_mm2 *= 0.7;
  c.model.material.linear_edge.k_ne_N_per_mm *= 1.4;
  return c;
}

/// The sweep's cuts as the monitor measured them, each described as commanded.
std::vector<CalibrationCut> sweep_cuts(const Sweep& k) {
  std::vector<CalibrationCut> cuts;
  std::uint64_t seed = 11;
  for (const double f : k.feeds_um) {
    const sim::Scenario s = scenario(k, f, seed++);
    const monitor::MonitorConfig c = commanded(s);
    test::MonitoredCut m = test::monitor_cut(s, c);
    cuts.push_back({"f_t " + std::to_string(f), c.model, m.filter, std::move(m.windows)});
  }
  return cuts;
}

CalibrationResult calibrate_sweep(const Sweep& k, bool tared) {
  CalibrationOptions o;
  o.tared = tared;
  return calibrate(sweep_cuts(k), o);
}

double truth_of(const std::string& name) {
  const model::LinearEdge le;
  if (name == "k_tc_N_per_mm2")
    return le.k_tc_N_per_mm2;
  if (name == "k_nc_N_per_mm2")
    return le.k_nc_N_per_mm2;
  if (name == "k_te_N_per_mm")
    return le.k_te_N_per_mm;
  if (name == "k_ne_N_per_mm")
    return le.k_ne_N_per_mm;
  return 0.0;
}

/// `classic_within`: the classic regression's coefficients within this fraction (0: not checked;
/// runout biases them).
void check_sweep(const Sweep& k, bool tared, double classic_within = 0.0) {
  const CalibrationResult r = calibrate_sweep(k, tared);
  ASSERT_TRUE(r.ok) << k.name << ": " << r.message;
  // A sweep the model describes gives coefficients fit for a material preset: no warning.
  EXPECT_TRUE(r.warnings.empty()) << (r.warnings.empty() ? "" : r.warnings.front());
  ASSERT_EQ(r.cuts.size(), k.feeds_um.size());
  const FitResult& f = r.joint.fit;
  std::printf(
      "%s%s: rho %.3f ± %.3f um (truth %.2f), gamma %.1f ± %.1f deg; %d iterations, "
      "%ld evaluations\n",
      k.name, tared ? " (tared)" : "", f.rho_um.value, f.rho_um.sigma, k.rho_um,
      f.gamma_rad.value * 180 / kPi, f.gamma_rad.sigma * 180 / kPi, f.iterations, f.evaluations);
  for (const auto& c : r.cuts) {
    EXPECT_GE(c.windows, 3) << c.name;
    EXPECT_LT(
        std::sqrt(std::pow(c.fit.residual_rms_N[0], 2) + std::pow(c.fit.residual_rms_N[1], 2)),
        0.02 * std::hypot(c.fit.measured_rms_N[0], c.fit.measured_rms_N[1]))
        << c.name;
  }
  // Coefficients: within 5 % and the truth within 2σ; the classic regression beside them.
  int checked = 0;
  for (const Estimate& e : f.coefficients) {
    const double truth = truth_of(e.name);
    if (truth == 0.0) {
      continue;
    }
    ++checked;
    double classic = std::nan(""), classic_sigma = std::nan("");
    for (const Estimate& c : r.classic.coefficients) {
      if (c.name == e.name) {
        classic = c.value;
        classic_sigma = c.sigma;
      }
    }
    std::printf("    %-15s %8.2f ± %5.2f (truth %7.2f)   classic %8.2f ± %5.2f\n", e.name.c_str(),
                e.value, e.sigma, truth, classic, classic_sigma);
    EXPECT_LT(std::fabs(e.value / truth - 1.0), 0.05) << k.name << " " << e.name;
    EXPECT_LE(std::fabs(e.value - truth), 2.0 * e.sigma) << k.name << " " << e.name;
    if (classic_within > 0.0) {
      EXPECT_TRUE(r.classic.ok) << r.classic.message;
      EXPECT_LT(std::fabs(classic / truth - 1.0), classic_within) << k.name << " " << e.name;
    }
  }
  EXPECT_EQ(checked, 4);
  // Each flute's cutting radius relative to CE1, modulo the labelling; ρ and γ within 2σ.
  model::Tool tool;
  tool.flutes = k.flutes;
  const auto pitch = model::flute_pitch_angles_rad(tool);
  const auto truth_pos =
      model::flute_positions(500.0 * k.diameter_mm, pitch, k.rho_um, k.gamma_rad);
  double radius_error = 1e300;
  int shift = 0;
  for (int sh = 0; sh < k.flutes; ++sh) {
    double worst = 0.0;
    for (int j = 0; j < k.flutes; ++j) {
      const double t = truth_pos[static_cast<std::size_t>((j + sh) % k.flutes)].radius_um -
                       truth_pos[static_cast<std::size_t>(sh)].radius_um;
      worst =
          std::max(worst, std::fabs(f.radius_from_ce1_um[static_cast<std::size_t>(j)].value - t));
    }
    if (worst < radius_error) {
      radius_error = worst;
      shift = sh;
    }
  }
  const double gamma_error = std::fabs(
      wrap_pi(f.gamma_rad.value - (k.gamma_rad + pitch[static_cast<std::size_t>(shift)])));
  std::printf("    radii error %.4f um; r_ce2 - r_ce1 %.3f ± %.3f um\n", radius_error,
              f.radius_from_ce1_um[1].value, f.radius_from_ce1_um[1].sigma);
  EXPECT_LT(radius_error, 0.1) << k.name;
  EXPECT_LE(std::fabs(f.rho_um.value - k.rho_um), 2.0 * f.rho_um.sigma) << k.name;
  EXPECT_LE(gamma_error, 2.0 * f.gamma_rad.sigma) << k.name;
}

Sweep four_flute_down() {
  return {"4-flute down 50 %, rho 1.5 at -100 deg",
          4,
          1.0,
          model::Operation::kDownMilling,
          0.5,
          {2.0, 3.0, 4.0, 5.0, 6.0},
          1.5,
          -1.75};
}

TEST(Calibration, TwoFluteSlotFeedSweep) {
  check_sweep({"2-flute slot, rho 1.2 at 29 deg",
               2,
               0.4,
               model::Operation::kSlot,
               0.4,
               {3.0, 4.0, 5.0, 6.0, 8.0},
               1.2,
               0.5},
              false);
}

TEST(Calibration, FourFluteDownMillingFeedSweepWithTaredChannels) {
  check_sweep(four_flute_down(), true);
}

TEST(Calibration, FourFluteDownMillingFeedSweep) {
  check_sweep(four_flute_down(), false);
}

// Without runout every flute cuts its share and the mean force follows the slot formulas: the
// classic regression, through the monitor, agrees with the truth too.
TEST(Calibration, ClassicRegressionAgreesWithoutRunout) {
  const Sweep k{"2-flute slot, no runout", 2,   0.4, model::Operation::kSlot, 0.4,
                {3.0, 4.0, 5.0, 6.0, 8.0}, 0.0, 0.0};
  check_sweep(k, false, 0.03);
}

// The classic regression against the slot formulas' own case: slot, linear-edge law, circular
// path, no runout, every flute cutting — the simulator's force, noise-free, averaged over whole
// revolutions. Its lines must give back the coefficients the simulator used.
std::array<double, 3> mean_force_on_tool(const sim::Scenario& s) {
  sim::CutSimulator simulator(s);
  const double rev_s = 60.0 / sim::actual_rpm(s);
  const auto n = static_cast<std::size_t>(std::llround(100 * rev_s * s.sample_rate_hz));
  std::vector<double> t(n), fx(n), fy(n), fz(n);
  simulator.next_block(t, fx, fy, fz);
  std::array<double, 3> mean{};
  for (std::size_t i = 0; i < n; ++i) {
    // The dynamometer reads minus the force on the tool (the default axis map).
    mean[0] -= fx[i] / static_cast<double>(n);
    mean[1] -= fy[i] / static_cast<double>(n);
    mean[2] -= fz[i] / static_cast<double>(n);
  }
  return mean;
}

void check_classic(model::Operation op, double radial_depth_mm, int flutes) {
  std::vector<MeanForceCut> cuts;
  model::LinearEdge truth;
  truth.k_tc_N_per_mm2 = 1300.0;
  truth.k_nc_N_per_mm2 = 520.0;
  truth.k_ac_N_per_mm2 = 210.0;
  truth.k_te_N_per_mm = 9.0;
  truth.k_ne_N_per_mm = 14.0;
  truth.k_ae_N_per_mm = 3.0;
  for (const double f : {2.0, 3.0, 4.5, 6.0, 8.0}) {
    sim::Scenario s;
    s.sample_rate_hz = 100000.0;
    s.model = model::without_effects(model::ModelConfig{});
    s.model.material.law = model::ForceLawKind::kLinearEdge;
    s.model.material.linear_edge = truth;
    s.model.tool.flutes = flutes;
    s.model.process.operation = op;
    s.model.process.radial_depth_mm = radial_depth_mm;
    s.model.process.feed_per_tooth_um = f;
    s.model.resolution.steps_per_rev = 3600;
    // Samples that do not repeat at the same angles every revolution: the mean of a force that
    // jumps at entry and exit is then not biased by where the samples fall.
    s.spindle.actual_rpm = 0.9987 * s.model.process.spindle_rpm;
    s.duration_s = 0.25;
    MeanForceCut c;
    c.model = s.model;
    c.chip_load_um = f * s.model.process.spindle_rpm / s.spindle.actual_rpm;
    c.mean_force_N = mean_force_on_tool(s);
    c.measured = {true, true, true};
    cuts.push_back(c);
  }
  const AverageForceRegression r = average_force_regression(cuts);
  ASSERT_TRUE(r.ok) << r.message;
  const std::map<std::string, double> expected = {
      {"k_tc_N_per_mm2", truth.k_tc_N_per_mm2}, {"k_nc_N_per_mm2", truth.k_nc_N_per_mm2},
      {"k_ac_N_per_mm2", truth.k_ac_N_per_mm2}, {"k_te_N_per_mm", truth.k_te_N_per_mm},
      {"k_ne_N_per_mm", truth.k_ne_N_per_mm},   {"k_ae_N_per_mm", truth.k_ae_N_per_mm}};
  ASSERT_EQ(r.coefficients.size(), 6U);
  for (const Estimate& e : r.coefficients) {
    std::printf("  %s %d flutes: %-15s %9.3f ± %6.3f (truth %7.2f)\n",
                op == model::Operation::kSlot ? "slot" : "down", flutes, e.name.c_str(), e.value,
                e.sigma, expected.at(e.name));
    EXPECT_NEAR(e.value, expected.at(e.name), 0.005 * expected.at(e.name)) << e.name;
  }
}

// What makes coefficients unfit for a material preset, on the figures of a real cut the model
// does not describe (PHM 2010 c1_cut158 at f_t 49.8 µm: 78.9 % of the force's RMS unexplained,
// k_nc −2350 ± 19 N/mm² as one of its minima stated it before the others were compared): each
// said once. A negative coefficient within 2σ of zero (k_tc 166 ±
// 2519) is no evidence of anything; an axial one may be negative; a good fit says nothing.
TEST(CalibrationWarnings, NameAFitThatDoesNotDescribeTheCutsAndANegativeCoefficient) {
  FitResult f;
  f.measured_rms_N = {11.0, 6.6, 0.0};
  f.residual_rms_N = {8.69, 5.24, 0.0};
  f.coefficients = {{"k_tc_N_per_mm2", 166.4, 2519.5},
                    {"k_nc_N_per_mm2", -2350.0, 18.9},
                    {"k_ac_N_per_mm2", -300.0, 10.0},
                    {"k_te_N_per_mm", 122.5, 43.9},
                    {"k_ne_N_per_mm", -5.0, 9.5}};
  const std::vector<std::string> w = calibration_warnings(f, 0.2);
  ASSERT_EQ(w.size(), 2u);
  EXPECT_NE(w[0].find("79.1 % of the measured force unexplained"), std::string::npos) << w[0];
  EXPECT_NE(w[0].find("63 % of its variance, above 20 %"), std::string::npos) << w[0];
  EXPECT_EQ(w[1].rfind("k_nc_N_per_mm2 = -2350 ± 19", 0), 0u) << w[1];
  // 63 % of the variance is within a 70 % allowance; the negative k_nc is still said.
  EXPECT_EQ(calibration_warnings(f, 0.7).size(), 1u);
  // Minima as good within the noise are said (their spread is in the σ's).
  f.competing_minima = 6;
  const std::vector<std::string> m = calibration_warnings(f, 0.7);
  ASSERT_EQ(m.size(), 2u);
  EXPECT_EQ(m[0].rfind("6 other minima of the fit as good within the noise", 0), 0u) << m[0];
  f.competing_minima = 1;
  EXPECT_EQ(calibration_warnings(f, 0.7)[0].rfind("1 other minimum of the fit", 0), 0u);
  f.competing_minima = 0;
  f.residual_rms_N = {0.11, 0.066, 0.0};  // 1 %
  f.coefficients = {{"k_tc_N_per_mm2", 2100.0, 15.0}, {"k_nc_N_per_mm2", 900.0, 12.0}};
  EXPECT_TRUE(calibration_warnings(f, 0.2).empty());
}

// A cut recorded with the dynamometer turned round (its x and y read the other way, its
// configuration not told): the joint fit follows the other cuts and misses this one by most of
// its force, while the whole sweep stays under identification.max_unexplained. calibrate had
// printed the cut's figure (up to "123 %") and said nothing; the calibration now names the cut,
// and only that one. With its amplifier's range three times too low as well, the turned cut pulls
// the fit its way (negative coefficients, said) and every cut is named, one missed by more than
// its whole force: that is said too.
TEST(Calibration, NamesACutTheOtherCutsDoNotDescribe) {
  const std::vector<CalibrationCut> cuts =
      sweep_cuts({"2-flute slot", 2, 0.4, model::Operation::kSlot, 0.4, {3.0, 4.0, 5.0}, 1.2, 0.5});
  bool whole_said = false;     // the whole fit's "the fit leaves …" warning
  bool negative_said = false;  // a coefficient below zero
  const auto named_cuts = [&](double gain) {
    std::vector<CalibrationCut> sweep = cuts;
    for (MeasuredRevolution& w : sweep[1].windows) {
      for (std::size_t a = 0; a < 2; ++a) {
        for (double& v : w.force_N[a]) {
          v *= -gain;
        }
      }
    }
    const CalibrationResult r = calibrate(sweep);
    EXPECT_TRUE(r.ok) << r.message;
    for (const CalibratedCut& c : r.cuts) {  // each cut's distance from the 20 % of variance
      std::printf("%s: %.1f %% of its variance unexplained\n", c.name.c_str(),
                  100.0 * unexplained_variance(c.fit.residual_rms_N, c.fit.measured_rms_N));
    }
    std::vector<std::string> named;
    whole_said = false;
    negative_said = false;
    for (const std::string& w : r.warnings) {
      std::printf("%s\n", w.c_str());
      if (w.rfind("cut ", 0) == 0) {
        named.push_back(w);
      }
      whole_said = whole_said || w.rfind("the fit leaves ", 0) == 0;
      negative_said = negative_said || w.find("below zero pulls") != std::string::npos;
    }
    return named;
  };
  const std::vector<std::string> turned = named_cuts(1.0);
  EXPECT_FALSE(whole_said);  // the whole sweep passes: only the cut says what is wrong
  ASSERT_EQ(turned.size(), 1u);
  EXPECT_EQ(turned[0].rfind("cut " + cuts[1].name + ": the joint fit leaves ", 0), 0u) << turned[0];
  EXPECT_NE(turned[0].find("% of its variance, above 20 %)"), std::string::npos) << turned[0];
  const std::vector<std::string> amplified = named_cuts(3.0);
  EXPECT_TRUE(whole_said);
  EXPECT_TRUE(negative_said);
  EXPECT_EQ(amplified.size(), 3u);
  EXPECT_TRUE(std::ranges::any_of(amplified, [](const std::string& w) {
    return w.find("; more than a model of no force at all would") != std::string::npos;
  }));
}

TEST(AverageForceRegression, SlotFormulasGiveBackTheSimulatorsCoefficients) {
  check_classic(model::Operation::kSlot, 0.4, 2);
  check_classic(model::Operation::kSlot, 0.4, 3);
}

TEST(AverageForceRegression, OtherImmersionsThroughTheirIntegrals) {
  check_classic(model::Operation::kDownMilling, 0.1, 2);
  check_classic(model::Operation::kUpMilling, 0.25, 4);
}

TEST(AverageForceRegression, SaysWhyItCannotFit) {
  MeanForceCut c;
  c.chip_load_um = 3.0;
  c.mean_force_N = {-1.0, 2.0, 0.0};
  EXPECT_FALSE(average_force_regression({c, c}).ok);
  const AverageForceRegression same = average_force_regression({c, c, c});
  EXPECT_FALSE(same.ok);
  EXPECT_NE(same.message.find("distinct feeds"), std::string::npos) << same.message;
  MeanForceCut d = c;
  d.chip_load_um = 4.0;
  d.model.process.operation = model::Operation::kDownMilling;
  d.model.process.radial_depth_mm = 0.1;
  const AverageForceRegression mixed = average_force_regression({c, d, c});
  EXPECT_FALSE(mixed.ok);
  EXPECT_NE(mixed.message.find("engagement"), std::string::npos) << mixed.message;
}

// Windows are laid onto the first before they are averaged: a window turned by a known angle
// (its tracker zero moved) comes back, and a window at another speed is left out.
TEST(Calibration, AveragesWindowsTurnedOntoTheFirst) {
  MeasuredRevolution a;
  const int bins = 256;
  for (auto& f : a.force_N) {
    f.resize(bins);
  }
  for (int b = 0; b < bins; ++b) {
    const double phi = 2.0 * kPi * b / bins;
    a.force_N[0][static_cast<std::size_t>(b)] = 0.3 + std::sin(2 * phi) + 0.4 * std::cos(phi - 1.0);
    a.force_N[1][static_cast<std::size_t>(b)] = -0.1 + 0.8 * std::cos(2 * phi + 0.3);
  }
  a.spindle_rpm = 25000.0;
  a.revolutions = 30;
  MeasuredRevolution turned = a;  // the same force seen from a tracker zero 0.2 rad later
  for (int b = 0; b < bins; ++b) {
    const double phi = 2.0 * kPi * b / bins - 0.2;
    turned.force_N[0][static_cast<std::size_t>(b)] =
        0.3 + std::sin(2 * phi) + 0.4 * std::cos(phi - 1.0);
    turned.force_N[1][static_cast<std::size_t>(b)] = -0.1 + 0.8 * std::cos(2 * phi + 0.3);
  }
  turned.revolutions = 10;
  MeasuredRevolution off = a;
  off.spindle_rpm = 24000.0;
  const WindowAverage w = average_windows({a, turned, off});
  EXPECT_EQ(w.windows_used, 2);
  EXPECT_EQ(w.windows_left_out, 1);
  EXPECT_EQ(w.revolution.revolutions, 40);
  EXPECT_NEAR(w.largest_turn_rad, 0.2, 1e-6);
  for (int b = 0; b < bins; ++b) {
    EXPECT_NEAR(w.revolution.force_N[0][static_cast<std::size_t>(b)],
                a.force_N[0][static_cast<std::size_t>(b)], 1e-7);
    EXPECT_NEAR(w.revolution.force_N[1][static_cast<std::size_t>(b)],
                a.force_N[1][static_cast<std::size_t>(b)], 1e-7);
  }
}

TEST(Calibration, RefusesCutsOfDifferentTools) {
  const Sweep k{"", 2, 0.4, model::Operation::kSlot, 0.4, {3.0}, 1.0, 0.0};
  FitCut a{"a.csv", commanded(scenario(k, 3.0, 1)).model, [](double) { return 1.0; }, {}};
  FitCut b = a;
  b.name = "b.csv";
  b.model.tool.diameter_mm = 0.5;
  try {
    (void)fit_cuts({a, b});
    FAIL() << "two tools accepted";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("b.csv"), std::string::npos) << what;
    EXPECT_NE(what.find("tool.diameter_mm"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace millwatch::identify
