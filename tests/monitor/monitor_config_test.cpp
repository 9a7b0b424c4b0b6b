// The monitor configuration's identification section: defaults, round trip, and errors that
// name the field (an unknown parameter, one the configured model does not have).

#include "core/monitor/monitor_config.hpp"

#include <gtest/gtest.h>

#include <cmath>
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

// A value that the rest of the configuration does not suit is named with what it does not suit
// and where it came from: the spindle window checked against the speed when the configuration
// is read (it had been found only when the pipeline started, "spindle.window_s: value 0.050000 s
// must hold at least 5 revolutions", without the file or the speed), a default cut-off against
// a low sample rate.
TEST(MonitorConfig, CrossFieldErrorsSayWhatTheValueDoesNotSuit) {
  const auto at_rpm = [](double rpm, double window_s) {
    return error_of(
        {{"model", {{"process", {{"spindle_rpm", rpm}}}}}, {"spindle", {{"window_s", window_s}}}});
  };
  EXPECT_EQ(at_rpm(5000.0, 0.05),
            "config.spindle.window_s: value 0.05 s holds 4.16 revolutions at "
            "model.process.spindle_rpm 5000: at least 5 needed (0.06 s or more)");
  EXPECT_EQ(at_rpm(6000.0, 0.05), "");  // 5 revolutions exactly
  // 4.9999 revolutions are not "5" (rounded down).
  EXPECT_EQ(at_rpm(5999.9, 0.05),
            "config.spindle.window_s: value 0.05 s holds 4.99 revolutions at "
            "model.process.spindle_rpm 5999.9: at least 5 needed (0.0501 s or more)");
  // The automatic window: ten revolutions within 0.02–0.25 s, and at least 5 (below 1200 rpm
  // the quarter second held fewer, and the automatic window was refused).
  EXPECT_EQ(at_rpm(1000.0, 0.0), "");
  EXPECT_EQ(at_rpm(300.0, 0.0), "");
  // Every speed's automatic window, though 5·60/rpm · rpm/60 may come back as 4.999… (131 whole
  // speeds below 1200 rpm, 1003 among them, had been refused).
  for (int rpm = 1; rpm < 1200; ++rpm) {
    EXPECT_EQ(at_rpm(rpm, 0.0), "") << rpm;
  }

  EXPECT_EQ(error_of({{"sample_rate_hz", 1000.0}}),
            "config.filter.cutoff_hz: value 3300 Hz (the default) must stay below 0.45 x the "
            "sample rate (450 Hz)");
  EXPECT_EQ(error_of({{"sample_rate_hz", 1000.0}, {"filter", {{"cutoff_hz", 3000.0}}}}),
            "config.filter.cutoff_hz: value 3000 Hz must stay below 0.45 x the sample rate "
            "(450 Hz)");
}

