// The lockstep model against independent computations: the time-marching model run through
// the causal filter sample by sample, and a known angle offset.

#include "core/monitor/lockstep.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>
#include <vector>

#include "core/model/milling_model.hpp"
#include "core/monitor/pipeline.hpp"
#include "core/monitor/run_summary.hpp"
#include "core/signal/butterworth_lowpass.hpp"
#include "core/signal/cpu_features.hpp"
#include "core/sim/scenario.hpp"
#include "tests/support/allocation_counter.hpp"
#include "tests/support/recording.hpp"
#include "tests/support/test_paths.hpp"

namespace millwatch::monitor {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

model::ModelConfig cut() {
  model::ModelConfig c;  // [000]'s cp-Ti slot with runout; rigid, so each revolution repeats
  c.effects.deflection.enabled = false;
  c.effects.accumulation.enabled = false;
  c.effects.helix_lag.discs = 5;
  return c;
}

/// A "measurement" that is the model itself, shifted: over `revolutions` turns of `samples` each
/// (sample n at tracker angle 2π(n + `phase`)/samples), the model at tracker angle a + shift_rad,
/// averaged on 256 bins.
SyncAverage shifted_model_average(const Lockstep& lockstep, double shift_rad, int samples,
                                  int revolutions, double phase = 0.5) {
  SyncAverage avg(256, revolutions);
  for (int r = 0; r < revolutions; ++r) {
    for (int n = 0; n < samples; ++n) {
      const double a = kTwoPi * (n + phase) / samples;
      const auto f = lockstep.force_at(a + shift_rad);
      avg.add(a, {f[0], f[1], f[2]});
    }
    avg.end_revolution();
  }
  return avg;
}

// The filtered model force at an angle is what the causal Butterworth filter gives when the
// model's force is fed through it sample by sample for many revolutions (its steady state),
// at the measured speed with the feed rate fixed by the commanded one.
TEST(Lockstep, EqualsTheTimeMarchedModelThroughTheCausalFilter) {
  const model::ModelConfig commanded = cut();
  const double fs = 50000.0;
  const double f_hz = 25252.0 / 60.0;
  const auto filter = signal::ButterworthDesign::lowpass(fs, 3300.0, 4);
  Lockstep lockstep(commanded, filter);
  ASSERT_TRUE(lockstep.set_spindle_hz(f_hz));
  EXPECT_FALSE(lockstep.set_spindle_hz(f_hz * 1.001));  // within 0.2 %: kept
  // Independent: MillingModel (time marching) at the actual speed and the thinner chip.
  model::ModelConfig actual = commanded;
  actual.process.spindle_rpm = 60.0 * f_hz;
  actual.process.feed_per_tooth_um = commanded.process.feed_per_tooth_um * 25000.0 / 25252.0;
  model::MillingModel marched(actual);
  marched.warm_up();
  const auto& w = marched.forces();
  const auto steps = static_cast<double>(w.fx_N.size());
  auto model_at = [&](const std::vector<double>& axis, double revolutions) {
    const double pos = (revolutions - std::floor(revolutions)) * steps;
    const auto k0 = static_cast<std::size_t>(pos) % axis.size();
    const std::size_t k1 = (k0 + 1) % axis.size();
    return axis[k0] + (pos - std::floor(pos)) * (axis[k1] - axis[k0]);
  };
  signal::LowPassFilter lx(filter), ly(filter);
  const int samples = static_cast<int>(40.0 * fs / f_hz);  // 40 revolutions
  double worst = 0.0, peak = 0.0;
  for (int n = 0; n < samples; ++n) {
    const double revolutions = n * f_hz / fs;
    const double x = lx.step(model_at(w.fx_N, revolutions));
    const double y = ly.step(model_at(w.fy_N, revolutions));
    if (n > samples / 2) {  // the filter's start-up has died away
      const auto m = lockstep.force_at(kTwoPi * revolutions);  // offset 0: model angle
      worst = std::max({worst, std::fabs(m[0] - x), std::fabs(m[1] - y)});
      peak = std::max({peak, std::fabs(x), std::fabs(y)});
    }
  }
  // The two differ by the linear interpolation between the 720 model steps before filtering
  // (the time-marched side interpolates the force, the lockstep its spectrum): well under 1 %.
  EXPECT_GT(peak, 0.5);
  EXPECT_LT(worst, 0.01 * peak);
}

// What the analyzer measured on the model revolution holds while the revision stays: it
// changes with each build, new parameters and alignment, not with a speed the model keeps, and
// two objects never share one.
TEST(Lockstep, ItsRevisionChangesWithTheModelOrItsAlignmentOnly) {
  const double fs = 50000.0;
  const auto filter = signal::ButterworthDesign::lowpass(fs, 3300.0, 4);
  Lockstep lockstep(cut(), filter);
  EXPECT_EQ(lockstep.revision(), 0U);
  ASSERT_TRUE(lockstep.set_spindle_hz(420.0));
  const std::uint64_t built = lockstep.revision();
  EXPECT_NE(built, 0U);
  EXPECT_FALSE(lockstep.set_spindle_hz(420.0 * 1.001));
  EXPECT_EQ(lockstep.revision(), built);  // the same model
  ASSERT_TRUE(lockstep.set_spindle_hz(420.0 * 1.01));
  const std::uint64_t rebuilt = lockstep.revision();
  EXPECT_NE(rebuilt, built);
  ASSERT_TRUE(lockstep.align(shifted_model_average(lockstep, 0.7, 256, 1)));
  const std::uint64_t aligned = lockstep.revision();
  EXPECT_NE(aligned, rebuilt);
  model::ModelConfig other = cut();
  other.effects.runout.offset_um = 0.5;
  lockstep.build(other, lockstep.spindle_hz());  // identified parameters
  lockstep.set_alignment(0.3);
  EXPECT_NE(lockstep.revision(), aligned);
  Lockstep second(cut(), filter);
  ASSERT_TRUE(second.set_spindle_hz(420.0));
  for (const std::uint64_t r : {built, rebuilt, aligned, lockstep.revision()}) {
    EXPECT_NE(second.revision(), r);
  }
}

// Alignment finds a known angle offset between the model and a measured average that is the
// model itself, shifted.
TEST(Lockstep, AlignmentFindsAKnownOffset) {
  const double fs = 50000.0;
  const double f_hz = 420.0;
  const auto filter = signal::ButterworthDesign::lowpass(fs, 3300.0, 4);
  Lockstep lockstep(cut(), filter);
  lockstep.set_spindle_hz(f_hz);
  const double shift_rad = 1.234;
  // The "measurement": the model at tracker angle a is the model at angle a + shift (the
  // offset still 0).
  ASSERT_TRUE(lockstep.align(shifted_model_average(lockstep, shift_rad, 400, 10, 0.37)));
  EXPECT_NEAR(std::remainder(lockstep.offset_rad() - shift_rad, kTwoPi), 0.0, 0.004);
  EXPECT_GT(lockstep.alignment_correlation(), 0.999);
}

// Along a line of angles (a revolution's samples: the angle a step per sample, over three turns
// from an aligned offset), forces_on_line() gives force_at() at each angle — its grid position
// advanced by a step per sample instead of a division and a floor, so equal to the rounding of
// that position — and each row's fourth value is Fx² + Fy² of the row, exactly.
TEST(Lockstep, ForcesOnALineAreTheForcesAtEachAngle) {
  const double fs = 111100.0;
  const auto filter = signal::ButterworthDesign::lowpass(fs, 3300.0, 4);
  Lockstep lockstep(cut(), filter);
  lockstep.set_spindle_hz(421.0);
  ASSERT_TRUE(lockstep.align(shifted_model_average(lockstep, 0.8, 512, 2)));
  const double step_rad = kTwoPi * 421.0 / fs;
  const auto count = static_cast<std::size_t>(3.0 * fs / 421.0);
  if (!signal::cpu_has_avx()) {
    GTEST_LOG_(INFO) << "no AVX on this CPU: forces_on_line's scalar kernel alone";
  }
  for (const double angle0_rad : {0.3, -2.0, 40.0}) {
    std::vector<double> rows(4 * count, -1.0), scalar_rows(4 * count, -2.0);
    lockstep.forces_on_line(angle0_rad, step_rad, count, rows.data());
    // The AVX kernel (where the CPU has it: else the scalar one twice) and the scalar one: the
    // same rows, bit for bit.
    lockstep.forces_on_line(angle0_rad, step_rad, count, scalar_rows.data(), false);
    for (std::size_t i = 0; i < rows.size(); ++i) {
      ASSERT_EQ(std::bit_cast<std::uint64_t>(rows[i]), std::bit_cast<std::uint64_t>(scalar_rows[i]))
          << i;
    }
    double largest = 0.0, worst = 0.0;
    for (std::size_t i = 0; i < count; ++i) {
      const double* r = &rows[4 * i];
      const auto f = lockstep.force_at(angle0_rad + step_rad * static_cast<double>(i));
      for (std::size_t a = 0; a < 3; ++a) {
        largest = std::max(largest, std::fabs(f[a]));
        worst = std::max(worst, std::fabs(r[a] - f[a]));
      }
      ASSERT_EQ(r[3], r[0] * r[0] + r[1] * r[1]) << i;
    }
    EXPECT_GT(largest, 1.0);  // newtons of a cut, not a flat line
    EXPECT_LT(worst, 1e-9 * largest) << angle0_rad;
  }
}

// Following a new speed re-evaluates the model without allocating.
TEST(Lockstep, FollowingTheSpeedAllocatesNothing) {
  const auto filter = signal::ButterworthDesign::lowpass(50000.0, 3300.0, 4);
  Lockstep lockstep(cut(), filter);
  lockstep.set_spindle_hz(400.0);
  test::AllocationCounter counter;
  for (int i = 1; i <= 20; ++i) {
    EXPECT_TRUE(lockstep.set_spindle_hz(400.0 * (1.0 + 0.005 * i)));
  }
  EXPECT_EQ(counter.allocations(), 0);
}

// What of the model revolution is approximate is said. On a soft tool (0.1 N/µm) with h_min
// 3 µm for the cp-Ti preset's 4 µm feed, some slots' accumulation repeats within no period
// the steady state waits for: the simulator's truth counts them (Recording::played), the
// lockstep's builds count them too, and the run's summary words it. The preset's own cut
// (h_min 0.2 µm, 0.47 N/µm) has none, and its summary says nothing.
TEST(Lockstep, TheSummarySaysWhenTheModelsSteadyStateDidNotSettle) {
  struct Run {
    sim::PlayedSteadyStates truth;
    nlohmann::json steady_state;
    std::int64_t builds = 0;
  };
  const auto run = [](double h_min_um, double stiffness_N_per_um) {
    std::ifstream preset(test::source_dir() / "config" / "presets" / "cpti_masrani2023.json");
    sim::Scenario s = sim::scenario_from_json(nlohmann::json::parse(preset));
    s.sample_rate_hz = 20000.0;
    s.duration_s = 0.5;
    s.model.effects.min_chip.h_min_um = h_min_um;
    s.model.effects.deflection.stiffness_N_per_um = stiffness_N_per_um;
    const test::Recording rec = test::record(s);
    const MonitorConfig config = test::monitor_for(s);
    test::Collector sink;
    Pipeline p(config, sink);
    test::replay(p, rec, 200);
    RunSummary summary(config);
    summary.finish(p.status());
    return Run{rec.played, summary.to_json()["model"]["steady_state"], p.status().model_builds};
  };

  const Run soft = run(3.0, 0.1);
  ASSERT_GT(soft.truth.unsettled_slots, 0);  // the cut as simulated
  ASSERT_GE(soft.builds, 1);
  const auto& st = soft.steady_state;
  EXPECT_GE(st["builds_with_unsettled_slots"].get<std::int64_t>(), 1) << st.dump();
  EXPECT_LE(st["builds_with_unsettled_slots"].get<std::int64_t>(), soft.builds) << st.dump();
  EXPECT_GT(st["unsettled_slots_most"].get<int>(), 0) << st.dump();
  EXPECT_EQ(st["slots_of_that_build"].get<int>(), soft.truth.slots) << st.dump();
  ASSERT_FALSE(st["notes"].empty()) << st.dump();
  EXPECT_NE(st["notes"][0].get<std::string>().find("did not repeat within 600 revolutions"),
            std::string::npos)
      << st.dump();

  const Run preset = run(0.2, 0.47);
  ASSERT_EQ(preset.truth.unsettled_slots, 0);
  ASSERT_GE(preset.builds, 1);
  EXPECT_EQ(preset.steady_state["builds_with_unsettled_slots"], 0) << preset.steady_state.dump();
  EXPECT_EQ(preset.steady_state["builds_with_areas_unsettled"], 0) << preset.steady_state.dump();
  EXPECT_TRUE(preset.steady_state["notes"].empty()) << preset.steady_state.dump();
}

}  // namespace
}  // namespace millwatch::monitor
