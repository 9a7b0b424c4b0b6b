#include "core/model/model_config.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <functional>
#include <numbers>
#include <string>
#include <vector>

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

/// Every field set to a valid value that differs from its default and from the other fields of
/// its struct, so that a field lost, defaulted or read into its neighbour shows.
ModelConfig distinct_config() {
  ModelConfig c;
  c.tool.diameter_mm = 0.6;
  c.tool.flutes = 3;
  c.tool.helix_deg = 35.5;
  c.tool.edge_radius_um = 2.25;
  c.tool.pitch_deg = {110.0, 125.0, 125.0};
  c.process.operation = Operation::kDownMilling;
  c.process.spindle_rpm = 31234.5;
  c.process.feed_per_tooth_um = 3.25;
  c.process.axial_depth_mm = 0.055;
  c.process.radial_depth_mm = 0.15;
  c.material.name = "test alloy";
  c.material.law = ForceLawKind::kKronenberg;
  auto& pl = c.material.power_law;
  pl.k_tc_Nmm = 401.1;
  pl.a_tc = 0.511;
  pl.k_nc_Nmm = 102.2;
  pl.a_nc = 0.322;
  pl.k_tp_Nmm = 503.3;
  pl.a_tp = 0.533;
  pl.k_np_Nmm = 64.4;
  pl.a_np = 0.244;
  pl.k_ac_Nmm = 75.5;
  pl.a_ac = 0.955;
  pl.k_ap_Nmm = 86.6;
  pl.a_ap = 1.166;
  auto& le = c.material.linear_edge;
  le.k_tc_N_per_mm2 = 1201.5;
  le.k_nc_N_per_mm2 = 455.5;
  le.k_ac_N_per_mm2 = 151.5;
  le.k_te_N_per_mm = 7.5;
  le.k_ne_N_per_mm = 11.5;
  le.k_ae_N_per_mm = 2.5;
  le.ploughing_area = true;
  le.k_tp_N_per_mm3 = 5001.0;
  le.k_np_N_per_mm3 = 8002.0;
  le.k_ap_N_per_mm3 = 3003.0;
  le.a_t_Nmm = 11.1;
  le.b_t = 0.61;
  le.a_n_Nmm = 12.2;
  le.b_n = 0.62;
  le.a_a_Nmm = 13.3;
  le.b_a = 0.63;
  auto& kr = c.material.kronenberg;
  kr.k_s0_N_per_mm2 = 1234.5;
  kr.m = 3.5;
  kr.radial_ratio = 0.45;
  kr.axial_ratio = -0.15;
  auto& e = c.effects;
  e.runout.enabled = false;
  e.runout.offset_um = 2.5;
  e.runout.angle_rad = -1.25;
  e.runout.helix = RunoutHelix::kRigidAxis;
  e.trochoidal.enabled = false;
  e.multi_pass.enabled = false;
  e.multi_pass.passes = 5;
  e.min_chip.enabled = false;
  e.min_chip.h_min_um = 0.35;
  e.accumulation.enabled = false;
  e.deflection.enabled = false;
  e.deflection.stiffness_N_per_um = 0.55;
  e.helix_lag.enabled = false;
  e.helix_lag.discs = 12;
  e.flank_wear.enabled = true;
  e.flank_wear.wear_um = {1.0, 2.0, 3.0};
  e.flank_wear.k_wt_N_per_mm2 = 310.0;
  e.flank_wear.k_wn_N_per_mm2 = 620.0;
  e.dynamometer.enabled = true;
  e.dynamometer.natural_hz = {2100.0, 2200.0, 3100.0};
  e.dynamometer.damping_ratio = {0.04, 0.06, 0.07};
  c.resolution.steps_per_rev = 1080;
  return c;
}

/// Through the text a file would hold.
ModelConfig round_trip(const ModelConfig& c) {
  return model_config_from_json(json::parse(to_json(c).dump()));
}

