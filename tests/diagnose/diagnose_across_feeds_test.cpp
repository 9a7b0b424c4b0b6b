// The diagnosis across feeds (core/diagnose/across_feeds.hpp) on simulated feed sweeps — three
// cuts of one tool at f_t 1, 2 and 4 µm, each recorded as a DAQ records it (finer angle step and
// more helix discs than the fitted model, noise, quantisation: tests/support/hidden_effect_cut)
// — with one effect hidden: the trend of the starting model's residual with the feed must point
// to the right kind of effect, each cut's diagnosis must name it, and its residual must shrink
// in every cut. The trend's exponent is also checked on analytic series.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "core/diagnose/across_feeds.hpp"
#include "tests/support/hidden_effect_cut.hpp"

namespace millwatch::diagnose {
namespace {

struct Sweep {
  std::vector<Diagnosis> diagnoses;
  AcrossFeeds across;
};

Sweep sweep(const std::string& hidden, const std::vector<double>& feeds_um) {
  Sweep s;
  DiagnoseOptions o;
  // The candidates that compete for a feed-dependent pattern (a fixed chip error, ploughing,
  // accumulation) and one of the chain, to keep the test short.
  o.candidates = {"runout", "min_chip_thickness", "chip_accumulation", "amplifier_drift"};
  o.uncertainties = false;
  s.diagnoses.reserve(feeds_um.size());
  for (const double f : feeds_um) {
    const auto cut = test::hidden_effect_cut_at_feed({hidden}, f, 0.25);
    s.diagnoses.push_back(diagnose(cut.record, cut.start, o));
  }
  std::vector<FeedCut> cuts;
  for (std::size_t i = 0; i < feeds_um.size(); ++i) {
    cuts.push_back({"f_t " + std::to_string(feeds_um[i]), feeds_um[i], &s.diagnoses[i]});
  }
  s.across = across_feeds(cuts);
  std::printf("%s hidden: %s\n  %s\n", hidden.c_str(), s.across.verdict.c_str(),
              s.across.trend.sentence.c_str());
  for (const auto& c : s.across.cuts) {
    std::printf(
        "  f_t %.1f um: before %.4f, %.4f N (spindle %.4f tooth %.4f rest %.4f; excess %.4f) "
        "after %.4f, %.4f N; floor %.4f; named %s\n",
        c.feed_per_tooth_um, c.before.total_N[0], c.before.total_N[1],
        c.before.spindle_harmonics_N[0], c.before.tooth_harmonics_N[0], c.before.rest_N[0],
        c.before.excess_N, c.after.total_N[0], c.after.total_N[1], c.noise_floor_N[0],
        c.named_effects.empty() ? "-" : c.named_effects.front().c_str());
  }
  return s;
}

TEST(AcrossFeeds, RunoutIsAFixedChipErrorIndependentOfFeed) {
  const Sweep s = sweep("runout", {1.0, 2.0, 4.0});
  ASSERT_EQ(s.across.cuts.size(), 3U);
  EXPECT_EQ(s.across.trend.name, "independent_of_feed") << s.across.trend.sentence;
  EXPECT_EQ(s.across.trend.band, "spindle_harmonics");
  EXPECT_TRUE(s.across.trend.has_sigma);
  ASSERT_EQ(s.across.named_in_every_cut.size(), 1U) << s.across.verdict;
  EXPECT_EQ(s.across.named_in_every_cut.front(), "runout");
  EXPECT_TRUE(s.across.shrinks_in_every_cut);
  for (const auto& c : s.across.cuts) {
    for (std::size_t a = 0; a < 2; ++a) {
      EXPECT_LT(c.after.total_N[a], 0.2 * c.before.total_N[a]) << c.name;
      EXPECT_LE(c.after.total_N[a], 1.3 * c.noise_floor_N[a]) << c.name;
    }
  }
}

TEST(AcrossFeeds, PloughingIsAFixedForceAtTheToothPasses) {
  // h_min 1 µm: at 1 µm per tooth every chip is below it (all ploughing), at 4 µm only near
  // entry and exit. The edge's ploughing force does not scale with the chip: the starting
  // model's error is of fixed size, in the tooth-passing harmonics, and weighs more at small
  // feeds — unlike runout's (spindle harmonics) and a coefficient error's (proportional).
  const Sweep s = sweep("min_chip_thickness", {1.0, 2.0, 4.0});
  ASSERT_EQ(s.across.cuts.size(), 3U);
  EXPECT_NE(s.across.trend.name, "proportional_to_feed") << s.across.trend.sentence;
  EXPECT_NE(s.across.trend.name, "at_noise_floor") << s.across.trend.sentence;
  EXPECT_EQ(s.across.trend.band, "tooth_passing_harmonics");
  EXPECT_LT(s.across.trend.relative_exponent, 0.0) << s.across.trend.sentence;
  EXPECT_NE(s.across.trend.suggests.find("min_chip_thickness"), std::string::npos);
  EXPECT_TRUE(s.across.shrinks_in_every_cut);
  ASSERT_EQ(s.across.named_in_every_cut.size(), 1U) << s.across.verdict;
  EXPECT_EQ(s.across.named_in_every_cut.front(), "min_chip_thickness");
  for (const auto& c : s.across.cuts) {
    for (std::size_t a = 0; a < 2; ++a) {
      EXPECT_LE(c.after.total_N[a], 1.3 * c.noise_floor_N[a]) << c.name;
    }
  }
  // After the diagnosis nothing stands above the noise in any cut.
  EXPECT_EQ(s.across.trend_after.name, "at_noise_floor") << s.across.trend_after.sentence;
}

TEST(FeedTrend, ReadsTheExponentOfAnAnalyticSeries) {
  const std::vector<double> f = {1.0, 2.0, 4.0, 8.0};
  const std::vector<double> floor(4, 0.01);
  auto series = [&](double scale, double n) {
    std::vector<double> e;
    for (const double x : f) {
      e.push_back(scale * std::pow(x, n));
    }
    return e;
  };
  const std::vector<double> measured = series(1.0, 0.7);  // F ∝ h^(1−a), a = 0.3
  auto t = feed_trend(f, series(0.5, 1.0), floor, measured, "tooth_passing_harmonics");
  EXPECT_EQ(t.name, "proportional_to_feed");
  EXPECT_NEAR(t.exponent, 1.0, 1e-12);
  EXPECT_NEAR(t.relative_exponent, 0.3, 1e-12);
  EXPECT_NEAR(t.exponent_sigma, 0.0, 1e-9);
  EXPECT_NE(t.suggests.find("riding on the force"), std::string::npos) << t.suggests;
  // Its share of the force growing as the feed (f_t^1.7 over a force ∝ f_t^0.7): the tooth path.
  t = feed_trend(f, series(0.05, 1.7), floor, measured, "tooth_passing_harmonics");
  EXPECT_EQ(t.name, "proportional_to_feed");
  EXPECT_NEAR(t.relative_exponent, 1.0, 1e-12);
  EXPECT_NE(t.suggests.find("trochoidal_path"), std::string::npos) << t.suggests;
  t = feed_trend(f, series(0.5, -0.3), floor, measured, "spindle_harmonics");
  EXPECT_EQ(t.name, "independent_of_feed");
  EXPECT_NEAR(t.exponent, -0.3, 1e-12);
  EXPECT_NE(t.suggests.find("runout"), std::string::npos) << t.suggests;
  t = feed_trend(f, series(0.5, -1.0), floor, measured, "tooth_passing_harmonics");
  EXPECT_EQ(t.name, "grows_as_feed_falls");
  // Scatter about the line gives σ: e ∝ f^0 with ±10 % alternating.
  t = feed_trend(f, {0.11, 0.09, 0.11, 0.09}, floor, measured, "rest");
  EXPECT_EQ(t.name, "independent_of_feed");
  EXPECT_GT(t.exponent_sigma, 0.01);
  EXPECT_LT(std::fabs(t.exponent), 3.0 * t.exponent_sigma);
  // At the noise floor everywhere: no trend is read.
  t = feed_trend(f, {0.0, 0.004, 0.0, 0.0}, floor, measured, "rest");
  EXPECT_EQ(t.name, "at_noise_floor");
  // One feed: none either; two: an exponent without σ.
  t = feed_trend({2.0, 2.0}, {0.1, 0.2}, {0.01, 0.01}, {1.0, 1.0}, "rest");
  EXPECT_EQ(t.name, "one_feed");
  EXPECT_FALSE(t.has_exponent);
  t = feed_trend({1.0, 4.0}, {0.4, 0.1}, {0.01, 0.01}, {1.0, 1.0}, "rest");
  EXPECT_TRUE(t.has_exponent);
  EXPECT_FALSE(t.has_sigma);
  EXPECT_NEAR(t.exponent, -1.0, 1e-12);
  // The sentence people read says the exponent has no σ, and why (it had given f_t^-1.00 bare).
  EXPECT_EQ(t.sentence.rfind("The residual above the noise varies as f_t^-1.00 (no σ: two cuts are "
                             "a line through two points; a third cut gives one) over 1–4 µm",
                             0),
            0u)
      << t.sentence;
}

TEST(AcrossFeeds, BadInputIsNamed) {
  Diagnosis failed;
  failed.message = "too short";
  EXPECT_THROW(across_feeds({{"a", 2.0, &failed}}), std::invalid_argument);
  EXPECT_THROW(across_feeds({}), std::invalid_argument);
  Diagnosis ok;
  ok.ok = true;
  try {
    (void)across_feeds({{"a.csv", 2.0, &ok}, {"b.csv", -1.0, &ok}});
    ADD_FAILURE() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("cut 2 (b.csv)"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace millwatch::diagnose