// A cut the default cut-off does not suit, with none configured: [002]'s copper slot at 96,000
// rpm (tooth-passing 3,200 Hz, where 3.3 kHz would pass nothing above the first harmonic), or a
// slow DAQ. The nearest cut-off that does is taken and said; a configured one is the user's.
TEST(MonitorConfig, ChoosesACutoffThatSuitsTheCutWhereNoneIsGiven) {
  const auto cut = [](double rpm, double rate_hz) {
    return nlohmann::json{{"model", {{"process", {{"spindle_rpm", rpm}}}}},
                          {"sample_rate_hz", rate_hz}};
  };
  // 4 x the tooth-passing frequency, the default's ratio at [000]'s 25,000 rpm.
  const MonitorConfig fast = monitor_config_from_json(cut(96000.0, 100000.0), "config");
  EXPECT_EQ(fast.filter_cutoff_hz, 12800.0);
  EXPECT_EQ(fast.filter_cutoff_note,
            "filter.cutoff_hz not given: the default 3300 Hz would not pass 1.5 x the "
            "tooth-passing frequency (3200 Hz: model.process.spindle_rpm 96000, 2 flutes); taking "
            "12800 Hz, 4 x the tooth-passing frequency (set filter.cutoff_hz to choose)");
  // A 20 kHz DAQ: 0.4 x its rate, below 4 x but above 1.5 x the tooth-passing frequency.
  const MonitorConfig slow_daq = monitor_config_from_json(cut(96000.0, 20000.0), "config");
  EXPECT_EQ(slow_daq.filter_cutoff_hz, 8000.0);
  EXPECT_NE(slow_daq.filter_cutoff_note.find(
                "taking 8000 Hz, the most the sample rate allows (0.4 x it)"),
            std::string::npos)
      << slow_daq.filter_cutoff_note;
  // A 5 kHz DAQ at 3,000 rpm: the default is above its Nyquist band; 0.4 x the rate.
  const MonitorConfig low_rate = monitor_config_from_json(cut(3000.0, 5000.0), "config");
  EXPECT_EQ(low_rate.filter_cutoff_hz, 2000.0);
  EXPECT_EQ(low_rate.filter_cutoff_note,
            "filter.cutoff_hz not given: the default 3300 Hz would not stay below 0.45 x the "
            "sample rate (5000 Hz); taking 2000 Hz, the most the sample rate allows (0.4 x it) "
            "(set filter.cutoff_hz to choose)");
  // A lower order: its zero-phase design (raised 1.55× at order 1) must stay below 0.45× the
  // rate too, so the cut-off does not reach 0.4×; both filters are then built.
  nlohmann::json order_1 = cut(96000.0, 20000.0);
  order_1["filter"] = {{"order", 1}};
  const MonitorConfig first_order = monitor_config_from_json(order_1, "config");
  EXPECT_NEAR(first_order.filter_cutoff_hz,
              0.449 * 20000.0 / std::sqrt(1.0 / (std::sqrt(2.0) - 1.0)), 1e-9);
  EXPECT_GT(first_order.filter_cutoff_hz, 1.5 * 3200.0);
  EXPECT_LT(zero_phase_design_cutoff_hz(first_order.filter_cutoff_hz, 1), 0.45 * 20000.0);
  // The rate changed after reading (the daemon takes a Comedi board's running rate): chosen
  // again for it; a configured cut-off is not.
  MonitorConfig rerun = fast;
  rerun.sample_rate_hz = 20000.0;
  choose_cutoff_for_cut(rerun);
  EXPECT_EQ(rerun.filter_cutoff_hz, 8000.0);
  // Where the default suits the cut it stays, unsaid ([000]'s cut; 60,000 rpm, 3,000 Hz ≤ 3.3 kHz).
  for (const double rpm : {25000.0, 60000.0}) {
    const MonitorConfig c = monitor_config_from_json(cut(rpm, 50000.0), "config");
    EXPECT_EQ(c.filter_cutoff_hz, 3300.0) << rpm;
    EXPECT_EQ(c.filter_cutoff_note, "") << rpm;
  }
  // A configured cut-off is never moved: the error names the user's value.
  nlohmann::json given = cut(96000.0, 100000.0);
  given["filter"] = {{"cutoff_hz", 4000.0}};
  EXPECT_EQ(error_of(given),
            "config.filter.cutoff_hz: value 4000 Hz must pass at least 1.5 x the tooth-passing "
            "frequency (4800 Hz at model.process.spindle_rpm 96000)");
  // No cut-off serves (1.5 x 3200 Hz above 0.4 x 10 kHz): the default's error, as before.
  EXPECT_EQ(error_of(cut(96000.0, 10000.0)),
            "config.filter.cutoff_hz: value 3300 Hz (the default) must pass at least 1.5 x the "
            "tooth-passing frequency (4800 Hz at model.process.spindle_rpm 96000)");
  // Written out, the chosen cut-off is read back as configured: the same, nothing to say.
  const MonitorConfig again = monitor_config_from_json(to_json(fast), "config");
  EXPECT_EQ(again.filter_cutoff_hz, 12800.0);
  EXPECT_EQ(again.filter_cutoff_note, "");
}

}  // namespace
}  // namespace millwatch::monitor
