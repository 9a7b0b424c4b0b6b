// The dynamometer's damping ratio is held to a physical range (kDampingRatioMin–Max: a clamped
// piezoelectric dynamometer rings with ζ of a few 0.1 % to a few %). Simulated cuts recorded as a
// DAQ records them (tests/support/hidden_effect_cut: finer angle step, more discs, noise,
// quantisation) with a hidden resonance: one whose x damping lies below the range — the fit must
// hold it at the lower bound, say so, and still close the gap with the y damping estimated
// freely — and one inside the range, where nothing is held.

#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "core/diagnose/diagnosis.hpp"
#include "core/diagnose/diagnosis_json.hpp"
#include "tests/support/hidden_effect_cut.hpp"

namespace millwatch::diagnose {
namespace {

Diagnosis diagnose_resonance(double zeta_x, double zeta_y) {
  auto cut = test::hidden_effect_cut({"dynamometer_dynamics"}, {}, 0.3);
  cut.scenario.model.effects.dynamometer.damping_ratio = {zeta_x, zeta_y, 0.05};
  cut.record = test::record_in_model_frame(cut.scenario);
  DiagnoseOptions o;
  o.candidates = {"runout", "helix_lag", "dynamometer_dynamics", "min_chip_thickness"};
  const Diagnosis d = diagnose(cut.record, cut.start, o);
  std::printf("zeta %.4f, %.4f: %s\n", zeta_x, zeta_y, d.verdict.c_str());
  for (const auto& s : d.steps) {
    for (const auto& p : s.parameters) {
      std::printf("  %s = %.5g ± %.2g %s\n", p.name.c_str(), p.value, p.sigma, p.at_bound.c_str());
    }
  }
  return d;
}

const Parameter* find(const std::vector<Parameter>& ps, const std::string& name) {
  for (const auto& p : ps) {
    if (p.name == name) {
      return &p;
    }
  }
  return nullptr;
}

TEST(DampingBound, AnUnderdampedFitIsHeldAtTheLowerBound) {
  const Diagnosis d = diagnose_resonance(0.0004, 0.03);
  ASSERT_TRUE(d.ok) << d.message;
  ASSERT_FALSE(d.steps.empty()) << d.verdict;
  EXPECT_EQ(d.named_effects.front(), "dynamometer_dynamics");
  const auto& ps = d.steps.front().parameters;
  const Parameter* x = find(ps, "damping_ratio_x");
  const Parameter* y = find(ps, "damping_ratio_y");
  ASSERT_NE(x, nullptr);
  ASSERT_NE(y, nullptr);
  EXPECT_EQ(x->at_bound, "lower");
  EXPECT_DOUBLE_EQ(x->value, kDampingRatioMin);
  EXPECT_TRUE(y->at_bound.empty());
  EXPECT_NEAR(y->value, 0.03, 0.01);
  // Said in the diagnosis and in report.json (no σ for a bound).
  ASSERT_EQ(d.at_bound.size(), 1U);
  EXPECT_EQ(d.at_bound.front().name, "damping_ratio_x");
  const auto j = to_json(d);
  const auto& jx = j["steps"][0]["parameters"]["damping_ratio_x"];
  EXPECT_EQ(jx["at_bound"], "lower");
  EXPECT_TRUE(jx["sigma"].is_null());
  EXPECT_EQ(j["parameters_at_bound"].size(), 1U);
  // Held a little above the truth, the resonance still explains the record: damping matters
  // only within ζ·f_n of the resonance, where no harmonic of 25,000 rpm lies.
  for (std::size_t a = 0; a < 2; ++a) {
    EXPECT_LE(d.steps.back().residual_rms_N[a], 1.3 * d.noise_floor_N[a]) << "axis " << a;
  }
}

TEST(DampingBound, ADampingInsideTheRangeIsEstimated) {
  const Diagnosis d = diagnose_resonance(0.02, 0.05);
  ASSERT_TRUE(d.ok) << d.message;
  ASSERT_FALSE(d.steps.empty()) << d.verdict;
  EXPECT_EQ(d.named_effects.front(), "dynamometer_dynamics");
  EXPECT_TRUE(d.at_bound.empty());
  for (const auto& p : d.steps.front().parameters) {
    EXPECT_TRUE(p.at_bound.empty()) << p.name;
  }
  const Parameter* x = find(d.steps.front().parameters, "damping_ratio_x");
  ASSERT_NE(x, nullptr);
  EXPECT_NEAR(x->value, 0.02, 0.01);
}

}  // namespace
}  // namespace millwatch::diagnose
