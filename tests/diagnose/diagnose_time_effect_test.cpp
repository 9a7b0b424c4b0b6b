// The diagnosis on simulated cuts whose model changes over the record: flank wear growing
// linearly (tool_wear) and a runout that jumps half-way (runout_change, behind a runout the
// starting model knows). Each is named and added, the residual ends within 1.3× the noise floor,
// and what it says agrees with the simulator's truth within its uncertainty (or the resolution
// of its search). The simulated cuts differ from the fitted model in discretisation, noise and
// quantisation (tests/support/hidden_effect_cut.hpp).

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "core/diagnose/diagnosis.hpp"
#include "tests/support/hidden_effect_cut.hpp"

namespace millwatch::diagnose {
namespace {

void print(const Diagnosis& d) {
  for (const auto& s : d.steps) {
    std::printf("  + %-16s residual %.4f, %.4f N (floor %.4f, %.4f)\n", s.added.c_str(),
                s.residual_rms_N[0], s.residual_rms_N[1], d.noise_floor_N[0], d.noise_floor_N[1]);
    for (const auto& p : s.parameters) {
      std::printf("      %s = %.4g ± %.2g\n", p.name.c_str(), p.value, p.sigma);
    }
  }
  std::printf("  %s\n", d.verdict.c_str());
}

TEST(DiagnoseTimeEffects, GrowingWearIsNamedWithItsGrowth) {
  const auto cut = test::hidden_effect_cut({"tool_wear"});
  const Diagnosis d = diagnose(cut.record, cut.start);
  print(d);
  ASSERT_TRUE(d.ok) << d.message;
  ASSERT_EQ(d.named_effects.size(), 1U) << d.verdict;
  EXPECT_EQ(d.named_effects[0], "tool_wear");
  for (std::size_t a = 0; a < 2; ++a) {
    EXPECT_LE(d.steps[0].residual_rms_N[a], 1.3 * d.noise_floor_N[a]) << "axis " << a;
  }
  // Truth: VB from 1 to 9 µm over the simulated cut (the recording keeps nearly all of it).
  const Parameter* growth = test::find_parameter(d.steps[0].parameters, "wear_growth_um");
  const Parameter* mid = test::find_parameter(d.steps[0].parameters, "wear_mid_um");
  ASSERT_NE(growth, nullptr);
  ASSERT_NE(mid, nullptr);
  EXPECT_NEAR(growth->value, 8.0, 0.3);
  EXPECT_NEAR(mid->value, 5.0, 0.3);
  EXPECT_GT(growth->sigma, 0.0);
}

TEST(DiagnoseTimeEffects, RunoutChangeIsNamedWithItsTimeAndBothRunouts) {
  const auto cut = test::hidden_effect_cut({"runout_change"}, {"runout"});
  const Diagnosis d = diagnose(cut.record, cut.start);
  print(d);
  ASSERT_TRUE(d.ok) << d.message;
  ASSERT_EQ(d.named_effects.size(), 1U) << d.verdict;
  EXPECT_EQ(d.named_effects[0], "runout_change");
  for (std::size_t a = 0; a < 2; ++a) {
    EXPECT_LE(d.steps[0].residual_rms_N[a], 1.3 * d.noise_floor_N[a]) << "axis " << a;
  }
  // Truth: at 0.2 s (from the simulation's start; the recording starts a few samples later)
  // ρ 1.0 µm at 0.6 rad becomes 2.0 µm at 1.2 rad. The force pins each flute's cutting radius
  // (r_CE2 − r_CE1 = −2ρ·cos γ for two flutes), not ρ·sin γ (physics-notes).
  const Parameter* t = test::find_parameter(d.steps[0].parameters, "change_time_s");
  ASSERT_NE(t, nullptr);
  EXPECT_NEAR(t->value, 0.2, 2.0 * t->sigma + 0.005);
  const Parameter* before =
      test::find_parameter(d.steps[0].parameters, "r_ce2_minus_r_ce1_before_um");
  const Parameter* after =
      test::find_parameter(d.steps[0].parameters, "r_ce2_minus_r_ce1_after_um");
  ASSERT_NE(before, nullptr);
  ASSERT_NE(after, nullptr);
  EXPECT_NEAR(std::fabs(before->value), 2.0 * 1.0 * std::cos(0.6), 2.0 * before->sigma + 0.02);
  EXPECT_NEAR(std::fabs(after->value), 2.0 * 2.0 * std::cos(1.2), 2.0 * after->sigma + 0.02);
}

// A time-varying candidate refits the rest of the model with it, so it can gain by landing in a
// better basin of the other parameters while its own parameters show nothing: on the cp-Ti
// preset's cut, with the ploughing coefficients fitted under deflection but the damping on x
// still held at its bound from an early step, runout_change gained ΔBIC 302.7 with
// r_CE2 − r_CE1 −2.851 ± 0.118 µm before and −2.791 ± 0.105 µm after
// (tests/cli/diagnose_preset_test.cpp's cut), and tool_wear 34.6 with 0.065 ± 1.013 µm of wear
// growing 0.032 ± 0.077 µm. Neither shows its effect; the changes of the cuts above do.
TEST(DiagnoseTimeEffects, ACandidateWhoseParametersShowNothingIsNotShown) {
  const std::vector<Parameter> same_runout = {{"change_time_s", 0.1349, 0.0036},
                                              {"rho_before_um", 1.503, 0.520},
                                              {"r_ce2_minus_r_ce1_before_um", -2.851, 0.118},
                                              {"rho_after_um", 1.430, 0.525},
                                              {"r_ce2_minus_r_ce1_after_um", -2.791, 0.105}};
  const std::string why = not_shown_by_parameters("runout_change", same_runout);
  EXPECT_NE(why.find("agree within 2σ (r_ce2_minus_r_ce1 -2.851 ± 0.118 µm before"),
            std::string::npos)
      << why;
  // The runout_change cut's truth: −2·1.0·cos 0.6 = −1.651 µm, then −2·2.0·cos 1.2 = −1.449 µm.
  std::vector<Parameter> changed = same_runout;
  changed[2] = {"r_ce2_minus_r_ce1_before_um", -1.651, 0.02};
  changed[4] = {"r_ce2_minus_r_ce1_after_um", -1.449, 0.02};
  EXPECT_EQ(not_shown_by_parameters("runout_change", changed), "");
  // ρ alone may show it (ρ·sin γ changed, the radii did not).
  changed = same_runout;
  changed[1] = {"rho_before_um", 1.0, 0.1};
  changed[3] = {"rho_after_um", 2.0, 0.1};
  EXPECT_EQ(not_shown_by_parameters("runout_change", changed), "");

  const std::vector<Parameter> no_wear = {{"wear_mid_um", 0.065, 1.013},
                                          {"wear_growth_um", 0.032, 0.077}};
  EXPECT_NE(not_shown_by_parameters("tool_wear", no_wear).find("neither the wear nor its growth"),
            std::string::npos);
  // The wear cut's truth: VB 5 µm at mid-record, growing 8 µm.
  EXPECT_EQ(not_shown_by_parameters("tool_wear",
                                    {{"wear_mid_um", 5.0, 0.1}, {"wear_growth_um", 8.0, 0.1}}),
            "");
  // A constant wear shows itself without a growth.
  EXPECT_EQ(not_shown_by_parameters("tool_wear",
                                    {{"wear_mid_um", 5.0, 0.1}, {"wear_growth_um", 0.0, 0.1}}),
            "");
  // Candidates without the rule are shown.
  EXPECT_EQ(not_shown_by_parameters("helix_lag", {}), "");
}

// σ 0 is not an infinitely precise value: a parameter the record does not pin, or one that sits
// on a bound, would pass |v| > 2σ whatever its value. Only estimates can show an effect.
TEST(DiagnoseTimeEffects, ValuesThatAreNotEstimatesShowNothing) {
  // The runout after the change undetermined (a segment too short to pin it): left where the
  // fit put it, 1 µm from the value before, σ 0.
  Parameter undetermined{"r_ce2_minus_r_ce1_after_um", -1.851, 0.0};
  undetermined.determined = false;
  const std::vector<Parameter> runout = {{"change_time_s", 0.1349, 0.0036},
                                         {"r_ce2_minus_r_ce1_before_um", -2.851, 0.118},
                                         undetermined};
  const std::string why = not_shown_by_parameters("runout_change", runout);
  EXPECT_NE(why.find("is not estimated (r_ce2_minus_r_ce1 -2.851 ± 0.118 µm before, -1.851 µm "
                     "after, not pinned by the record)"),
            std::string::npos)
      << why;
  // ρ on a flute's contact edge is the least the force allows, not a measurement.
  std::vector<Parameter> contact = {{"rho_before_um", 1.0, 0.1}, {"rho_after_um", 3.0, 0.0}};
  contact[1].lower_bound = true;
  EXPECT_NE(not_shown_by_parameters("runout_change", contact).find("not a measurement"),
            std::string::npos);
  // The same values as estimates show the change.
  EXPECT_EQ(
      not_shown_by_parameters("runout_change", {{"r_ce2_minus_r_ce1_before_um", -2.851, 0.118},
                                                {"r_ce2_minus_r_ce1_after_um", -1.851, 0.118}}),
      "");

  // The wear on its physical bound and its growth unpinned: both σ 0, nothing shown.
  Parameter at_bound{"wear_mid_um", 0.0, 0.0, "lower"};
  Parameter growth{"wear_growth_um", 0.4, 0.0};
  growth.determined = false;
  const std::string wear = not_shown_by_parameters("tool_wear", {at_bound, growth});
  EXPECT_NE(wear.find("0.000 µm, at its physical bound; growing 0.400 µm, not pinned"),
            std::string::npos)
      << wear;
  // h_min at the least its profile tries is at most that, not a minimum chip thickness: the gain
  // is the ploughing coefficients on the few chips below it (a cut with the deflection and no
  // minimum chip thickness: chip_accumulation 0.2 µm ± 0.035, 0.05·f_t, then the profile's
  // least). Inside the range it shows itself (the cp-Ti preset's truth, 0.2 µm).
  Parameter least{"h_min_um", 0.08, 0.0};
  least.upper_bound = true;
  least.bound_note = "the least the profile tries (0.020·f_t)";
  const std::string chip = not_shown_by_parameters(
      "chip_accumulation", {least, {"k_tp_Nmm", 316.4, 46.9}, {"k_np_Nmm", 47.6, 2.7}});
  EXPECT_NE(chip.find("h_min is not estimated (0.080 µm, the least the profile tries"),
            std::string::npos)
      << chip;
  EXPECT_NE(not_shown_by_parameters("min_chip_thickness", {least}), "");
  EXPECT_EQ(not_shown_by_parameters("chip_accumulation", {{"h_min_um", 0.2, 0.035}}), "");
  // A σ that is not a number is not an estimate either.
  EXPECT_NE(not_shown_by_parameters(
                "tool_wear", {{"wear_mid_um", 5.0, std::nan("")}, {"wear_growth_um", 8.0, 0.0}}),
            "");
}

TEST(DiagnoseTimeEffects, ANegativePloughingCoefficientShowsNoPloughing) {
  // The AlSi10Mg preset's cut, ploughing_area scored from the plain model: ΔBIC 15,639 with
  // K_tp −3,821 ± 1,400 N/mm³, ploughing that would pull the edge along. Where it lands beside
  // the accumulation, both coefficients positive and near the truth's (4,000, 6,000), it shows.
  const Parameter h{"h_min_um", 3.2, 0.8};
  const std::string why = not_shown_by_parameters(
      "ploughing_area", {h, {"k_tp_N_per_mm3", -3821.0, 1400.0}, {"k_np_N_per_mm3", 1.0e4, 1300}});
  EXPECT_NE(why.find("a negative ploughing coefficient (k_tp_N_per_mm3 = -3821 ± 1.4e+03)"),
            std::string::npos)
      << why;
  EXPECT_NE(not_shown_by_parameters("min_chip_thickness", {h, {"k_np_Nmm", -40.0, 5.0}}), "");
  EXPECT_EQ(not_shown_by_parameters("ploughing_area", {{"h_min_um", 1.315, 0.026},
                                                       {"k_tp_N_per_mm3", 3519.0, 430.0},
                                                       {"k_np_N_per_mm3", 7212.0, 410.0}}),
            "");
  // Within 2σ of zero it may be either sign (a coefficient the record hardly pins); the axial
  // one's sign follows the helix.
  EXPECT_EQ(not_shown_by_parameters("chip_accumulation", {h, {"k_tp_Nmm", -50.0, 40.0}}), "");
  EXPECT_EQ(not_shown_by_parameters("ploughing_area", {h, {"k_ap_N_per_mm3", -500.0, 10.0}}), "");
}

}  // namespace
}  // namespace millwatch::diagnose
