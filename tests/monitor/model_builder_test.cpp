// The lockstep model built off the sample thread (ModelBuilder) against the same model built in
// place, and the pipeline that takes such builds a fixed number of revolutions after asking:
// the same results whatever the blocks or the machine's timing.

#include "core/monitor/model_builder.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "core/monitor/pipeline.hpp"
#include "core/signal/butterworth_lowpass.hpp"
#include "tests/support/recording.hpp"

namespace millwatch::monitor {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

/// [000]'s cp-Ti slot as the monitor models it by default (runout, trochoid, minimum chip and its
/// accumulation, deflection, helix lag): the model whose build takes milliseconds.
model::ModelConfig full_cut() {
  model::ModelConfig c;
  c.effects.helix_lag.discs = 5;
  return c;
}

/// Every filtered force the two give, over a turn of angles, the same bit for bit: one by one
/// (force_at()) and along a line (forces_on_line(), from the table the residuals read); and the
/// same unfiltered waveform.
void expect_same_model(const Lockstep& a, const Lockstep& b) {
  ASSERT_TRUE(a.has_model());
  ASSERT_TRUE(b.has_model());
  EXPECT_EQ(a.spindle_hz(), b.spindle_hz());
  EXPECT_EQ(a.waveform().fx_N, b.waveform().fx_N);
  EXPECT_EQ(a.waveform().fy_N, b.waveform().fy_N);
  constexpr std::size_t kRows = 1000;
  std::vector<double> rows_a(4 * kRows), rows_b(4 * kRows);
  a.forces_on_line(0.1, kTwoPi / 997.0, kRows, rows_a.data());
  b.forces_on_line(0.1, kTwoPi / 997.0, kRows, rows_b.data());
  EXPECT_EQ(rows_a, rows_b);
  for (int k = 0; k < 997; ++k) {
    const double angle = kTwoPi * k / 997.0;
    const auto fa = a.force_at(angle);
    const auto fb = b.force_at(angle);
    for (std::size_t axis = 0; axis < 3; ++axis) {
      ASSERT_EQ(fa[axis], fb[axis]) << "angle " << angle << ", axis " << axis;
    }
  }
}

// A build on the builder's thread, taken into a lockstep, is the model that lockstep would have
// built in place — at a new speed, again at another (the spare then holds the taken lockstep's
// old tables), and with new parameters — and the lockstep keeps its alignment.
TEST(ModelBuilder, ItsBuildIsTheModelBuiltInPlaceAndTheAlignmentStays) {
  const auto filter = signal::ButterworthDesign::lowpass(50000.0, 3300.0, 4);
  const model::ModelConfig commanded = full_cut();
  const double hz = 25252.0 / 60.0;
  Lockstep live(commanded, filter);
  ASSERT_TRUE(live.set_spindle_hz(hz));
  live.set_alignment(0.7);
  ASSERT_TRUE(live.aligned());
  Lockstep in_place(commanded, filter);  // aligned the same (force_at() reads the alignment)

  ModelBuilder builder(commanded, filter, false);
  EXPECT_FALSE(builder.busy());
  for (const double speed_hz : {1.01 * hz, 1.02 * hz}) {
    const std::uint64_t revision = live.revision();
    builder.start(live.commanded_config(), speed_hz);
    EXPECT_TRUE(builder.busy());
    EXPECT_EQ(builder.spindle_hz(), speed_hz);
    builder.take_into(live);
    EXPECT_FALSE(builder.busy());
    ASSERT_TRUE(in_place.set_spindle_hz(speed_hz));
    in_place.set_alignment(0.7);
    expect_same_model(live, in_place);
    EXPECT_NE(live.revision(), revision);  // what was measured on the old model is not reused
    EXPECT_TRUE(live.aligned());
    EXPECT_DOUBLE_EQ(live.offset_rad(), 0.7);
  }

  // Identified parameters (more runout, a stiffer tool) at the model's speed.
  model::ModelConfig identified = commanded;
  identified.effects.runout.offset_um += 0.5;
  identified.effects.deflection.stiffness_N_per_um *= 1.2;
  builder.start(identified, live.spindle_hz());
  builder.take_into(live);
  in_place.set_parameters(identified, 0.7, true);
  expect_same_model(live, in_place);
  EXPECT_EQ(live.commanded_config().effects.runout.offset_um, identified.effects.runout.offset_um);

  // A build still running when the builder goes: it waits for it and stops.
  builder.start(commanded, 1.03 * hz);
}

// A ramp at 50 kHz with the default model: every 0.2 % of speed the model is rebuilt on the
// builder's thread and taken a fixed number of revolutions later. Replayed in blocks of 1 ms and
// of 0.2 s (where the sample thread reaches the due revolution long before the build is done,
// and waits), every revolution's residuals and model are the same: when a model applies depends
// on the samples alone. And the model follows the speed: at the end it is the cut's.
TEST(ModelBuilder, APipelineTakesItsBuildsAtTheSameRevolutionWhateverTheBlocks) {
  sim::Scenario s;
  s.sample_rate_hz = 50000.0;
  s.duration_s = 1.0;
  s.spindle.actual_rpm = 25000.0;
  s.spindle.profile = sim::SpindleProfileKind::kRamp;
  s.spindle.ramp_end_rpm = 26000.0;
  s.spindle.ramp_start_s = 0.3;
  s.spindle.ramp_end_s = 0.7;
  s.noise.enabled = true;
  s.model.effects.helix_lag.discs = 5;
  const test::Recording r = test::record(s);
  MonitorConfig c = test::monitor_for(s);
  c.identification.enabled = false;

  std::vector<test::Collector> outs(2);
  std::vector<PipelineStatus> status;
  std::vector<double> model_hz;
  const std::vector<std::size_t> blocks = {50, 10000};
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    Pipeline p(c, outs[i]);
    test::replay(p, r, blocks[i]);
    status.push_back(p.status());
    model_hz.push_back(p.lockstep().spindle_hz());
  }
  // Through 1,000 rpm at 0.2 % a build: about 20 after the lock's.
  EXPECT_GE(status[0].model_builds, 15);
  EXPECT_EQ(status[0].model_builds, status[1].model_builds);
  EXPECT_NEAR(60.0 * model_hz[0], 26000.0, 0.002 * 26000.0);
  EXPECT_EQ(model_hz[0], model_hz[1]);

  ASSERT_EQ(outs[0].revolutions.size(), outs[1].revolutions.size());
  int modelled = 0;
  for (std::size_t k = 0; k < outs[0].revolutions.size(); ++k) {
    const RevolutionRecord& a = outs[0].revolutions[k];
    const RevolutionRecord& b = outs[1].revolutions[k];
    ASSERT_EQ(a.revolution, b.revolution);
    ASSERT_EQ(a.model_valid, b.model_valid) << "revolution " << a.revolution;
    if (!a.model_valid) {
      continue;
    }
    ++modelled;
    for (std::size_t axis = 0; axis < 3; ++axis) {
      ASSERT_EQ(a.residual_rms_N[axis], b.residual_rms_N[axis]) << "revolution " << a.revolution;
    }
    ASSERT_EQ(a.model.alpha_deg, b.model.alpha_deg) << "revolution " << a.revolution;
    ASSERT_EQ(a.model_offset_rad, b.model_offset_rad) << "revolution " << a.revolution;
  }
  EXPECT_GT(modelled, 300);  // ~415 revolutions in the second
}

}  // namespace
}  // namespace millwatch::monitor
