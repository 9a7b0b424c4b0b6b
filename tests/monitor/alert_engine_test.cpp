#include "core/monitor/alert_engine.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "core/config/json_reader.hpp"
#include "core/identify/identifier.hpp"
#include "core/monitor/input_check.hpp"
#include "core/monitor/revolution_record.hpp"
#include "tests/support/allocation_counter.hpp"

namespace millwatch::monitor {
namespace {

constexpr std::int64_t kRevolution_us = 2376;  // 25,252 rpm

using Forces = std::array<double, kMaxFlutes>;

/// A valid revolution whose flutes' force ranges have lengths `force_N` (in the x–y plane).
RevolutionRecord revolution(std::int64_t n, int flutes, const Forces& force_N) {
  RevolutionRecord r;
  r.revolution = n;
  r.utime_us = n * kRevolution_us;
  r.measured.valid = true;
  r.measured.bounded = true;
  r.measured.flutes = flutes;
  for (int j = 0; j < flutes; ++j) {
    const auto i = static_cast<std::size_t>(j);
    r.measured.range_N[i] = {0.8 * force_N[i], 0.6 * force_N[i], 0.0};
    r.measured.peak_resultant_N[i] = force_N[i];
  }
  return r;
}

/// Feeds revolutions to an engine and keeps what it raises and clears.
struct Feed {
  explicit Feed(const AlertConfig& c = {}, std::uint64_t seed = 1) : engine(c), rng(seed) {}

  AlertEngine engine;
  std::vector<Alert> alerts;
  std::int64_t next = 0;
  std::mt19937_64 rng;
  std::normal_distribution<double> normal{0.0, 1.0};
  Forces noise{};    // AR(1) state per flute, relative
  double rpm = 0.0;  // the revolutions' speed (0: not known)