// Written and read back through text, every field keeps its (non-default) value, compared field
// by field against the values set, not against to_json again.
TEST(ModelConfig, JsonRoundTripPreservesEveryField) {
  const ModelConfig d;  // defaults
  const ModelConfig c = distinct_config();
  const ModelConfig b = round_trip(c);

  EXPECT_EQ(b.tool.diameter_mm, 0.6);
  EXPECT_EQ(b.tool.flutes, 3);
  EXPECT_EQ(b.tool.helix_deg, 35.5);
  EXPECT_EQ(b.tool.edge_radius_um, 2.25);
  EXPECT_EQ(b.tool.pitch_deg, (std::vector<double>{110.0, 125.0, 125.0}));
  EXPECT_EQ(b.process.operation, Operation::kDownMilling);
  EXPECT_EQ(b.process.spindle_rpm, 31234.5);
  EXPECT_EQ(b.process.feed_per_tooth_um, 3.25);
  EXPECT_EQ(b.process.axial_depth_mm, 0.055);
  EXPECT_EQ(b.process.radial_depth_mm, 0.15);
  EXPECT_EQ(b.material.name, "test alloy");
  EXPECT_EQ(b.material.law, ForceLawKind::kKronenberg);

  const auto& pl = b.material.power_law;
  EXPECT_EQ(pl.k_tc_Nmm, 401.1);
  EXPECT_EQ(pl.a_tc, 0.511);
  EXPECT_EQ(pl.k_nc_Nmm, 102.2);
  EXPECT_EQ(pl.a_nc, 0.322);
  EXPECT_EQ(pl.k_tp_Nmm, 503.3);
  EXPECT_EQ(pl.a_tp, 0.533);
  EXPECT_EQ(pl.k_np_Nmm, 64.4);
  EXPECT_EQ(pl.a_np, 0.244);
  EXPECT_EQ(pl.k_ac_Nmm, 75.5);
  EXPECT_EQ(pl.a_ac, 0.955);
  EXPECT_EQ(pl.k_ap_Nmm, 86.6);
  EXPECT_EQ(pl.a_ap, 1.166);

  const auto& le = b.material.linear_edge;
  EXPECT_EQ(le.k_tc_N_per_mm2, 1201.5);
  EXPECT_EQ(le.k_nc_N_per_mm2, 455.5);
  EXPECT_EQ(le.k_ac_N_per_mm2, 151.5);
  EXPECT_EQ(le.k_te_N_per_mm, 7.5);
  EXPECT_EQ(le.k_ne_N_per_mm, 11.5);
  EXPECT_EQ(le.k_ae_N_per_mm, 2.5);
  EXPECT_TRUE(le.ploughing_area);
  EXPECT_EQ(le.k_tp_N_per_mm3, 5001.0);
  EXPECT_EQ(le.k_np_N_per_mm3, 8002.0);
  EXPECT_EQ(le.k_ap_N_per_mm3, 3003.0);
  EXPECT_EQ(le.a_t_Nmm, 11.1);
  EXPECT_EQ(le.b_t, 0.61);
  EXPECT_EQ(le.a_n_Nmm, 12.2);
  EXPECT_EQ(le.b_n, 0.62);
  EXPECT_EQ(le.a_a_Nmm, 13.3);
  EXPECT_EQ(le.b_a, 0.63);

  const auto& kr = b.material.kronenberg;
  EXPECT_EQ(kr.k_s0_N_per_mm2, 1234.5);
  EXPECT_EQ(kr.m, 3.5);
  EXPECT_EQ(kr.radial_ratio, 0.45);
  EXPECT_EQ(kr.axial_ratio, -0.15);

  const auto& e = b.effects;
  EXPECT_FALSE(e.runout.enabled);
  EXPECT_EQ(e.runout.offset_um, 2.5);
  EXPECT_EQ(e.runout.angle_rad, -1.25);
  EXPECT_EQ(e.runout.helix, RunoutHelix::kRigidAxis);
  EXPECT_FALSE(e.trochoidal.enabled);
  EXPECT_FALSE(e.multi_pass.enabled);
  EXPECT_EQ(e.multi_pass.passes, 5);
  EXPECT_FALSE(e.min_chip.enabled);
  EXPECT_EQ(e.min_chip.h_min_um, 0.35);
  EXPECT_FALSE(e.accumulation.enabled);
  EXPECT_FALSE(e.deflection.enabled);
  EXPECT_EQ(e.deflection.stiffness_N_per_um, 0.55);
  EXPECT_FALSE(e.helix_lag.enabled);
  EXPECT_EQ(e.helix_lag.discs, 12);
  EXPECT_TRUE(e.flank_wear.enabled);
  EXPECT_EQ(e.flank_wear.wear_um, (std::vector<double>{1.0, 2.0, 3.0}));
  EXPECT_EQ(e.flank_wear.k_wt_N_per_mm2, 310.0);
  EXPECT_EQ(e.flank_wear.k_wn_N_per_mm2, 620.0);
  EXPECT_TRUE(e.dynamometer.enabled);
  EXPECT_EQ(e.dynamometer.natural_hz, (std::array<double, 3>{2100.0, 2200.0, 3100.0}));
  EXPECT_EQ(e.dynamometer.damping_ratio, (std::array<double, 3>{0.04, 0.06, 0.07}));
  EXPECT_EQ(b.resolution.steps_per_rev, 1080);

  // The values above really are not the defaults (a field the reader ignores would fail).
  EXPECT_NE(b.tool.diameter_mm, d.tool.diameter_mm);
  EXPECT_NE(b.effects.runout.enabled, d.effects.runout.enabled);
  EXPECT_NE(b.effects.runout.helix, d.effects.runout.helix);
  EXPECT_NE(b.effects.accumulation.enabled, d.effects.accumulation.enabled);
  EXPECT_NE(b.material.linear_edge.ploughing_area, d.material.linear_edge.ploughing_area);
  EXPECT_NE(b.effects.flank_wear.enabled, d.effects.flank_wear.enabled);
  EXPECT_NE(b.resolution.steps_per_rev, d.resolution.steps_per_rev);
}

