// The summary as a person reads it says what the JSON says: the revolutions measured as the JSON
// (revolutions_measured) and the "revolutions missed" warning count them, and how many of them
// had all their tooth events (revolutions: those α and the periods come from).

#include "shell/summary_text.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

namespace millwatch::shell {
namespace {

nlohmann::json summary(int with_all_events, int measured) {
  return {{"input", "cut.csv"},
          {"spindle_rpm_commanded", 25000.0},
          {"revolutions", with_all_events},
          {"revolutions_measured", measured},
          {"revolutions_cutting", 101.0}};
}

TEST(SummaryText, CountsTheRevolutionsMeasuredAsTheJsonDoes) {
  const std::string some = summary_text(summary(37, 41));
  EXPECT_NE(
      some.find("revolutions   41 measured of ~101 turned while cutting (37 with all their tooth "
                "events)\n"),
      std::string::npos)
      << some;
  const std::string all = summary_text(summary(41, 41));
  EXPECT_NE(all.find("revolutions   41 measured of ~101 turned while cutting\n"), std::string::npos)
      << all;
  // A record in which no cutting was heard (PHM c1_cut001): not "0 measured of ~0 turned".
  nlohmann::json none = summary(0, 0);
  none["revolutions_cutting"] = 0.0;
  const std::string idle = summary_text(none);
  EXPECT_NE(idle.find("revolutions   none: no cutting heard\n"), std::string::npos) << idle;
  // Nor where the record was too short for the tracker to hear anything (a force of 52 N RMS
  // in the line above it had read "no cutting heard").
  none["warnings"] = nlohmann::json::array(
      {{{"kind", "record too short"}, {"detail", "0.1000 s of samples, 0.4000 s needed"}}});
  const std::string short_text = summary_text(none);
  EXPECT_NE(short_text.find("revolutions   none: the record is too short (warnings below)\n"),
            std::string::npos)
      << short_text;
}

// α from one revolution has no spread to state (the JSON's std is null): not "± 0.00°".
TEST(SummaryText, AlphaFromOneRevolutionHasNoSpread) {
  nlohmann::json one = summary(1, 1);
  one["alpha_deg"] = {{"mean", 157.29}, {"std", nullptr}};
  const std::string text = summary_text(one);
  EXPECT_NE(text.find("alpha         157.29° (one revolution: no spread)"), std::string::npos)
      << text;
  nlohmann::json many = summary(41, 41);
  many["alpha_deg"] = {{"mean", 157.29}, {"std", 0.15}};
  // The ± of a mean over revolutions is their spread, and says so (the runout's is a σ).
  EXPECT_NE(summary_text(many).find("alpha         157.29° ± 0.15° rev to rev"), std::string::npos);
  many["spindle_rpm"] = 25252.0;
  many["spindle_rpm_std"] = 1.0;
  many["delta_fy_N"] = 0.776;
  many["delta_fy_N_std"] = 0.002;
  const std::string text_many = summary_text(many);
  EXPECT_NE(text_many.find("speed         25252.0 rpm measured (± 1.0 rev to rev), 25000 "
                           "commanded (+1.01 %)"),
            std::string::npos)
      << text_many;
  EXPECT_NE(text_many.find("delta Fy      0.776 N ± 0.002 rev to rev"), std::string::npos)
      << text_many;
}

// Each flute's period and resultant peak have their spread on the row under them, in their
// columns; a flute without one (a single revolution) shows a dash.
TEST(SummaryText, FlutePeriodsAndPeaksHaveTheirSpreadUnderThem) {
  nlohmann::json j = summary(41, 41);
  j["tooth_period_s"] = {1.3379e-3, 1.0382e-3};
  j["tooth_period_s_std"] = {2.1e-6, nullptr};
  j["peak_force_N"] = {{"resultant", {1.639, 0.942}}};
  j["peak_force_N_std"] = {{"resultant", {0.004, 0.0031}}};
  const std::string text = summary_text(j);
  EXPECT_NE(text.find("  period [ms]         1.3379    1.0382\n"
                      "    ± rev to rev      0.0021         —\n"
                      "  peak |Fxy| [N]       1.639     0.942\n"
                      "    ± rev to rev       0.004     0.003\n"),
            std::string::npos)
      << text;
}

// The identified runout, and where a flute cuts nothing beyond it (the fit on a flute's contact
// edge), that the figure is a lower bound.
TEST(SummaryText, TheRunoutSaysWhenItIsALowerBound) {
  nlohmann::json j = summary(41, 41);
  j["runout"] = {{"rho_um", 1.795},
                 {"rho_std_um", 0.015},
                 {"gamma_deg", 15.7},
                 {"gamma_std_deg", 0.5},
                 {"rho_is_lower_bound", false}};
  const std::string measured = summary_text(j);
  EXPECT_NE(measured.find("  runout        1.795 ± 0.015 µm at 15.7° ± 0.5° (identified)\n"),
            std::string::npos)
      << measured;
  j["runout"]["rho_is_lower_bound"] = true;
  const std::string bound = summary_text(j);
  EXPECT_NE(bound.find("  runout        ≥ 1.795 ± 0.015 µm at 15.7° ± 0.5° (identified; at a "
                       "flute's contact edge: a flute cuts nothing beyond it, so the force "
                       "bounds the runout from below only)\n"),
            std::string::npos)
      << bound;
}

// CE1's cutting radius against each flute's, which the force pins best (as the alerts state it),
// follows the runout: for two flutes with what it is.
TEST(SummaryText, TheRadiiFollowTheRunout) {
  nlohmann::json j = summary(41, 41);
  j["runout"] = {{"rho_um", 3.053},
                 {"rho_std_um", 0.216},
                 {"gamma_deg", -77.1},
                 {"gamma_std_deg", 3.5},
                 {"r_minus_r_ce1_um", {0.0, -1.366}},
                 {"r_minus_r_ce1_std_um", {0.0, 0.041}}};
  const std::string two = summary_text(j);
  EXPECT_NE(two.find("  radii         r_CE1 − r_CE2 1.366 ± 0.041 µm (= 2ρ·cos γ: what the "
                     "force pins)\n"),
            std::string::npos)
      << two;
  j["runout"]["r_minus_r_ce1_um"] = {0.0, 0.5, -1.25};
  j["runout"]["r_minus_r_ce1_std_um"] = {0.0, 0.02, 0.03};
  const std::string three = summary_text(j);
  EXPECT_NE(three.find("  radii         r_CE1 − r_CE2 -0.500 ± 0.020 µm, r_CE1 − r_CE3 1.250 ± "
                       "0.030 µm\n"),
            std::string::npos)
      << three;
  // On a contact edge the idle flute is named: with three flutes its deficit to the flute
  // before it is the bound (not r_CE1 − r_CE3); with two, r_CE1 − r_CE2 is.
  j["runout"]["rho_is_lower_bound"] = true;
  j["runout"]["edge_flute"] = 3;
  const std::string edge = summary_text(j);
  EXPECT_NE(edge.find("  radii         r_CE1 − r_CE2 -0.500 ± 0.020 µm, r_CE1 − r_CE3 1.250 ± "
                      "0.030 µm (flute 3 cuts nothing: its radius lies at least a chip below the "
                      "flute's before it)\n"),
            std::string::npos)
      << edge;
  j["runout"]["r_minus_r_ce1_um"] = {0.0, -3.839};
  j["runout"]["r_minus_r_ce1_std_um"] = {0.0, 0.102};
  j["runout"]["edge_flute"] = 2;
  const std::string two_edge = summary_text(j);
  EXPECT_NE(two_edge.find("  radii         r_CE1 − r_CE2 ≥ 3.839 ± 0.102 µm (flute 2 cuts nothing "
                          "beyond it: a lower bound)\n"),
            std::string::npos)
      << two_edge;
}

// A warning is printed whole: its reason comes last.
TEST(SummaryText, PrintsAWarningWhole) {
  nlohmann::json j = summary(41, 41);
  const std::string detail =
      "the identified model leaves 77 % of the measured force unexplained (RMS; 59 % of its "
      "variance, above identification.max_unexplained 20 %): runout and coefficients describe "
      "this cut poorly";
  j["warnings"] = {{{"kind", "model does not fit"}, {"detail", detail}, {"occurrences", 1}}};
  EXPECT_NE(summary_text(j).find("    model does not fit: " + detail + "\n"), std::string::npos)
      << summary_text(j);
}

// A warning whose events count samples says how many samples, not how many events: three bad
// samples in two blocks had read "(×2)".
TEST(SummaryText, AWarningOfSamplesCountsTheSamples) {
  nlohmann::json j = summary(41, 41);
  const std::string detail = "NaN, infinite or beyond ±1e6 N: replaced by the channel's last good";
  j["warnings"] = {
      {{"kind", "non-finite or implausible samples"},
       {"detail", detail},
       {"occurrences", 2},
       {"samples", 3}},
      {{"kind", "gap in the samples"}, {"detail", "a"}, {"occurrences", 1}, {"samples", 1}},
      {{"kind", "no steady tooth-passing signal"}, {"detail", "b"}, {"occurrences", 4}}};
  const std::string text = summary_text(j);
  EXPECT_NE(text.find(detail + " (3 samples at 2 places)\n"), std::string::npos) << text;
  EXPECT_NE(text.find("gap in the samples: a (1 sample)\n"), std::string::npos) << text;
  EXPECT_NE(text.find("no steady tooth-passing signal: b (×4)\n"), std::string::npos) << text;
}

// A sensor alert before the first revolution (revolution −1) says so, not "rev -1" or "rev 0".
TEST(SummaryText, AlertsSayTheirRevolutionOrThatTheyCameBeforeTheFirst) {
  nlohmann::json j = summary(41, 41);
  j["alerts"] = {{{"revolution", -1}, {"active", true}, {"message", "sensor trouble: a"}},
                 {{"revolution", 412}, {"active", false}, {"message", "sensor trouble cleared"}}};
  const std::string text = summary_text(j);
  EXPECT_NE(text.find("    before rev 0  RAISED  sensor trouble: a\n"), std::string::npos) << text;
  EXPECT_NE(text.find("    rev      412  cleared sensor trouble cleared\n"), std::string::npos)
      << text;
}

// The lockstep model's notes on its steady state (RunSummary's model.steady_state.notes) are
// printed one a line; a summary without them, or with a model or steady_state of another kind,
// prints none and does not fail.
TEST(SummaryText, PrintsTheModelsSteadyStateNotes) {
  nlohmann::json j = summary(41, 41);
  j["model"] = {{"steady_state", {{"notes", {"1 of 1 model builds had slots …"}}}}};
  const std::string text = summary_text(j);
  EXPECT_NE(text.find("  model note    1 of 1 model builds had slots …\n"), std::string::npos)
      << text;
  for (const nlohmann::json& model :
       {nlohmann::json(nullptr), nlohmann::json(3), nlohmann::json::object(),
        nlohmann::json{{"steady_state", nullptr}},
        nlohmann::json{{"steady_state", {{"notes", 7}}}}}) {
    j["model"] = model;
    std::string without;
    ASSERT_NO_THROW(without = summary_text(j)) << model.dump();
    EXPECT_EQ(without.find("model note"), std::string::npos) << model.dump();
  }
}

}  // namespace
}  // namespace millwatch::shell
