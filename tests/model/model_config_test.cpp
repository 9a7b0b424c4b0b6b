#include "core/model/model_config.hpp"

#include <gtest/gtest.h>

#include <functional>
#include <numbers>

#include "core/config/json_reader.hpp"

namespace millwatch::model {
namespace {

using nlohmann::json;

std::string error_of(const json& j) {
  try {
    model_config_from_json(j);
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(ModelConfig, DefaultsAreMasraniKarpatCase) {
  const ModelConfig c = model_config_from_json(json::object());
  EXPECT_DOUBLE_EQ(c.tool.diameter_mm, 0.4);
  EXPECT_EQ(c.tool.flutes, 2);
  EXPECT_DOUBLE_EQ(c.material.power_law.k_tc_Nmm, 465.4);
  EXPECT_DOUBLE_EQ(c.effects.runout.offset_um, 1.82);
  EXPECT_DOUBLE_EQ(c.effects.deflection.stiffness_N_per_um, 0.47);
}

TEST(ModelConfig, JsonRoundTripPreservesEveryField) {
  ModelConfig c;
  c.tool.flutes = 3;
  c.tool.pitch_deg = {110.0, 125.0, 125.0};
  c.process.operation = Operation::kDownMilling;
  c.process.radial_depth_mm = 0.15;
  c.material.law = ForceLawKind::kKronenberg;
  c.material.kronenberg.m = 3.5;
  c.effects.flank_wear.enabled = true;
  c.effects.flank_wear.wear_um = {1.0, 2.0, 3.0};
  c.effects.dynamometer.enabled = true;
  c.resolution.steps_per_rev = 1080;
  const json j = to_json(c);
  const ModelConfig back = model_config_from_json(j);
  EXPECT_EQ(to_json(back), j);
  EXPECT_EQ(back.process.operation, Operation::kDownMilling);
  EXPECT_EQ(back.tool.pitch_deg.size(), 3u);
}

TEST(ModelConfig, BadValuesNameFieldValueAndRange) {
  EXPECT_EQ(error_of({{"tool", {{"diameter_mm", -0.4}}}}),
            "tool.diameter_mm: value -0.4 is out of range (0, 50] mm");
  EXPECT_EQ(error_of({{"tool", {{"flutes", 0}}}}), "tool.flutes: value 0 is out of range [1, 8]");
  EXPECT_EQ(error_of({{"tool", {{"flutes", "two"}}}}),
            "tool.flutes: expected an integer, got string \"two\"");
  EXPECT_NE(
      error_of({{"process", {{"spindel_rpm", 1000}}}}).find("process.spindel_rpm: unknown key"),
      std::string::npos);
  EXPECT_NE(error_of({{"effects", {{"runout", {{"enabled", "yes"}}}}}})
                .find("effects.runout.enabled: expected true or false"),
            std::string::npos);
  EXPECT_NE(error_of({{"material", {{"law", "magic"}}}}).find("material.law: value \"magic\""),
            std::string::npos);
}

TEST(ModelConfig, CrossFieldChecksNameTheField) {
  EXPECT_NE(error_of({{"process", {{"operation", "up"}, {"radial_depth_mm", 0.5}}}})
                .find("process.radial_depth_mm: value 0.5"),
            std::string::npos);
  EXPECT_NE(error_of({{"tool", {{"flutes", 2}, {"pitch_deg", {170.0, 170.0}}}}})
                .find("tool.pitch_deg: entries sum to 340"),
            std::string::npos);
  EXPECT_NE(error_of({{"effects", {{"min_chip", {{"enabled", false}}}}}})
                .find("effects.accumulation.enabled"),
            std::string::npos);
  EXPECT_EQ(error_of({{"tool", {{"flutes", 3}}}, {"resolution", {{"steps_per_rev", 720}}}}), "");
  EXPECT_NE(error_of({{"tool", {{"flutes", 7}}}}).find("resolution.steps_per_rev"),
            std::string::npos);
}

TEST(ModelConfig, EffectSwitchesByName) {
  ModelConfig c;
  for (const char* name : kEffectNames) {
    set_effect(c, name, true);
    EXPECT_TRUE(effect_enabled(c, name)) << name;
  }
  const ModelConfig none = without_effects(c);
  for (const char* name : kEffectNames) {
    EXPECT_FALSE(effect_enabled(none, name)) << name;
  }
  EXPECT_THROW(set_effect(c, "gravity", true), std::invalid_argument);
  // accumulation needs min_chip: switching one keeps the pair consistent
  set_effect(c, "min_chip", false);
  EXPECT_FALSE(c.effects.accumulation.enabled);
}

TEST(ModelConfig, PitchAnglesAreCumulative) {
  Tool t;
  t.flutes = 3;
  t.pitch_deg = {100.0, 130.0, 130.0};
  const auto psi = flute_pitch_angles_rad(t);
  ASSERT_EQ(psi.size(), 3u);
  EXPECT_NEAR(psi[1], 100.0 * std::numbers::pi / 180.0, 1e-12);
  EXPECT_NEAR(psi[2], 230.0 * std::numbers::pi / 180.0, 1e-12);
}

}  // namespace
}  // namespace millwatch::model