// Each choice of the enumerations (operation, force law, runout along the helix) survives.
TEST(ModelConfig, JsonRoundTripKeepsEveryChoiceOfEveryEnumeration) {
  for (Operation op : {Operation::kSlot, Operation::kUpMilling, Operation::kDownMilling}) {
    ModelConfig c;
    c.process.operation = op;
    c.process.radial_depth_mm = 0.1;
    EXPECT_EQ(round_trip(c).process.operation, op) << to_string(op);
  }
  for (ForceLawKind law :
       {ForceLawKind::kPowerLaw, ForceLawKind::kLinearEdge, ForceLawKind::kKronenberg}) {
    ModelConfig c;
    c.material.law = law;
    EXPECT_EQ(round_trip(c).material.law, law) << to_string(law);
  }
  for (RunoutHelix helix : {RunoutHelix::kRigidAxis, RunoutHelix::kTipPattern}) {
    ModelConfig c;
    c.effects.runout.helix = helix;
    EXPECT_EQ(round_trip(c).effects.runout.helix, helix) << to_string(helix);
  }
}

/// JSON pointers of every object (including the root) and every leaf (a non-object value).
void collect(const json& j, const json::json_pointer& at, std::vector<json::json_pointer>& objects,
             std::vector<json::json_pointer>& leaves) {
  objects.push_back(at);
  for (const auto& [key, value] : j.items()) {
    if (value.is_object()) {
      collect(value, at / key, objects, leaves);
    } else {
      leaves.push_back(at / key);
    }
  }
}

std::string dotted(const json::json_pointer& p) {
  std::string s = p.to_string().substr(1);
  std::replace(s.begin(), s.end(), '/', '.');
  return s;
}

// A key the reader does not know, at any level of the file, is an error naming it by its full
// path (a misspelt key is never silently ignored).
TEST(ModelConfig, UnknownKeyAtEveryLevelIsReportedWithItsPath) {
  const json full = to_json(distinct_config());
  std::vector<json::json_pointer> objects, leaves;
  collect(full, json::json_pointer(), objects, leaves);
  EXPECT_EQ(objects.size(),
            18u);  // root, tool, process, material + 3 laws, effects + 9, resolution
  for (const auto& at : objects) {
    json j = full;
    j[at]["bogus_key"] = 1.0;
    const std::string where = at.empty() ? "bogus_key" : dotted(at) + ".bogus_key";
    EXPECT_EQ(error_of(j).rfind(where + ": unknown key", 0), 0u) << error_of(j);
  }
}

// Every field is optional: a missing one takes its default and leaves the others alone, except
// where the default breaks a cross-field rule with the values kept (then that is reported).
TEST(ModelConfig, MissingFieldTakesItsDefault) {
  const json full = to_json(distinct_config());
  const json defaults = to_json(ModelConfig{});
  std::vector<json::json_pointer> objects, leaves;
  collect(full, json::json_pointer(), objects, leaves);
  EXPECT_EQ(leaves.size(), 66u);  // every field of ModelConfig
  std::vector<std::string> refused;
  for (const auto& at : leaves) {
    json j = full;
    j[at.parent_pointer()].erase(at.back());
    std::string error;
    try {
      json expected = full;
      if (defaults.contains(at)) {
        expected[at] = defaults[at];
      } else {
        expected[at.parent_pointer()].erase(at.back());  // written only when set (pitch_deg)
      }
      EXPECT_EQ(to_json(model_config_from_json(j)), expected) << dotted(at);
    } catch (const config::ConfigError& e) {
      refused.push_back(dotted(at));
      error = e.what();
    }
    if (!error.empty()) {
      EXPECT_NE(error.find(": "), std::string::npos) << error;
    }
  }
  // The default 2 flutes do not fit three pitch entries and three wear values; accumulation
  // on by default needs min_chip, which is off here.
  std::sort(refused.begin(), refused.end());
  EXPECT_EQ(refused, (std::vector<std::string>{"effects.accumulation.enabled", "tool.flutes"}));
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