  void feed(int flutes, const Forces& force_N) {
    RevolutionRecord r = revolution(next++, flutes, force_N);
    r.spindle_rpm = rpm;
    engine.on_revolution(r, [&](const Alert& a) { alerts.push_back(a); });
  }
  /// `count` revolutions of flute forces level·(1 + e), e an AR(1) per flute with lag-1
  /// correlation rho and stationary σ `sigma` (relative).
  void noisy(int count, int flutes, const Forces& level_N, double sigma, double rho = 0.0) {
    const double innovation = sigma * std::sqrt(1.0 - rho * rho);
    for (int n = 0; n < count; ++n) {
      Forces f{};
      for (std::size_t j = 0; j < static_cast<std::size_t>(flutes); ++j) {
        noise[j] = rho * noise[j] + innovation * normal(rng);
        f[j] = level_N[j] * (1.0 + noise[j]);
      }
      feed(flutes, f);
    }
  }
  [[nodiscard]] int count(AlertKind kind, bool active) const {
    return static_cast<int>(std::count_if(alerts.begin(), alerts.end(), [&](const Alert& a) {
      return a.kind == kind && a.active == active;
    }));
  }
  [[nodiscard]] const Alert* first(AlertKind kind, bool active = true) const {
    for (const auto& a : alerts) {
      if (a.kind == kind && a.active == active) {
        return &a;
      }
    }
    return nullptr;
  }
  [[nodiscard]] int change_alarms() const {
    return count(AlertKind::kRunoutChange, true) + count(AlertKind::kWearDrift, true) +
           count(AlertKind::kBreakage, true);
  }
};

int baseline_revolutions(const AlertConfig& c) {
  return c.block_revolutions * c.baseline_blocks;
}

/// The two numbers around the arrow of a message ("… a % → b % …" or "a N → b N").
std::pair<double, double> before_after(const Alert& a, const char* format) {
  double before = NAN, after = NAN;
  const std::string text(a.message.data());
  const auto colon = text.find(": ");
  EXPECT_EQ(std::sscanf(text.c_str() + colon + 2, format, &before, &after), 2) << text;
  return {before, after};
}

TEST(AlertConfig, JsonRoundTripAndFieldNamedErrors) {
  AlertConfig c;
  c.block_revolutions = 30;
  c.runout_change_min = 0.05;
  c.false_alarm_revolutions = 1e8;
  const AlertConfig back = alert_config_from_json(to_json(c), "alerts");
  EXPECT_EQ(to_json(back), to_json(c));
  EXPECT_EQ(to_json(alert_config_from_json(nlohmann::json::object(), "alerts")),
            to_json(AlertConfig{}));

  auto error_of = [](const nlohmann::json& j) {
    try {
      alert_config_from_json(j, "alerts");
    } catch (const config::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error_of({{"cusum_k", -1.0}}).find("alerts.cusum_k: value -1"), std::string::npos);
  EXPECT_NE(error_of({{"false_alarm_revolutions", 10.0}}).find("alerts.false_alarm_revolutions"),
            std::string::npos);
  EXPECT_NE(error_of({{"block_revolutions", 0}}).find("alerts.block_revolutions"),
            std::string::npos);
  // The CUSUM's threshold is no longer a setting: it follows from the false-alarm rate.
  EXPECT_NE(error_of({{"cusum_threshold_sigma", 8.0}}).find("unknown key"), std::string::npos);
  // The limits on the estimates.
  AlertConfig e;
  e.runout_feed_fraction = 0.7;
  e.estimate_windows = 3;
  e.coefficient_increase = 0.2;
  e.runout_step_revolutions = 4;
  EXPECT_EQ(to_json(alert_config_from_json(to_json(e), "alerts")), to_json(e));
  EXPECT_NE(error_of({{"runout_feed_fraction", 0.0}}).find("alerts.runout_feed_fraction: value 0"),
            std::string::npos);
  EXPECT_NE(error_of({{"estimate_windows", 0}}).find("alerts.estimate_windows"), std::string::npos);
  EXPECT_NE(error_of({{"estimate_baseline_windows", 65}}).find("alerts.estimate_baseline_windows"),
            std::string::npos);
  EXPECT_NE(error_of({{"runout_step_revolutions", 33}}).find("alerts.runout_step_revolutions"),
            std::string::npos);
  EXPECT_NE(error_of({{"runout_change_min_um", -0.1}}).find("alerts.runout_change_min_um"),
            std::string::npos);
}

// The design on noise alone: 2 flutes at 6 % imbalance with 2 % noise per flute and revolution,
// independent and AR(1) with ρ = 0.8 between revolutions; 3 flutes likewise. Defaults: one
// false alarm per 10⁷ revolutions and detector, so none in 4·10⁵.
TEST(AlertEngine, NoFalseAlarmOnLongNoiseOnlySequences) {
  for (const double rho : {0.0, 0.8}) {
    Feed two({}, 11);
    two.noisy(400000, 2, {1.03, 0.97}, 0.02, rho);
    EXPECT_EQ(two.change_alarms(), 0) << "rho " << rho;
    EXPECT_EQ(two.count(AlertKind::kRunout, true), 0);
    Feed three({}, 12);
    three.noisy(200000, 3, {1.0, 0.9, 0.8}, 0.02, rho);
    EXPECT_EQ(three.change_alarms(), 0) << "rho " << rho;
  }
}

// The empirical false-alarm rate against the documented ARL₀, with the design's safety margins
// taken away (no minimum relevant change, no baseline margin, a long baseline) and the wear
// limit at zero, so that both CUSUMs run at their design point: ARL₀ = 20,000 revolutions.
// With the margins on (the defaults) the rate is far lower.
TEST(AlertEngine, EmpiricalFalseAlarmRateMatchesTheDesign) {
  AlertConfig c;
  c.false_alarm_revolutions = 2e4;
  c.runout_change_min = 0.0;
  c.baseline_margin = 0.0;
  c.baseline_blocks = 400;
  c.wear_increase = 1e-9;
  for (const double rho : {0.0, 0.6}) {
    int change = 0, wear = 0;
    std::int64_t monitored = 0;
    for (int engine = 0; engine < 8; ++engine) {
      Feed run(c, 100 + static_cast<std::uint64_t>(engine));
      run.noisy(baseline_revolutions(c) + 150000, 2, {1.03, 0.97}, 0.02, rho);
      change += run.count(AlertKind::kRunoutChange, true);
      wear += run.count(AlertKind::kWearDrift, true);
      monitored += 150000;
    }
    const double expected = static_cast<double>(monitored) / c.false_alarm_revolutions;  // 60
    std::printf(
        "rho %.1f: %d runout-change and %d wear false alarms in %lld revolutions "
        "(design %.0f each)\n",
        rho, change, wear, static_cast<long long>(monitored), expected);
    // Loosely: the σ estimate is conservative (the larger of two estimates, the AR(1) long-run
    // factor), so fewer alarms than designed; never many more.
    EXPECT_LE(change, 2.0 * expected) << rho;
    EXPECT_LE(wear, 2.0 * expected) << rho;
    EXPECT_GE(change + wear, 0.05 * expected) << rho;
  }
}

// The per-revolution runout-change detector at its design point: persistence 1, no least
// change, ARL₀ 20,000 revolutions (z = 4.06 on a single revolution's share): 1.2·10⁶ monitored
// revolutions of independent noise give about 60 raises. (By default, with 2 revolutions in a
// row, the rate is the square of the single revolution's for independent noise: the Gaussian
// bound per revolution that the header documents is far on the safe side.)
TEST(AlertEngine, PerRevolutionStepDetectorFalseAlarmRateMatchesTheDesign) {
  AlertConfig c;
  c.false_alarm_revolutions = 2e4;
  c.runout_step_min = 1e-9;
  c.runout_step_revolutions = 1;
  c.runout_change_min = 1.0;  // keeps the block detector out of the count
  int raised = 0, by_block = 0;
  std::int64_t monitored = 0;
  for (int engine = 0; engine < 8; ++engine) {
    Feed run(c, 200 + static_cast<std::uint64_t>(engine));
    run.noisy(baseline_revolutions(c) + 150000, 2, {1.03, 0.97}, 0.02);
    for (const Alert& a : run.alerts) {
      if (a.kind == AlertKind::kRunoutChange && a.active) {
        const bool per_revolution =
            std::string(a.message.data()).find("1 revolutions)") != std::string::npos;
        raised += per_revolution ? 1 : 0;
        by_block += per_revolution ? 0 : 1;
      }
    }
    monitored += 150000;
  }
  const double expected = static_cast<double>(monitored) / c.false_alarm_revolutions;  // 60
  std::printf("%d per-revolution runout-change false alarms in %lld revolutions (design %.0f)\n",
              raised, static_cast<long long>(monitored), expected);
  EXPECT_EQ(by_block, 0);
  EXPECT_LE(raised, 1.5 * expected);
  EXPECT_GE(raised, 0.5 * expected);
}

// A step of the flute imbalance from 6 % to 12 % (each share by 3 % of the mean flute force,
// 1.5 times the least relevant change) trips the CUSUM in the block it falls in, and the alert
// is confirmed on the next, the first wholly after the step: within 2 blocks = 50 revolutions.
// The text states before and after.
TEST(AlertEngine, StepInImbalanceIsDetectedWithinTwoBlocks) {
  Feed run({}, 21);
  run.noisy(3010, 2, {1.03, 0.97}, 0.01);
  run.noisy(1990, 2, {1.06, 0.94}, 0.01);
  ASSERT_EQ(run.count(AlertKind::kRunoutChange, true), 1);
  const Alert& a = *run.first(AlertKind::kRunoutChange);
  std::printf("%s\n", a.message.data());
  EXPECT_GE(a.revolution, 3010);
  EXPECT_LT(a.revolution, 3010 + 50);
  EXPECT_EQ(a.severity, AlertSeverity::kWarning);
  const auto [before, after] = before_after(a, "flute imbalance %lf %% → %lf %%");
  EXPECT_NEAR(before, 6.0, 0.2) << a.message.data();
  EXPECT_NEAR(after, 12.0, 0.5) << a.message.data();
  EXPECT_NEAR(a.value, 0.12, 0.005);
  EXPECT_NEAR(a.threshold, 0.06, 0.002);
  EXPECT_NE(std::string(a.message.data()).find("baseline 6."), std::string::npos);
  EXPECT_NE(std::string(a.message.data()).find("revolutions)"), std::string::npos);
  EXPECT_EQ(run.change_alarms(), 1);  // no wear, no breakage
  // A 0.5 % change of the shares (1 % of imbalance) is below the least relevant change.
  Feed small({}, 22);
  small.noisy(3000, 2, {1.03, 0.97}, 0.01);
  small.noisy(50000, 2, {1.035, 0.965}, 0.01);
  EXPECT_EQ(small.change_alarms(), 0);
}

// A large step of the shares (flute 0 from +3 % to +20 % of the mean flute force, 2 % noise)
// is raised per revolution: at the step's second revolution (runout_step_revolutions = 2), with
// the imbalance before and after; a step below runout_step_min (+3 % → +7 %) is not raised per
// revolution but by the block CUSUM, blocks later.
TEST(AlertEngine, LargeStepIsRaisedWithinRevolutions) {
  Feed run({}, 25);
  run.noisy(600, 2, {1.03, 0.97}, 0.02);
  run.noisy(100, 2, {1.20, 0.80}, 0.02);
  ASSERT_EQ(run.count(AlertKind::kRunoutChange, true), 1);
  const Alert& a = *run.first(AlertKind::kRunoutChange);
  std::printf("%s\n", a.message.data());
  EXPECT_EQ(a.revolution, 601);
  const auto [before, after] = before_after(a, "flute imbalance %lf %% → %lf %%");
  EXPECT_NEAR(before, 6.0, 0.5);
  EXPECT_NEAR(after, 40.0, 4.0);  // two revolutions' mean
  EXPECT_NE(std::string(a.message.data()).find("2 revolutions)"), std::string::npos);
  EXPECT_EQ(run.count(AlertKind::kRunoutChange, false), 0);  // the step stays

  Feed small({}, 26);
  small.noisy(600, 2, {1.03, 0.97}, 0.01);
  small.noisy(300, 2, {1.07, 0.93}, 0.01);
  ASSERT_EQ(small.count(AlertKind::kRunoutChange, true), 1);
  EXPECT_GE(small.first(AlertKind::kRunoutChange)->revolution, 600 + 25);
  EXPECT_NE(std::string(small.first(AlertKind::kRunoutChange)->message.data()).find("over 25"),
            std::string::npos);
}

// Without a least relevant change the detector is the CUSUM alone: for a shift of 1.5 σ (of a
// block median) from the engine's own baseline, the mean delay agrees with Siegmund's ARL₁ for
// the engine's k and h. (Measured from the true level instead, the delay also carries the
// baseline's error: a baseline 2 standard errors high makes a 1.5 σ shift look like 1.05 σ,
// below the allowance with its margin — the price of the false-alarm guarantee.)
TEST(AlertEngine, StatisticalDetectionDelayAgreesWithSiegmund) {
  AlertConfig c;
  c.runout_change_min = 0.0;
  const int trials = 40;
  double delay_blocks = 0.0;
  double predicted = 0.0;
  for (int trial = 0; trial < trials; ++trial) {
    Feed run(c, 300 + static_cast<std::uint64_t>(trial));
    run.noisy(baseline_revolutions(c), 2, {1.03, 0.97}, 0.02);
    const AlertEngine::Baseline& b = run.engine.baseline();
    ASSERT_TRUE(b.ready);
    const double share = b.share[0] + 1.5 * b.share_sigma[0];  // flute 0's share after
    predicted = cusum_average_run_length(b.change_allowance[0], b.change_threshold[0], 1.5);
    const std::int64_t start = run.next;
    while (run.count(AlertKind::kRunoutChange, true) == 0 && run.next < start + 200000) {
      run.noisy(c.block_revolutions, 2, {1.0 + share, 1.0 - share}, 0.02);
    }
    ASSERT_EQ(run.count(AlertKind::kRunoutChange, true), 1);
    delay_blocks += static_cast<double>(run.next - start) / c.block_revolutions / trials;
  }
  std::printf("1.5 sigma shift: mean delay %.1f blocks, Siegmund %.1f\n", delay_blocks, predicted);
  EXPECT_NEAR(delay_blocks, predicted, 0.25 * predicted);
}

// A 20 % rise of every flute's force raises wear drift once the rise passes the 15 % limit;
// 10 % raises nothing; back at the baseline it clears (once).
TEST(AlertEngine, TwentyPercentRiseOfFluteForceRaisesWearDrift) {
  Feed run({}, 31);
  run.noisy(1000, 2, {1.03, 0.97}, 0.01);
  for (int n = 0; n < 4000; ++n) {  // a ramp to +20 % over 4,000 revolutions
    const double g = 1.0 + 0.2 * n / 4000.0;
    run.noisy(1, 2, {1.03 * g, 0.97 * g}, 0.01);
  }
  run.noisy(2000, 2, {1.03 * 1.2, 0.97 * 1.2}, 0.01);
  ASSERT_EQ(run.count(AlertKind::kWearDrift, true), 1);
  const Alert& a = *run.first(AlertKind::kWearDrift);
  std::printf("%s\n", a.message.data());
  const auto [before, after] = before_after(a, "mean flute force %lf N → %lf N");
  EXPECT_NEAR(before, 1.0, 0.005) << a.message.data();
  EXPECT_GT(after, 1.15) << a.message.data();
  EXPECT_LT(after, 1.17) << a.message.data();
  EXPECT_GT(a.value, 0.15);
  EXPECT_EQ(a.threshold, 0.15);
  EXPECT_NE(std::string(a.message.data()).find("limit +15.0 %"), std::string::npos);
  // The ramp crosses 15 % at revolution 4,000; raised within 10 blocks after.
  EXPECT_GT(a.revolution, 4000);
  EXPECT_LT(a.revolution, 4250);
  EXPECT_EQ(run.count(AlertKind::kRunoutChange, true), 0);  // all flutes alike: shares unchanged
  run.noisy(3000, 2, {1.03, 0.97}, 0.01);
  EXPECT_EQ(run.count(AlertKind::kWearDrift, false), 1);
  EXPECT_EQ(run.count(AlertKind::kWearDrift, true), 1);

  Feed ten({}, 32);
  ten.noisy(1000, 2, {1.03, 0.97}, 0.01);
  ten.noisy(50000, 2, {1.03 * 1.1, 0.97 * 1.1}, 0.01);
  EXPECT_EQ(ten.change_alarms(), 0);
}

// Flute 1 of 3 collapses to 5 % of its force: breakage (an alarm) exactly when the collapse has
// lasted persist_revolutions; healed, it clears once.
TEST(AlertEngine, CollapsingFluteRaisesBreakageWithinItsPersistence) {
  Feed run({}, 41);
  run.noisy(2000, 3, {1.0, 0.9, 0.8}, 0.02);
  run.noisy(100, 3, {1.0, 0.045, 0.8}, 0.02);
  ASSERT_EQ(run.count(AlertKind::kBreakage, true), 1);
  const Alert& a = *run.first(AlertKind::kBreakage);
  std::printf("%s\n", a.message.data());
  EXPECT_EQ(a.revolution, 2000 + AlertConfig{}.persist_revolutions - 1);
  EXPECT_EQ(a.severity, AlertSeverity::kAlarm);
  EXPECT_NEAR(a.value, 0.05, 0.01);
  EXPECT_EQ(a.threshold, 0.3);
  int flute = -1;
  double now = NAN, before = NAN;
  EXPECT_EQ(std::sscanf(a.message.data(),
                        "breakage: flute %d cuts %lf %% of the strongest flute's force (baseline "
                        "%lf %%)",
                        &flute, &now, &before),
            3)
      << a.message.data();
  EXPECT_EQ(flute, 2);  // counted from 1, as the summary's table and runout high count them
  EXPECT_NEAR(now, 4.5, 0.5);
  EXPECT_NEAR(before, 90.0, 0.5);
  // A collapse is breakage: the per-revolution runout-change detector waits for it.
  EXPECT_EQ(run.count(AlertKind::kRunoutChange, true), 0);
  run.noisy(100, 3, {1.0, 0.9, 0.8}, 0.02);
  EXPECT_EQ(run.count(AlertKind::kBreakage, false), 1);
  EXPECT_EQ(run.count(AlertKind::kBreakage, true), 1);
  // A flute that loses half its force is chipped, not broken.
  Feed chipped({}, 42);
  chipped.noisy(2000, 3, {1.0, 0.9, 0.8}, 0.02);
  chipped.noisy(2000, 3, {1.0, 0.45, 0.8}, 0.02);
  EXPECT_EQ(chipped.count(AlertKind::kBreakage, true), 0);
  EXPECT_EQ(chipped.count(AlertKind::kRunoutChange, true), 1);
}

/// Two flutes cutting f_t ± 1 µm (a radius difference of 2 µm), K N per µm, at a fixed feed rate
/// of 4 µm/tooth at 25,000 rpm: f_t = 4·25,000/n.
Forces two_flutes_at(double rpm, double radius_difference_um = 2.0, double k_N_per_um = 0.25) {
  const double feed_um = 4.0 * 25000.0 / rpm;
  return {k_N_per_um * (feed_um + 0.5 * radius_difference_um),
          k_N_per_um * (feed_um - 0.5 * radius_difference_um)};
}

// The spindle slows from 25,000 to 20,000 rpm at a fixed feed rate (f_t 4 → 5 µm): the flutes'
// shares move from ±25 % to ±20 % and the mean force rises 25 %, with the runout and the tool
// unchanged. Told the speed, the engine holds its flute-force detectors (no runout change, no
// wear drift), counts the held revolutions, forms a new baseline at 20,000 rpm once the speed
// holds, and then still raises a real change of the runout. Without the speed (the control) the
// same revolutions raise both false alarms. A short excursion returns to the old baseline, and
// a flute that breaks while the speed is off is still an alarm.
TEST(AlertEngine, ASpeedChangeHoldsTheFluteForceDetectorsAndStartsABaselineThere) {
  const AlertConfig config;
  const int baseline = baseline_revolutions(config);
  const auto ramp = [](Feed& run, bool told) {
    run.rpm = told ? 25000.0 : 0.0;
    run.noisy(1000, 2, two_flutes_at(25000.0), 0.01);
    for (int n = 0; n < 400; ++n) {
      const double rpm = 25000.0 - 5000.0 * n / 400.0;
      run.rpm = told ? rpm : 0.0;
      run.noisy(1, 2, two_flutes_at(rpm), 0.01);
    }
    run.rpm = told ? 20000.0 : 0.0;
    run.noisy(2000, 2, two_flutes_at(20000.0), 0.01);
  };
  Feed control({}, 71);
  ramp(control, false);
  EXPECT_EQ(control.count(AlertKind::kRunoutChange, true), 1);
  EXPECT_EQ(control.count(AlertKind::kWearDrift, true), 1);
  EXPECT_EQ(control.engine.held_revolutions(), 0);

  Feed run({}, 71);
  ramp(run, true);
  EXPECT_EQ(run.change_alarms(), 0);
  ASSERT_TRUE(run.engine.baseline().ready);
  EXPECT_NEAR(run.engine.baseline().spindle_rpm, 20000.0, 1.0);
  EXPECT_NEAR(run.engine.baseline().share[0], 0.20, 0.005);
  // Held: the ramp's revolutions beyond 1 % (below 25,000 · 0.99) and the new baseline's, less
  // the ramp's last ones within 1 % of 20,000 rpm (12.5 rpm a revolution: at most 16), which
  // already count towards it.
  const auto ramp_held = static_cast<std::int64_t>(400.0 * (1.0 - 250.0 / 5000.0));
  EXPECT_LE(run.engine.held_revolutions(), ramp_held + baseline);
  EXPECT_GE(run.engine.held_revolutions(), ramp_held + baseline - 17);
  // A real change at the new speed: the radius difference 2 → 2.8 µm (shares ±20 % → ±28 %).
  run.noisy(500, 2, two_flutes_at(20000.0, 2.8), 0.01);
  EXPECT_EQ(run.count(AlertKind::kRunoutChange, true), 1);

  Feed dip({}, 72);
  dip.rpm = 25000.0;
  dip.noisy(1000, 2, two_flutes_at(25000.0), 0.01);
  dip.rpm = 24000.0;
  dip.noisy(40, 2, two_flutes_at(24000.0), 0.01);
  dip.rpm = 25000.0;
  dip.noisy(2000, 2, two_flutes_at(25000.0), 0.01);
  EXPECT_EQ(dip.change_alarms(), 0);
  EXPECT_EQ(dip.engine.held_revolutions(), 40);
  EXPECT_NEAR(dip.engine.baseline().spindle_rpm, 25000.0, 1.0);

  Feed broken({}, 73);
  broken.rpm = 25000.0;
  broken.noisy(1000, 3, {1.0, 0.9, 0.8}, 0.02);
  broken.rpm = 22000.0;
  broken.noisy(100, 3, {1.1, 0.045, 0.9}, 0.02);
  EXPECT_EQ(broken.count(AlertKind::kBreakage, true), 1);
  EXPECT_EQ(broken.engine.held_revolutions(), 100);
}

// A new baseline (another tool, a re-lock) while a flute is broken clears the breakage, with the
// figures it was raised on: the new tool has none yet.
TEST(AlertEngine, BreakageClearedByANewBaselineKeepsItsFigures) {
  Feed run({}, 43);
  run.noisy(2000, 3, {1.0, 0.9, 0.8}, 0.02);
  run.noisy(100, 3, {1.0, 0.045, 0.8}, 0.02);
  ASSERT_EQ(run.count(AlertKind::kBreakage, true), 1);
  run.engine.rebaseline();
  run.noisy(1, 3, {1.0, 0.9, 0.8}, 0.02);
  ASSERT_EQ(run.count(AlertKind::kBreakage, false), 1);
  const Alert& raised = *run.first(AlertKind::kBreakage, true);
  const Alert& cleared = *run.first(AlertKind::kBreakage, false);
  EXPECT_EQ(cleared.revolution, 2100);
  EXPECT_EQ(cleared.quantity, "flute_strength_fraction_of_baseline");
  EXPECT_NEAR(cleared.value, 0.05, 0.01);
  EXPECT_EQ(cleared.threshold, 0.3);
  EXPECT_EQ(cleared.value, raised.value);
  EXPECT_NE(std::string(cleared.message.data())
                .find("breakage cleared: new baseline (raised on flute_strength_fraction_of_"
                      "baseline 0.0"),
            std::string::npos)
      << cleared.message.data();
}

/// A revolution measured from samples as the revolution meter does: each flute's force pulse
/// F_j·sin(πu) along a direction, plus channel offsets and white noise; peaks are the samples
/// of largest magnitude, ranges max − min.
RevolutionRecord sampled_revolution(std::int64_t n, const std::array<double, 2>& force_N,
                                    const std::array<double, 3>& offset_N, std::mt19937_64& rng) {
  std::normal_distribution<double> noise(0.0, 0.005);
  RevolutionRecord r = revolution(n, 2, {});
  constexpr int kSamples = 60;
  for (std::size_t j = 0; j < 2; ++j) {
    std::array<double, 3> lo{}, hi{}, peak{};
    double peak_resultant = 0.0;
    for (int s = 0; s <= kSamples; ++s) {
      const double pulse = force_N[j] * std::sin(std::numbers::pi * s / kSamples);
      const std::array<double, 3> f = {-0.9 * pulse + offset_N[0] + noise(rng),
                                       0.5 * pulse + offset_N[1] + noise(rng),
                                       -0.2 * pulse + offset_N[2] + noise(rng)};
      for (std::size_t a = 0; a < 3; ++a) {
        lo[a] = s == 0 ? f[a] : std::min(lo[a], f[a]);
        hi[a] = s == 0 ? f[a] : std::max(hi[a], f[a]);
        peak[a] = std::fabs(f[a]) > std::fabs(peak[a]) ? f[a] : peak[a];
      }
      peak_resultant = std::max(peak_resultant, std::hypot(f[0], f[1], f[2]));
    }
    for (std::size_t a = 0; a < 3; ++a) {
      r.measured.range_N[j][a] = hi[a] - lo[a];
    }
    r.measured.peak_N[j] = peak;
    r.measured.peak_resultant_N[j] = peak_resultant;
  }
  return r;
}

// Charge-amplifier drift: offsets growing linearly on every channel to (0.4, −0.3, 0.2) N over
// 20,000 revolutions of a 1 N cut. The peak forces (and their imbalance) move by far more than
// the change and wear limits; the range-based flute forces do not, and nothing is raised.
TEST(AlertEngine, ChannelOffsetDriftAloneRaisesNothing) {
  AlertEngine engine;
  std::vector<Alert> alerts;
  std::mt19937_64 rng(51);
  const int total = 20000;
  double peak_mean_first = 0.0, peak_mean_last = 0.0, imbalance_first = 0.0, imbalance_last = 0.0;
  for (int n = 0; n < total; ++n) {
    const double g = static_cast<double>(n) / total;
    const RevolutionRecord r = sampled_revolution(n, {1.0, 0.9}, {0.4 * g, -0.3 * g, 0.2 * g}, rng);
    engine.on_revolution(r, [&](const Alert& a) { alerts.push_back(a); });
    const auto& p = r.measured.peak_resultant_N;
    const double mean = 0.5 * (p[0] + p[1]);
    const double imbalance = std::fabs(p[0] - p[1]) / mean;
    if (n < 1000) {
      peak_mean_first += mean / 1000;
      imbalance_first += imbalance / 1000;
    } else if (n >= total - 1000) {
      peak_mean_last += mean / 1000;
      imbalance_last += imbalance / 1000;
    }
  }
  // The drift is large in what the old detectors watched…
  EXPECT_GT(std::fabs(peak_mean_last / peak_mean_first - 1.0), 0.2);
  EXPECT_GT(std::fabs(imbalance_last - imbalance_first), 0.05);
  // …and raises nothing here.
  for (const auto& a : alerts) {
    ADD_FAILURE() << a.message.data();
  }
}

// Hysteresis: the runout alert with the imbalance hovering about its limit is raised once and
// cleared once; so is a runout change that comes and goes.
TEST(AlertEngine, AlertsAreRaisedOnceAndClearedOnce) {
  Feed run({}, 61);
  // Flute forces 1 ± x/2: imbalance x; noise of 1 % per flute gives the imbalance σ ≈ 1.4 %.
  auto at_imbalance = [](double x) { return Forces{1.0 + 0.5 * x, 1.0 - 0.5 * x}; };
  run.noisy(1000, 2, at_imbalance(0.20), 0.01);
  run.noisy(2000, 2, at_imbalance(0.27), 0.01);  // just above 25 %: dips below now and then
  run.noisy(2000, 2, at_imbalance(0.19), 0.01);  // just below 0.8·25 %
  EXPECT_EQ(run.count(AlertKind::kRunout, true), 1);
  EXPECT_EQ(run.count(AlertKind::kRunout, false), 1);
  const Alert& cleared = *run.first(AlertKind::kRunout, false);
  EXPECT_EQ(cleared.severity, AlertSeverity::kInfo);
  EXPECT_NE(std::string(cleared.message.data()).find("runout cleared: flute imbalance 1"),
            std::string::npos);
  // The same sequence moved the imbalance 20 % → 27 % → 19 %: one runout change raised, and
  // cleared when it came back within the allowance.
  EXPECT_EQ(run.count(AlertKind::kRunoutChange, true), 1);
  EXPECT_EQ(run.count(AlertKind::kRunoutChange, false), 1);
  EXPECT_EQ(run.count(AlertKind::kWearDrift, true), 0);
  EXPECT_EQ(run.count(AlertKind::kBreakage, true), 0);
}

TEST(AlertEngine, RebaselineClearsChangeAlertsAndAcceptsTheNewLevel) {
  Feed run({}, 71);
  run.noisy(1000, 2, {1.03, 0.97}, 0.01);
  run.noisy(1000, 2, {1.08, 0.92}, 0.01);
  ASSERT_EQ(run.count(AlertKind::kRunoutChange, true), 1);
  run.engine.rebaseline();
  run.noisy(1, 2, {1.08, 0.92}, 0.01);
  ASSERT_EQ(run.count(AlertKind::kRunoutChange, false), 1);
  // The new baseline has no figure yet: the clear repeats what the alert was raised on, not 0.
  const Alert& raised = *run.first(AlertKind::kRunoutChange, true);
  const Alert& cleared = *run.first(AlertKind::kRunoutChange, false);
  EXPECT_NE(std::string(cleared.message.data()).find("cleared: new baseline"), std::string::npos)
      << cleared.message.data();
  EXPECT_EQ(cleared.quantity, raised.quantity);
  EXPECT_EQ(cleared.value, raised.value);
  EXPECT_EQ(cleared.threshold, raised.threshold);
  EXPECT_NEAR(cleared.value, 0.16, 0.03);  // the imbalance 8 % − (−8 %) it was raised on
  run.noisy(20000, 2, {1.08, 0.92}, 0.01);
  EXPECT_EQ(run.count(AlertKind::kRunoutChange, true), 1);
  EXPECT_NEAR(run.engine.baseline().share[0], 0.08, 0.003);
}

/// An engine fed input counters alone, and the alerts it gave.
struct InputRun {
  AlertEngine engine;
  std::vector<Alert> alerts;
  InputCounters c;
  void input(std::int64_t samples_in, std::int64_t utime_us) {
    c.samples_in = samples_in;
    engine.on_input(c, utime_us, [this](const Alert& a) { alerts.push_back(a); });
  }
};

TEST(AlertEngine, SensorTroubleIsRaisedAndClearedWithItsFigures) {
  InputRun run;
  run.input(25000, 0);
  run.c.samples_flagged = 100;
  run.c.gaps = 1;
  run.input(50000, 500000);
  run.input(75000, 1000000);
  const std::vector<Alert>& alerts = run.alerts;
  ASSERT_EQ(alerts.size(), 2u);
  EXPECT_TRUE(alerts[0].active);
  // Before any revolution: not revolution 0, which is the first revolution's number.
  EXPECT_EQ(alerts[0].revolution, -1);
  EXPECT_EQ(alerts[0].utime_us, 500000);
  EXPECT_NE(std::string(alerts[0].message.data()).find("0.400 % of recent samples"),
            std::string::npos)
      << alerts[0].message.data();
  EXPECT_EQ(alerts[0].quantity, "bad_sample_fraction");  // above its limit: what raised it
  EXPECT_DOUBLE_EQ(alerts[0].value, 0.004);
  EXPECT_FALSE(alerts[1].active);
}

// A dead in-plane channel is sensor trouble that names the channel: raised on its own, and said
// again when the alert stood already for a gap (it had kept the gap's text alone); cleared once
// the channel carries force again and the input is clean.
TEST(AlertEngine, ADeadChannelIsSensorTroubleNamingIt) {
  InputRun run;
  run.c.gaps = 1;
  run.input(25000, 0);  // raised for the gap
  run.engine.set_dead_channel(1, 0.004, 0.02);
  run.input(50000, 500000);   // said again, naming fy
  run.input(75000, 1000000);  // nothing new
  run.engine.set_dead_channel(-1, 0.6, 0.02);
  run.input(100000, 1500000);  // cleared
  const std::vector<Alert>& alerts = run.alerts;
  ASSERT_EQ(alerts.size(), 3u);
  EXPECT_TRUE(alerts[0].active);
  EXPECT_EQ(std::string(alerts[0].message.data()).find("fy"), std::string::npos);
  // Each states the quantity that raised it (both had stated the bad samples' share, 0, under
  // its limit): the gaps, then the dead channel's range against the other's.
  EXPECT_EQ(alerts[0].quantity, "new_gaps");
  EXPECT_EQ(alerts[0].value, 1.0);
  EXPECT_EQ(alerts[0].threshold, 0.0);
  EXPECT_TRUE(alerts[1].active);
  EXPECT_EQ(alerts[1].quantity, "sync_range_ratio");
  EXPECT_EQ(alerts[1].value, 0.004);
  EXPECT_EQ(alerts[1].threshold, 0.02);
  EXPECT_NE(std::string(alerts[1].message.data()).find("fy carries no cutting force while fx does"),
            std::string::npos)
      << alerts[1].message.data();
  EXPECT_FALSE(alerts[2].active);
  // The clear states the quantity the raise did (it was said again for the dead channel), as
  // it stands now.
  EXPECT_EQ(alerts[2].quantity, "sync_range_ratio");
  EXPECT_EQ(alerts[2].value, 0.6);
}

/// An identified window of a 2-flute cut (commanded 25,000 rpm, f_t as given): the radius
/// difference d = r_CE2 − r_CE1 and two coefficients, with total σ's (statistical: a fifth).
identify::IdentifiedWindow fitted(std::int64_t last_revolution, double d_um, double d_sigma_um,
                                  double k_tc, double k_te, double k_sigma_rel,
                                  double feed_um = 3.0) {
  identify::IdentifiedWindow w;
  w.revolution = last_revolution;
  w.utime_us = last_revolution * kRevolution_us;
  w.window_revolutions = 30;
  identify::FitResult& f = w.fit;
  f.ok = true;
  f.config.process.feed_per_tooth_um = feed_um;
  f.rho_um = {"rho_um", -0.5 * d_um, 0.5 * d_sigma_um, 0.1 * d_sigma_um, 0.5 * d_sigma_um};
  f.gamma_rad = {"gamma_rad", 0.0, 0.1, 0.05, 0.1};
  f.radius_from_ce1_um = {{"r_ce1_minus_r_ce1_um", 0.0, 0.0, 0.0, 0.0},
                          {"r_ce2_minus_r_ce1_um", d_um, d_sigma_um, 0.2 * d_sigma_um, 0.0}};
  f.coefficients = {{"k_tc_N_per_mm2", k_tc, k_sigma_rel * k_tc, 0.2 * k_sigma_rel * k_tc, 0.0},
                    {"k_te_N_per_mm", k_te, k_sigma_rel * k_te, 0.2 * k_sigma_rel * k_te, 0.0}};
  return w;
}

/// Feeds identified windows (no revolutions) and keeps the alerts.
struct Windows {
  explicit Windows(const AlertConfig& c = {}, std::uint64_t seed = 1) : engine(c), rng(seed) {}
  AlertEngine engine;
  std::vector<Alert> alerts;
  std::int64_t next = 29;
  std::mt19937_64 rng;
  std::normal_distribution<double> normal{0.0, 1.0};
  /// `count` windows of d (µm) and coefficients × factor, with Gaussian scatter of σ_stat.
  void feed(int count, double d_um, double d_sigma_um, double factor = 1.0, double feed_um = 3.0) {
    for (int i = 0; i < count; ++i) {
      const double k_noise = 0.01 * 0.2;  // k σ 1 % total, 0.2 % statistical
      const auto w = fitted(next, d_um + 0.2 * d_sigma_um * normal(rng), d_sigma_um,
                            1100.0 * factor * (1.0 + k_noise * normal(rng)),
                            8.0 * factor * (1.0 + k_noise * normal(rng)), 0.01, feed_um);
      engine.on_identification(w, [&](const Alert& a) { alerts.push_back(a); });
      next += 30;
    }
  }
  [[nodiscard]] int count(AlertKind kind, bool active) const {
    return static_cast<int>(std::count_if(alerts.begin(), alerts.end(), [&](const Alert& a) {
      return a.kind == kind && a.active == active;
    }));
  }
  [[nodiscard]] const Alert* first(AlertKind kind, bool active = true) const {
    for (const auto& a : alerts) {
      if (a.kind == kind && a.active == active) {
        return &a;
      }
    }
    return nullptr;
  }
};

// Runout from the estimates, on u = (r_CE1 − r_CE2)/f_t against 50 %: raised after 2 windows
// whose u − 3σ_u is above the limit, once although u hovers about it; cleared after 2 windows
// with u + 3σ_u below 40 %. An estimate above the limit by less than its 3σ raises nothing.
TEST(AlertEngine, RunoutHighFollowsTheEstimateWithItsSigmaAndHysteresis) {
  Windows w;
  w.feed(3, -0.9, 0.03);   // 30 % of f_t = 3 µm
  w.feed(2, -1.95, 0.03);  // 65 % ± 1 %
  ASSERT_EQ(w.count(AlertKind::kRunout, true), 1);
  const Alert& raised = *w.first(AlertKind::kRunout);
  std::printf("%s\n", raised.message.data());
  EXPECT_EQ(raised.revolution, 29 + 4 * 30);
  EXPECT_NEAR(raised.value, 0.65, 0.01);
  EXPECT_EQ(raised.threshold, 0.5);
  double deficit = NAN, sigma = NAN, first = NAN, now = NAN;
  ASSERT_EQ(std::sscanf(raised.message.data(),
                        "runout high: r_CE1 − r_CE2 %lf ± %lf µm = %*f ± %*f %% of f_t 3.00 µm "
                        "(first window %lf %% → %lf %%",
                        &deficit, &sigma, &first, &now),
            4)
      << raised.message.data();
  EXPECT_NEAR(deficit, 1.95, 0.03);
  EXPECT_EQ(sigma, 0.03);
  EXPECT_NEAR(first, 30.0, 1.0);
  EXPECT_NEAR(now, 65.0, 1.0);
  w.feed(4, -1.5, 0.03);   // 50 %: inside the hysteresis band
  w.feed(4, -1.65, 0.03);  // 55 %
  EXPECT_EQ(w.count(AlertKind::kRunout, true), 1);
  EXPECT_EQ(w.count(AlertKind::kRunout, false), 0);
  w.feed(1, -1.0, 0.03);  // 33 % + 3 %: below 40 %, once
  w.feed(1, -1.5, 0.03);
  w.feed(2, -1.0, 0.03);
  ASSERT_EQ(w.count(AlertKind::kRunout, false), 1);
  EXPECT_EQ(w.first(AlertKind::kRunout, false)->severity, AlertSeverity::kInfo);

  Windows unsure;
  unsure.feed(10, -1.8, 0.15);  // 60 % ± 5 %: 3σ reaches below the limit
  EXPECT_EQ(unsure.count(AlertKind::kRunout, true), 0);
}

// A fit on a flute's contact edge (FitResult::runout_at_contact_edge: a flute cuts nothing, the
// force bounds the runout from below only) raises runout high as any other, its lower bound
// above the limit; the message says ρ and the edge flute's radius difference are lower bounds
// ("≥").
TEST(AlertEngine, RunoutHighSaysWhenTheRunoutIsALowerBound) {
  AlertEngine engine;
  std::vector<Alert> alerts;
  for (int i = 0; i < 2; ++i) {
    identify::IdentifiedWindow w = fitted(29 + 30 * i, -3.0, 0.04, 1100.0, 8.0, 0.01);
    w.fit.runout_at_contact_edge = true;  // r_CE1 − r_CE2 = f_t: flute 2 just stops cutting
    w.fit.edge_flute = 1;
    engine.on_identification(w, [&](const Alert& a) { alerts.push_back(a); });
  }
  ASSERT_EQ(alerts.size(), 1u);
  const std::string message = alerts[0].message.data();
  std::printf("%s\n", message.c_str());
  EXPECT_EQ(alerts[0].kind, AlertKind::kRunout);
  EXPECT_NE(message.find("runout high: r_CE1 − r_CE2 ≥ 3.000 ± "), std::string::npos) << message;
  EXPECT_NE(message.find("; ρ ≥ 1.50 ± 0.02 µm at γ"), std::string::npos) << message;
}

// Runout change from the estimates: a step of r_CE1 − r_CE2 by 0.3 µm (above the least relevant
// 0.2 µm and far above the windows' scatter) is raised on its second window, with before → after
// in µm; back at the baseline it clears after two windows. A step of 0.15 µm raises nothing.
TEST(AlertEngine, RadiusDifferenceStepFromTheEstimates) {
  Windows w;
  w.feed(12, -0.9, 0.03);
  ASSERT_TRUE(w.engine.estimate_baseline().ready);
  EXPECT_NEAR(w.engine.estimate_baseline().radius_difference_um[1], -0.9, 0.01);
  EXPECT_EQ(w.engine.estimate_baseline().radius_limit_um[1], 0.2);
  w.feed(3, -1.2, 0.03);
  ASSERT_EQ(w.count(AlertKind::kRunoutChange, true), 1);
  const Alert& a = *w.first(AlertKind::kRunoutChange);
  std::printf("%s\n", a.message.data());
  EXPECT_EQ(a.revolution, 29 + 13 * 30);
  EXPECT_EQ(a.severity, AlertSeverity::kWarning);
  const auto [before, after] = before_after(a, "r_CE1 − r_CE2 %lf ± %*f µm → %lf");
  EXPECT_NEAR(before, 0.9, 0.01);
  EXPECT_NEAR(after, 1.2, 0.02);
  EXPECT_EQ(a.quantity, "radius_difference_um");
  w.feed(3, -0.9, 0.03);
  EXPECT_EQ(w.count(AlertKind::kRunoutChange, false), 1);

  Windows small;
  small.feed(12, -0.9, 0.03);
  small.feed(20, -1.05, 0.03);
  EXPECT_EQ(small.count(AlertKind::kRunoutChange, true), 0);
}

// Wear drift from the estimates: the coefficients ramping to +20 % over 40 windows after a
// 10-window baseline raise it once their rise passes +10 % (the first coefficient to be sure
// names itself, with before → after and units); +8 % for ever raises nothing; back at the
// baseline it clears.
TEST(AlertEngine, CoefficientRiseRaisesWearDrift) {
  Windows w;
  w.feed(10, -0.9, 0.03);
  for (int i = 1; i <= 40; ++i) {
    w.feed(1, -0.9, 0.03, 1.0 + 0.2 * i / 40.0);
  }
  ASSERT_EQ(w.count(AlertKind::kWearDrift, true), 1);
  const Alert& a = *w.first(AlertKind::kWearDrift);
  std::printf("%s\n", a.message.data());
  EXPECT_GT(a.value, 0.10);
  EXPECT_EQ(a.quantity, "coefficient_rise");
  // +10 % is reached at window 20 of the ramp (revolution 29 + 29·30 = 899).
  EXPECT_GT(a.revolution, 899);
  EXPECT_LT(a.revolution, 899 + 8 * 30);
  EXPECT_NE(std::string(a.message.data()).find("limit +10.0 %"), std::string::npos);
  const bool named = std::string(a.message.data()).find("k_tc ") != std::string::npos ||
                     std::string(a.message.data()).find("k_te ") != std::string::npos;
  EXPECT_TRUE(named) << a.message.data();
  EXPECT_NE(std::string(a.message.data()).find(" N/mm"), std::string::npos);
  w.feed(10, -0.9, 0.03, 1.0);
  EXPECT_EQ(w.count(AlertKind::kWearDrift, false), 1);
  EXPECT_EQ(w.count(AlertKind::kRunoutChange, true), 0);

  Windows eight;
  eight.feed(10, -0.9, 0.03);
  eight.feed(300, -0.9, 0.03, 1.08);
  EXPECT_EQ(eight.count(AlertKind::kWearDrift, true), 0);
}

// A coefficient the windows did not fit (no statistical σ: K_ac of the demo's power law with no
// fz compared, held by Levenberg–Marquardt at its rounding) is not wear, however steady it is in
// the baseline and however far it moves after: found on the demo replay, which raised "k_ac
// 4.8e-12 → 5.5e-11 (+1051 %)" on a steady cut.
TEST(AlertEngine, ACoefficientWithoutStatisticalSigmaRaisesNoWear) {
  AlertEngine engine;
  std::vector<Alert> alerts;
  for (int i = 0; i < 40; ++i) {
    auto w = fitted(29 + 30 * i, -0.9, 0.03, 1100.0, 8.0, 0.01);
    const double held = i < 10 ? 4.8e-12 : 5.5e-11;  // steady baseline, then ×11
    w.fit.coefficients.push_back({"k_ac_Nmm", held, 3.8e-11, 0.0, 3.8e-11});
    engine.on_identification(w, [&](const Alert& a) { alerts.push_back(a); });
  }
  for (const Alert& a : alerts) {
    std::printf("%s\n", a.message.data());
  }
  EXPECT_EQ(std::count_if(alerts.begin(), alerts.end(),
                          [](const Alert& a) { return a.kind == AlertKind::kWearDrift; }),
            0);
  // The same jump in a fitted coefficient (statistical σ 0.2 %) is wear.
  AlertEngine fitted_engine;
  std::vector<Alert> raised;
  for (int i = 0; i < 40; ++i) {
    const double k = i < 10 ? 1100.0 : 1400.0;
    fitted_engine.on_identification(fitted(29 + 30 * i, -0.9, 0.03, k, 8.0, 0.01),
                                    [&](const Alert& a) { raised.push_back(a); });
  }
  EXPECT_EQ(
      std::count_if(raised.begin(), raised.end(),
                    [](const Alert& a) { return a.kind == AlertKind::kWearDrift && a.active; }),
      1);
}

// The coefficients are compared at constant conditions: a feed 5 % higher starts a new baseline
// (no alert although the coefficients and radii come out different there).
TEST(AlertEngine, OtherConditionsStartANewEstimateBaseline) {
  Windows w;
  w.feed(12, -0.9, 0.03);
  ASSERT_TRUE(w.engine.estimate_baseline().ready);
  EXPECT_NEAR(w.engine.estimate_baseline().feed_per_tooth_um, 3.0, 1e-9);
  w.feed(3, -1.3, 0.03, 1.25, 3.15);
  EXPECT_FALSE(w.engine.estimate_baseline().ready);
  w.feed(20, -1.3, 0.03, 1.25, 3.15);
  EXPECT_TRUE(w.engine.estimate_baseline().ready);
  EXPECT_NEAR(w.engine.estimate_baseline().feed_per_tooth_um, 3.15, 1e-9);
  EXPECT_EQ(w.count(AlertKind::kRunoutChange, true), 0);
  EXPECT_EQ(w.count(AlertKind::kWearDrift, true), 0);
}

// With identification expected the flute forces' runout and wear detectors stay quiet: the 114 %
// imbalance of the runout test below raises nothing until the estimates speak.
TEST(AlertEngine, ExpectedEstimatesSilenceTheImbalanceRunout) {
  Feed run({}, 62);
  run.engine.expect_estimates();
  run.noisy(2000, 2, {1.5, 0.5}, 0.01);
  EXPECT_EQ(run.count(AlertKind::kRunout, true), 0);
  Feed without({}, 62);
  without.noisy(2000, 2, {1.5, 0.5}, 0.01);
  EXPECT_EQ(without.count(AlertKind::kRunout, true), 1);
}

// Estimates that stop coming hand runout back to the flute forces: after one identified window
// (runout 30 % of f_t) the 114 % imbalance raises nothing while estimates are followed; once the
// pipeline says they stopped (expect_estimates(false)), the imbalance raises runout within its
// persistence, and the next window takes over again (the imbalance is silent, no second alarm).
TEST(AlertEngine, EstimatesThatStopComingHandRunoutBackToTheFluteForces) {
  Feed run({}, 62);
  run.engine.expect_estimates();
  run.noisy(100, 2, {1.0, 1.0}, 0.01);
  run.engine.on_identification(fitted(99, -0.9, 0.03, 1100.0, 8.0, 0.01),
                               [&](const Alert& a) { run.alerts.push_back(a); });
  run.noisy(1000, 2, {1.5, 0.5}, 0.01);
  EXPECT_EQ(run.count(AlertKind::kRunout, true), 0);
  run.engine.expect_estimates(false);
  const std::int64_t stopped = run.next;
  run.noisy(1000, 2, {1.5, 0.5}, 0.01);
  ASSERT_EQ(run.count(AlertKind::kRunout, true), 1);
  const Alert& raised = *run.first(AlertKind::kRunout);
  EXPECT_EQ(raised.quantity, "flute_imbalance");
  EXPECT_NEAR(raised.value, 1.0, 0.1);  // (1.5 − 0.5)/1
  EXPECT_LE(raised.revolution, stopped + AlertConfig{}.persist_revolutions + 1);
  run.engine.on_identification(fitted(run.next, -0.9, 0.03, 1100.0, 8.0, 0.01),
                               [&](const Alert& a) { run.alerts.push_back(a); });
  run.noisy(1000, 2, {1.5, 0.5}, 0.01);
  EXPECT_EQ(run.count(AlertKind::kRunout, true), 1);
}

// An estimate that cannot tell (60 ± 10 % of f_t: u − 3σ below the 40 % clearing level, u + 3σ
// above the 50 % limit) leaves runout to the flute forces, as where a flute cuts nothing
// and the force bounds a runout beyond the feed poorly ([002]'s copper slot, 177 % imbalance):
// raised where they differ by 100 %, quoting them and the estimate; not raised where they agree;
// cleared once they agree again; a decisive estimate still decides alone.
TEST(AlertEngine, AnUndecidedEstimateLeavesRunoutToTheFluteForces) {
  const auto window = [](Feed& run) {
    run.engine.on_identification(fitted(run.next, -1.8, 0.3, 1100.0, 8.0, 0.01),
                                 [&](const Alert& a) { run.alerts.push_back(a); });
  };
  Feed run({}, 62);
  run.engine.expect_estimates();
  run.noisy(100, 2, {1.5, 0.5}, 0.01);
  window(run);
  EXPECT_EQ(run.count(AlertKind::kRunout, true), 0);  // two windows in a row raise
  run.noisy(30, 2, {1.5, 0.5}, 0.01);
  window(run);
  ASSERT_EQ(run.count(AlertKind::kRunout, true), 1);
  const Alert& raised = *run.first(AlertKind::kRunout);
  EXPECT_EQ(raised.quantity, "flute_imbalance");
  EXPECT_NEAR(raised.value, 1.0, 0.1);  // (1.5 − 0.5)/1
  EXPECT_EQ(raised.threshold, AlertConfig{}.runout_imbalance);
  EXPECT_NE(std::string(raised.message.data())
                .find("the estimate cannot tell: r_CE1 − r_CE2 1.800 ± 0.300 µm = 60 ± 10 % of f_t "
                      "3 µm"),
            std::string::npos)
      << raised.message.data();
  // Forces between the clearing level (20 %) and the limit (25 %): they say neither, nothing
  // clears.
  for (int i = 0; i < 3; ++i) {
    run.noisy(30, 2, {1.11, 0.89}, 0.002);  // I = 22 %
    window(run);
  }
  EXPECT_EQ(run.count(AlertKind::kRunout, false), 0);
  // The flutes agree again: the next two undecided windows clear it, quoting the forces.
  run.noisy(30, 2, {1.0, 1.0}, 0.01);
  window(run);
  run.noisy(30, 2, {1.0, 1.0}, 0.01);
  window(run);
  ASSERT_EQ(run.count(AlertKind::kRunout, false), 1);
  const Alert& cleared = *run.first(AlertKind::kRunout, false);
  EXPECT_EQ(cleared.quantity, "flute_imbalance");
  EXPECT_LT(cleared.value, 0.2);
  EXPECT_NE(std::string(cleared.message.data()).find("runout cleared: flute imbalance "),
            std::string::npos)
      << cleared.message.data();
  EXPECT_NE(std::string(cleared.message.data()).find("(below 20.00 % for 10 revolutions)"),
            std::string::npos)
      << cleared.message.data();

  // Raised by a decisive estimate (65 ± 1 %) while the forces sit between the clearing level and
  // the limit (I = 22 %, never raised): undecided windows after it do not clear it, the forces
  // saying neither.
  Feed band({}, 62);
  band.engine.expect_estimates();
  for (int i = 0; i < 2; ++i) {
    band.noisy(30, 2, {1.11, 0.89}, 0.002);
    band.engine.on_identification(fitted(band.next, -1.95, 0.03, 1100.0, 8.0, 0.01),
                                  [&](const Alert& a) { band.alerts.push_back(a); });
  }
  ASSERT_EQ(band.count(AlertKind::kRunout, true), 1);
  for (int i = 0; i < 4; ++i) {
    band.noisy(30, 2, {1.11, 0.89}, 0.002);
    window(band);
  }
  EXPECT_EQ(band.count(AlertKind::kRunout, false), 0);

  // Flutes that agree throughout: the same estimates raise nothing.
  Feed even({}, 62);
  even.engine.expect_estimates();
  for (int i = 0; i < 6; ++i) {
    even.noisy(30, 2, {1.0, 1.0}, 0.01);
    window(even);
  }
  EXPECT_EQ(even.count(AlertKind::kRunout, true), 0);

  // A decisive estimate below the limit (30 ± 1 %) outweighs the imbalance (as before), and one
  // above it (65 ± 1 %) raises on its own figures.
  Feed decided({}, 62);
  decided.engine.expect_estimates();
  for (int i = 0; i < 3; ++i) {
    decided.noisy(30, 2, {1.5, 0.5}, 0.01);
    decided.engine.on_identification(fitted(decided.next, -0.9, 0.03, 1100.0, 8.0, 0.01),
                                     [&](const Alert& a) { decided.alerts.push_back(a); });
  }
  EXPECT_EQ(decided.count(AlertKind::kRunout, true), 0);
  for (int i = 0; i < 2; ++i) {
    decided.noisy(30, 2, {1.0, 1.0}, 0.01);
    decided.engine.on_identification(fitted(decided.next, -1.95, 0.03, 1100.0, 8.0, 0.01),
                                     [&](const Alert& a) { decided.alerts.push_back(a); });
  }
  ASSERT_EQ(decided.count(AlertKind::kRunout, true), 1);
  EXPECT_EQ(decided.first(AlertKind::kRunout)->quantity, "radius_deficit_per_feed");
}

// Steady state: nothing is allocated per identified window either.
TEST(AlertEngine, ExaminingAWindowAllocatesNothing) {
  std::vector<identify::IdentifiedWindow> windows;
  for (int i = 0; i < 60; ++i) {
    const double d = i < 30 ? -0.9 : -1.9;  // a runout change, then runout high
    windows.push_back(fitted(29 + 30 * i, d, 0.03, 1100.0 * (1.0 + 0.005 * i), 8.0, 0.01));
  }
  AlertEngine engine;
  int alerts = 0;
  auto sink = [&](const Alert&) { ++alerts; };
  const test::AllocationCounter counter;
  for (const auto& w : windows) {
    engine.on_identification(w, sink);
  }
  EXPECT_EQ(counter.allocations(), 0);
  EXPECT_GE(alerts, 3);  // runout change, runout high, wear drift
}

// Steady state: nothing is allocated per revolution, including the revolution that completes the
// baseline and those that raise and clear alerts.
TEST(AlertEngine, ExaminingARevolutionAllocatesNothing) {
  AlertEngine engine;
  std::mt19937_64 rng(81);
  std::normal_distribution<double> noise(0.0, 0.01);
  int alerts = 0;
  auto sink = [&](const Alert&) { ++alerts; };
  const test::AllocationCounter counter;
  for (int n = 0; n < 6000; ++n) {
    const double step = n < 3000 ? 0.03 : 0.2;  // then runout and runout change
    const Forces f{(1.0 + step) * (1.0 + noise(rng)), (1.0 - step) * (1.0 + noise(rng))};
    engine.on_revolution(revolution(n, 2, f), sink);
  }
  EXPECT_EQ(counter.allocations(), 0);
  EXPECT_GE(alerts, 2);
}

}  // namespace
}  // namespace millwatch::monitor
