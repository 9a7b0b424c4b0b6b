#include "core/model/parameter_map.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <numbers>
#include <set>
#include <string>
#include <vector>

#include "core/config/json_reader.hpp"
#include "core/model/steady_state.hpp"
#include "tests/support/allocation_counter.hpp"

namespace millwatch::model {
namespace {

/// The value at a configuration path such as "effects.dynamometer.natural_hz[1]", read from the
/// JSON form of the configuration (model_config.cpp's to_json, independent of the map).
double json_value(const ModelConfig& c, const std::string& path) {
  nlohmann::json j = to_json(c);
  std::size_t from = 0;
  while (from < path.size()) {
    std::size_t to = path.find('.', from);
    std::string key = path.substr(from, to == std::string::npos ? std::string::npos : to - from);
    const std::size_t bracket = key.find('[');
    if (bracket != std::string::npos) {
      const int index = std::stoi(key.substr(bracket + 1));
      j = j.at(key.substr(0, bracket)).at(static_cast<std::size_t>(index));
    } else {
      j = j.at(key);
    }
    from = to == std::string::npos ? path.size() : to + 1;
  }
  return j.get<double>();
}

std::vector<ModelConfig> every_law() {
  std::vector<ModelConfig> configs(3);
  configs[1].material.law = ForceLawKind::kLinearEdge;
  configs[2].material.law = ForceLawKind::kKronenberg;
  configs[2].effects.flank_wear.wear_um = {3.0, 4.0};  // one per flute
  return configs;
}

// Setting a parameter writes exactly its named field (read back through the JSON form, not
// through the map), getting it reads it back, and nothing else changes.
TEST(ParameterMap, EachParameterIsItsNamedField) {
  for (const ModelConfig& base : every_law()) {
    SCOPED_TRACE(to_string(base.material.law));
    for (const ParameterInfo& p : available_parameters(base)) {
      SCOPED_TRACE(p.name);
      const std::string names[] = {p.name};
      const ParameterMap map = make_parameter_map(base, names);
      const double value = p.lower + 0.37 * std::min(p.upper - p.lower, 10.0 * p.scale);
      ModelConfig c = base;
      set_parameters(map, Eigen::VectorXd::Constant(1, value), c);
      EXPECT_DOUBLE_EQ(json_value(c, p.field), value);
      EXPECT_DOUBLE_EQ(get_parameters(map, c)[0], value);
      // Only that field moved: putting the old value back restores the whole configuration.
      set_parameters(map, Eigen::VectorXd::Constant(1, json_value(base, p.field)), c);
      EXPECT_EQ(to_json(c), to_json(base));
    }
  }
}

// A vector of independent values for runout, coefficients, h_min, stiffness, wear and the
// dynamometer goes in and comes out, and lands in the right fields.
TEST(ParameterMap, RoundTripOfAParameterVector) {
  ModelConfig c;
  const std::vector<std::string> names = {"rho_um",         "gamma_rad",      "k_tc_Nmm",
                                          "a_tc",           "k_nc_Nmm",       "a_nc",
                                          "h_min_um",       "k_np_Nmm",       "stiffness_N_per_um",
                                          "wear_um",        "k_wt_N_per_mm2", "natural_hz_y",
                                          "damping_ratio_z"};
  const ParameterMap map = make_parameter_map(c, names);
  ASSERT_EQ(map.size(), 13);
  Eigen::VectorXd x(13);
  x << 2.5, -0.7, 500.0, 0.6, 130.0, 0.3, 0.35, 75.0, 0.9, 12.0, 250.0, 4321.0, 0.12;
  ASSERT_TRUE(within_bounds(map, x));
  set_parameters(map, x, c);
  EXPECT_EQ(c.effects.runout.offset_um, 2.5);
  EXPECT_EQ(c.effects.runout.angle_rad, -0.7);
  EXPECT_EQ(c.material.power_law.k_tc_Nmm, 500.0);
  EXPECT_EQ(c.material.power_law.a_tc, 0.6);
  EXPECT_EQ(c.material.power_law.k_nc_Nmm, 130.0);
  EXPECT_EQ(c.material.power_law.a_nc, 0.3);
  EXPECT_EQ(c.effects.min_chip.h_min_um, 0.35);
  EXPECT_EQ(c.material.power_law.k_np_Nmm, 75.0);
  EXPECT_EQ(c.effects.deflection.stiffness_N_per_um, 0.9);
  EXPECT_EQ(c.effects.flank_wear.wear_um, std::vector<double>{12.0});
  EXPECT_EQ(c.effects.flank_wear.k_wt_N_per_mm2, 250.0);
  EXPECT_EQ(c.effects.dynamometer.natural_hz[1], 4321.0);
  EXPECT_EQ(c.effects.dynamometer.damping_ratio[2], 0.12);
  EXPECT_EQ(get_parameters(map, c), x);
  Eigen::VectorXd y(13);
  test::AllocationCounter counter;
  set_parameters(map, x, c);
  get_parameters(map, c, y);
  EXPECT_EQ(counter.allocations(), 0);
  EXPECT_EQ(y, x);
  EXPECT_THROW(set_parameters(map, Eigen::VectorXd::Zero(3), c), std::invalid_argument);
}

// Bounds are the configuration's own limits: every value between them is accepted by
// model_config_from_json (and validate), the defaults lie inside, and a step past a hard limit
// is refused with the field named.
TEST(ParameterMap, BoundsAreTheConfigurationsLimits) {
  for (const ModelConfig& base : every_law()) {
    SCOPED_TRACE(to_string(base.material.law));
    for (const ParameterInfo& p : available_parameters(base)) {
      SCOPED_TRACE(p.name);
      EXPECT_LT(p.lower, p.upper);
      EXPECT_GT(p.scale, 0.0);
      const double now = json_value(base, p.field);
      EXPECT_GE(now, p.lower);
      EXPECT_LE(now, p.upper);
      for (double v : {p.lower, p.upper, 0.5 * (p.lower + p.upper)}) {
        ModelConfig c = base;
        const std::string names[] = {p.name};
        set_parameters(make_parameter_map(base, names), Eigen::VectorXd::Constant(1, v), c);
        EXPECT_NO_THROW(model_config_from_json(to_json(c))) << v;
      }
    }
  }
  // Hard limits: past them the configuration is invalid.
  const ModelConfig c;
  auto error_past_upper = [&](const std::string& name) {
    const std::string names[] = {name};
    const ParameterMap map = make_parameter_map(c, names);
    ModelConfig d = c;
    const double upper = map.parameters[0].upper;
    set_parameters(map, Eigen::VectorXd::Constant(1, upper + 1e-6 * std::max(1.0, upper)), d);
    try {
      model_config_from_json(to_json(d));
    } catch (const config::ConfigError& e) {
      return e.path();
    }
    return std::string("accepted");
  };
  EXPECT_EQ(error_past_upper("rho_um"), "effects.runout.offset_um");
  EXPECT_EQ(error_past_upper("gamma_rad"), "effects.runout.angle_rad");
  EXPECT_EQ(error_past_upper("h_min_um"), "effects.min_chip.h_min_um");
  EXPECT_EQ(error_past_upper("damping_ratio_x"), "effects.dynamometer.damping_ratio[0]");
  EXPECT_EQ(error_past_upper("a_tc"), "material.power_law.a_tc");
  EXPECT_NEAR(make_parameter_map(c, std::vector<std::string>{"rho_um"}).parameters[0].upper,
              0.2 * 200.0, 1e-9);  // R/5 for the 0.4 mm tool
}

TEST(ParameterMap, UnknownOrForeignNamesAreRefusedByName) {
  const ModelConfig power;  // power law, one wear value
  auto message = [&](const ModelConfig& c, const std::string& name) {
    try {
      const std::string names[] = {name};
      make_parameter_map(c, names);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(message(power, "rho").find("unknown parameter \"rho\""), std::string::npos);
  EXPECT_NE(message(power, "rho").find("rho_um"), std::string::npos);  // lists the known ones
  EXPECT_NE(message(power, "k_tc_N_per_mm2").find("power_law law"), std::string::npos);
  EXPECT_FALSE(message(power, "wear_um[0]").empty());  // one shared value: "wear_um"
  ModelConfig per_flute;
  per_flute.effects.flank_wear.wear_um = {1.0, 2.0};
  EXPECT_FALSE(message(per_flute, "wear_um").empty());
  EXPECT_FALSE(message(per_flute, "wear_um[2]").empty());
  EXPECT_TRUE(message(per_flute, "wear_um[1]").empty());
  EXPECT_THROW(make_parameter_map(power, std::vector<std::string>{"rho_um", "rho_um"}),
               std::invalid_argument);
  EXPECT_THROW(parameters_of_effect(power, "vibration"), std::invalid_argument);
}

// Every parameter belongs to exactly one effect; the diagnosis switches an effect and its
// parameters on together.
TEST(ParameterMap, ParametersBelongToTheirEffects) {
  ModelConfig c;
  EXPECT_EQ(parameters_of_effect(c, "runout"), (std::vector<std::string>{"rho_um", "gamma_rad"}));
  EXPECT_EQ(parameters_of_effect(c, "deflection"),
            (std::vector<std::string>{"stiffness_N_per_um"}));
  EXPECT_EQ(parameters_of_effect(c, "force_law"),
            (std::vector<std::string>{"k_tc_Nmm", "a_tc", "k_nc_Nmm", "a_nc", "k_ac_Nmm", "a_ac"}));
  EXPECT_EQ(parameters_of_effect(c, "min_chip").front(), "h_min_um");
  EXPECT_TRUE(parameters_of_effect(c, "trochoidal").empty());
  EXPECT_TRUE(parameters_of_effect(c, "ploughing_area").empty());  // not the power law's
  c.material.law = ForceLawKind::kLinearEdge;
  EXPECT_EQ(parameters_of_effect(c, "ploughing_area"),
            (std::vector<std::string>{"k_tp_N_per_mm3", "k_np_N_per_mm3", "k_ap_N_per_mm3"}));
  std::multiset<std::string> seen;
  std::vector<std::string> effects = {"force_law"};
  effects.insert(effects.end(), kEffectNames.begin(), kEffectNames.end());
  for (const std::string& effect : effects) {
    for (const std::string& name : parameters_of_effect(c, effect)) {
      seen.insert(name);
    }
  }
  const auto all = available_parameters(c);
  EXPECT_EQ(seen.size(), all.size());
  for (const ParameterInfo& p : all) {
    EXPECT_EQ(seen.count(p.name), 1u) << p.name;
  }
  const std::vector<std::string> chosen = {"runout", "deflection"};
  const ParameterMap map = make_effect_parameter_map(c, chosen);
  ASSERT_EQ(map.size(), 3);
  EXPECT_EQ(map.parameters[2].name, "stiffness_N_per_um");
}

// The force basis names its columns by parameter names, so a fitter can map them.
TEST(ParameterMap, ForceBasisColumnsAreParameters) {
  for (ModelConfig c : every_law()) {
    c.effects.deflection.enabled = false;
    for (bool area : {false, true}) {
      c.material.linear_edge.ploughing_area = area;
      SteadyStateWorkspace ws;
      const ForceBasis& basis = evaluate_force_basis(c, 25000.0, 360, ws);
      std::vector<std::string> names;
      for (int col = 0; col < basis.columns; ++col) {
        names.emplace_back(basis.names[static_cast<std::size_t>(col)]);
      }
      EXPECT_NO_THROW(make_parameter_map(c, names)) << to_string(c.material.law);
    }
  }
}

}  // namespace
}  // namespace millwatch::model
