// The diagnosis on simulated cuts in which one effect of the catalogue is hidden: the simulator
// has it on, the diagnosis starts from the plain model without it. The simulated cut differs
// from the fitted model in what a real cut would (tests/support/hidden_effect_cut.hpp: finer
// angle step, more helix discs, noise, quantisation), so a test could fail. The diagnosis must
// name the effect, add it, and bring the residual within 1.3× the noise floor.

#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "core/diagnose/diagnosis.hpp"
#include "tests/support/hidden_effect_cut.hpp"

namespace millwatch::diagnose {
namespace {

void print(const Diagnosis& d) {
  std::printf("  noise floor %.4f, %.4f N; measured %.4f, %.4f N; band %.0f Hz; %.2f s\n",
              d.noise_floor_N[0], d.noise_floor_N[1], d.measured_rms_N[0], d.measured_rms_N[1],
              d.band_hz, d.seconds);
  std::printf("  start: residual %.4f, %.4f N  BIC %.1f\n", d.initial.residual_rms_N[0],
              d.initial.residual_rms_N[1], d.initial.criterion);
  auto candidates = [](const std::vector<CandidateScore>& cs) {
    for (const auto& c : cs) {
      std::printf("      %-22s %s gain %9.1f  residual %.4f, %.4f N %s\n", c.name.c_str(),
                  c.ok ? "ok" : "FAILED", c.gain, c.residual_rms_N[0], c.residual_rms_N[1],
                  c.message.c_str());
    }
  };
  if (d.steps.empty()) {
    candidates(d.initial.candidates);
  }
  for (const auto& s : d.steps) {
    std::printf("  + %s: residual %.4f, %.4f N  BIC %.1f gain %.1f, over %s by %.1f\n",
                s.added.c_str(), s.residual_rms_N[0], s.residual_rms_N[1], s.criterion, s.gain,
                s.runner_up.c_str(), s.margin_over_runner_up);
    for (const auto& p : s.parameters) {
      std::printf("      %s = %.4g ± %.2g\n", p.name.c_str(), p.value, p.sigma);
    }
    candidates(s.candidates);
  }
  std::printf("  stop: %s\n  verdict: %s\n  localisation (start): %s\n", d.stop_reason.c_str(),
              d.verdict.c_str(), d.initial.localisation.summary.c_str());
}

class HiddenEffect : public ::testing::TestWithParam<const char*> {};

TEST_P(HiddenEffect, IsNamedAddedAndClosesTheGap) {
  const std::string effect = GetParam();
  // Deflection leaves no trace in a symmetric cut (each steady chip is the feed per tooth
  // whatever the stiffness): it is hidden behind a runout the starting model knows.
  // A runout change is a change of a runout the starting model knows.
  const bool behind_runout = effect == "tool_deflection" || effect == "runout_change";
  const auto cut = behind_runout ? test::hidden_effect_cut({effect}, {"runout"})
                                 : test::hidden_effect_cut({effect});
  const Diagnosis d = diagnose(cut.record, cut.start);
  std::printf("%s hidden\n", effect.c_str());
  print(d);
  ASSERT_TRUE(d.ok) << d.message;
  ASSERT_FALSE(d.named_effects.empty()) << d.verdict;
  EXPECT_EQ(d.named_effects.front(), effect);
  EXPECT_EQ(d.named_effects.size(), 1U);
  const auto& last = d.steps.back().residual_rms_N;
  for (std::size_t a = 0; a < 2; ++a) {
    EXPECT_LE(last[a], 1.3 * d.noise_floor_N[a]) << "axis " << a;
  }
  // [001]'s ploughed area belongs to the linear law: a power-law cut does not score it.
  const bool linear = cut.start.material.law == model::ForceLawKind::kLinearEdge;
  EXPECT_EQ(linear, effect == "ploughing_area");
  for (const auto& c : d.steps.front().candidates) {
    EXPECT_TRUE(linear || c.name != "ploughing_area");
  }
}

INSTANTIATE_TEST_SUITE_P(Catalogue, HiddenEffect,
                         ::testing::Values("runout", "min_chip_thickness", "chip_accumulation",
                                           "ploughing_area", "tool_deflection", "helix_lag",
                                           "trochoidal_path", "dynamometer_dynamics",
                                           "spindle_speed_error", "amplifier_drift", "mains_hum"),
                         [](const auto& p) { return std::string(p.param); });

TEST(Diagnose, PloughedAreaIsFoundWithItsHMinAndCoefficients) {
  // [001]'s law hidden (h_min 1.5 µm, K_tp 4000, K_np 6000 N/mm³): the step states them, and
  // the edge force the plain linear law fitted in their place is gone from the law.
  const auto cut = test::hidden_effect_cut({"ploughing_area"});
  const Diagnosis d = diagnose(cut.record, cut.start);
  print(d);
  ASSERT_TRUE(d.ok) << d.message;
  ASSERT_EQ(d.named_effects, std::vector<std::string>{"ploughing_area"}) << d.verdict;
  const auto& ps = d.steps.front().parameters;
  const Parameter* h = test::find_parameter(ps, "h_min_um");
  const Parameter* ktp = test::find_parameter(ps, "k_tp_N_per_mm3");
  const Parameter* knp = test::find_parameter(ps, "k_np_N_per_mm3");
  ASSERT_NE(h, nullptr);
  ASSERT_NE(ktp, nullptr);
  ASSERT_NE(knp, nullptr);
  EXPECT_FALSE(h->upper_bound || h->lower_bound) << h->bound_note;
  EXPECT_GT(h->sigma, 0.0);
  EXPECT_NEAR(h->value, 1.5, 3.0 * h->sigma);
  // The truth's finer angle step and more helix discs than the fitted model's move the
  // coefficients by a few per cent, beyond their σ from the noise alone.
  EXPECT_NEAR(ktp->value, 4000.0, 0.05 * 4000.0);
  EXPECT_NEAR(knp->value, 6000.0, 0.05 * 6000.0);
  EXPECT_TRUE(d.final_model.material.linear_edge.ploughing_area);
  EXPECT_TRUE(d.final_model.effects.min_chip.enabled);
}

TEST(Diagnose, PloughedAreaBesideAConfiguredHMinIsProfiled) {
  // The starting model has a minimum chip thickness of its own (0.5 µm, configured: no σ, a third
  // of the truth's): the ploughed area profiles h_min afresh rather than taking that one.
  auto cut = test::hidden_effect_cut({"ploughing_area"});
  cut.start.effects.min_chip.enabled = true;
  const Diagnosis d = diagnose(cut.record, cut.start);
  print(d);
  ASSERT_TRUE(d.ok) << d.message;
  ASSERT_FALSE(d.named_effects.empty()) << d.verdict;
  EXPECT_EQ(d.named_effects.front(), "ploughing_area") << d.verdict;
  const Parameter* h = test::find_parameter(d.steps.front().parameters, "h_min_um");
  ASSERT_NE(h, nullptr);
  EXPECT_NEAR(h->value, 1.5, 3.0 * h->sigma);
  for (std::size_t a = 0; a < 2; ++a) {
    EXPECT_LE(d.final_residual_rms_N[a], 1.3 * d.noise_floor_N[a]) << "axis " << a;
  }
}

TEST(Diagnose, NegativeControlAddsNothing) {
  const auto cut = test::hidden_effect_cut({});
  const Diagnosis d = diagnose(cut.record, cut.start);
  print(d);
  ASSERT_TRUE(d.ok) << d.message;
  EXPECT_TRUE(d.named_effects.empty()) << d.verdict;

  // The model describes the record to its noise: its σ need no caveat.
  EXPECT_TRUE(d.sigma_caveat.empty()) << d.sigma_caveat;
}

}  // namespace
}  // namespace millwatch::diagnose
