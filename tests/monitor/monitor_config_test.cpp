// The monitor configuration's identification section: defaults, round trip, and errors that
// name the field (an unknown parameter, one the configured model does not have).

#include "core/monitor/monitor_config.hpp"

#include <gtest/gtest.h>

#include <string>

#include "core/config/json_reader.hpp"

namespace millwatch::monitor {
namespace {

std::string error_of(const nlohmann::json& j) {
  try {
    (void)monitor_config_from_json(j, "config");
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(MonitorConfig, IdentificationDefaultsAndRoundTrip) {
  const MonitorConfig d = monitor_config_from_json(nlohmann::json::object());
  EXPECT_TRUE(d.identification.enabled);
  EXPECT_TRUE(d.identification.extra_parameters.empty());
  EXPECT_DOUBLE_EQ(d.identification.max_unexplained, 0.2);
  EXPECT_DOUBLE_EQ(d.identification.runout_prior_um, 5.0);

  nlohmann::json j = nlohmann::json::parse(R"({
    "model": {"effects": {"min_chip": {"enabled": true, "h_min_um": 0.4},
                          "deflection": {"enabled": true, "stiffness_N_per_um": 0.5}}},
    "identification": {"enabled": false, "extra_parameters": ["h_min_um", "stiffness_N_per_um"],
                       "max_unexplained": 0.1, "runout_prior_um": 3}})");
  const MonitorConfig c = monitor_config_from_json(j);
  EXPECT_FALSE(c.identification.enabled);
  ASSERT_EQ(c.identification.extra_parameters.size(), 2u);
  EXPECT_EQ(c.identification.extra_parameters[0], "h_min_um");
  EXPECT_EQ(c.identification.extra_parameters[1], "stiffness_N_per_um");
  EXPECT_DOUBLE_EQ(c.identification.max_unexplained, 0.1);
  EXPECT_DOUBLE_EQ(c.identification.runout_prior_um, 3.0);
  EXPECT_EQ(to_json(monitor_config_from_json(to_json(c))), to_json(c));
}

TEST(MonitorConfig, IdentificationErrorsNameTheField) {
  const std::string unknown =
      error_of(nlohmann::json::parse(R"({"identification": {"extra_parameters": ["h_mni_um"]}})"));
  EXPECT_NE(unknown.find("config.identification.extra_parameters"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("h_mni_um"), std::string::npos) << unknown;

  // h_min is a parameter only when the minimum-chip effect is on.
  const std::string off = error_of(nlohmann::json::parse(
      R"({"model": {"effects": {"min_chip": {"enabled": false}, "accumulation": {"enabled": false}}},
          "identification": {"extra_parameters": ["h_min_um"]}})"));
  EXPECT_NE(off.find("identification.extra_parameters"), std::string::npos) << off;

  const std::string not_names =
      error_of(nlohmann::json::parse(R"({"identification": {"extra_parameters": "h_min_um"}})"));
  EXPECT_NE(not_names.find("expected an array"), std::string::npos) << not_names;
  const std::string bad_fraction =
      error_of(nlohmann::json::parse(R"({"identification": {"max_unexplained": 0}})"));
  EXPECT_NE(bad_fraction.find("config.identification.max_unexplained"), std::string::npos)
      << bad_fraction;
  const std::string typo = error_of(nlohmann::json::parse(R"({"identification": {"enable": 1}})"));
  EXPECT_NE(typo.find("enable"), std::string::npos) << typo;
}

// identification.cpu_budget: a fraction of one core in (0, 1], round-tripped; anything else is an
// error naming the key and the range.
TEST(MonitorConfig, CpuBudgetIsAFractionOfOneCore) {
  const MonitorConfig d = monitor_config_from_json(nlohmann::json::object());
  EXPECT_GT(d.identification.cpu_budget, 0.0);
  EXPECT_LE(d.identification.cpu_budget, 0.05);  // the daemon's 5 % of a core, all told
  for (const double ok : {1e-4, 0.5, 1.0}) {
    nlohmann::json j = {{"identification", {{"cpu_budget", ok}}}};
    const MonitorConfig c = monitor_config_from_json(j);
    EXPECT_DOUBLE_EQ(c.identification.cpu_budget, ok);
    EXPECT_DOUBLE_EQ(to_json(c)["identification"]["cpu_budget"].get<double>(), ok);
  }
  for (const nlohmann::json& bad : {nlohmann::json(0.0), nlohmann::json(-0.1), nlohmann::json(1.5),
                                    nlohmann::json("2 %"), nlohmann::json(nullptr)}) {
    const std::string e = error_of({{"identification", {{"cpu_budget", bad}}}});
    EXPECT_NE(e.find("config.identification.cpu_budget"), std::string::npos)
        << bad.dump() << ": " << e;
  }
  EXPECT_NE(error_of({{"identification", {{"cpu_budget", 0.0}}}}).find("(0, 1]"),
            std::string::npos);
}

}  // namespace
}  // namespace millwatch::monitor
