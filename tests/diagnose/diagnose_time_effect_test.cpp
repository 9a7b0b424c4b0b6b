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

}  // namespace
}  // namespace millwatch::diagnose
