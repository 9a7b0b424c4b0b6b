#include "core/monitor/pipeline.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "core/identify/identifier.hpp"
#include "core/model/periodic_response.hpp"
#include "core/model/steady_state.hpp"
#include "core/monitor/run_summary.hpp"
#include "core/sim/cut_simulator.hpp"
#include "tests/support/allocation_counter.hpp"
#include "tests/support/recording.hpp"

namespace millwatch::monitor {
namespace {

using test::Collector;
using test::knocked_record;
using test::monitor_for;
using test::record;
using test::Recording;
using test::replay;

sim::Scenario cut_at_50khz(bool measurement_errors) {
  sim::Scenario s;  // [000]'s cp-Ti slot, 4 µm/tooth, runout 1.82 µm / 0.58 rad
  s.sample_rate_hz = 50000.0;
  s.duration_s = 1.0;
  s.spindle.actual_rpm = 25252.0;  // 25,000 commanded
  s.model.effects.dynamometer.enabled = true;
  s.model.effects.dynamometer.natural_hz = {4500.0, 4600.0, 6000.0};
  s.noise.enabled = measurement_errors;
  s.noise.sigma_N = {0.02, 0.02, 0.02};
  s.quantisation.enabled = measurement_errors;
  s.hum.enabled = measurement_errors;
  // Drift is not noise: a slowly growing offset bends the valleys where the force is small.
  // The pipeline re-zeroes whenever the tool is not cutting (see the stop/start test).
  s.drift.enabled = false;
  return s;
}

/// The revolution of `records` that starts nearest `utime_us` (within a quarter revolution).
const RevolutionRecord* at_time(const std::vector<RevolutionRecord>& records,
                                std::int64_t utime_us) {
  const RevolutionRecord* best = nullptr;
  for (const auto& r : records) {
    if (best == nullptr ||
        std::llabs(r.utime_us - utime_us) < std::llabs(best->utime_us - utime_us)) {
      best = &r;
    }
  }
  return best != nullptr && std::llabs(best->utime_us - utime_us) < 600 ? best : nullptr;
}

/// Issue 3 §7's targets for every revolution of `noisy` with a full α window: α's and ΔFy's
/// window means against `clean`'s revolution at the same time (0.3°, 2 %), the speed within
/// 0.05 % of 25,252 rpm; with `model`, the lockstep model valid. `compared` counts them.
void expect_accuracy_targets(const Collector& noisy, const Collector& clean, bool model,
                             int& compared) {
  for (const auto& ra : noisy.revolutions) {
    const RevolutionRecord* match = at_time(clean.revolutions, ra.utime_us);
    ASSERT_NE(match, nullptr) << ra.utime_us;
    const auto& rb = *match;
    if (ra.window_revolutions < 30) {
      continue;
    }
    ++compared;
    EXPECT_NEAR(ra.alpha_mean_deg, rb.alpha_mean_deg, 0.3) << ra.utime_us;
    EXPECT_NEAR(ra.delta_fy_mean_N, rb.delta_fy_mean_N, 0.02 * std::fabs(rb.delta_fy_mean_N))
        << ra.utime_us;
    EXPECT_NEAR(ra.spindle_rpm, 25252.0, 0.0005 * 25252.0);
    if (model) {
      EXPECT_TRUE(ra.model_valid) << ra.utime_us;
    }
  }
}

// Issue 3 §7: rpm within 0.05 % from 0.25 s; α's mean within 0.3° of the same detector on the
// noise-free signal at 50 kHz; ΔFy within 2 %.
TEST(Pipeline, MeetsTheAccuracyTargetsOnASimulatedCut) {
  const sim::Scenario noisy = cut_at_50khz(true);
  const sim::Scenario clean = cut_at_50khz(false);
  Collector a, b;
  Pipeline pa(monitor_for(noisy), a);
  Pipeline pb(monitor_for(clean), b);
  replay(pa, record(noisy), 1000);
  replay(pb, record(clean), 1000);

  // The first speed estimate comes after 0.25 s of data.
  const SpindleUpdate* first = nullptr;
  for (const auto& u : a.spindle) {
    if (u.estimate.valid) {
      first = &u;
      break;
    }
  }
  ASSERT_NE(first, nullptr);
  EXPECT_LE(first->utime_us, 300000);
  EXPECT_NEAR(first->estimate.spindle_rpm, 25252.0, 0.0005 * 25252.0);

  ASSERT_GT(a.revolutions.size(), 150u);
  int compared = 0;
  expect_accuracy_targets(a, b, false, compared);
  EXPECT_GT(compared, 100);
}

/// Standard deviation of the per-revolution α of `c`'s valid revolutions.
double alpha_scatter_deg(const Collector& c) {
  double n = 0.0, sum = 0.0, sum2 = 0.0;
  for (const auto& r : c.revolutions) {
    if (r.measured.valid) {
      n += 1.0;
      sum += r.measured.alpha_deg;
      sum2 += r.measured.alpha_deg * r.measured.alpha_deg;
    }
  }
  return n > 1.0 ? std::sqrt(std::max(0.0, (sum2 - sum * sum / n) / (n - 1.0))) : 0.0;
}

// Issue 10: past the low-pass, a 333.3 kHz recording of a cut at 25,000 rpm is measured on every
// third sample (111.1 kHz). It must meet issue 3's accuracy targets against the noise-free
// detector at the same rate, and measure each revolution's α at least as steadily as a 50 kHz
// recording of the same cut does.
TEST(Pipeline, MeasuresA333kHzRecordingToTheAccuracyTargets) {
  sim::Scenario fast = cut_at_50khz(true);
  fast.sample_rate_hz = 333300.0;
  fast.duration_s = 0.8;
  sim::Scenario fast_clean = cut_at_50khz(false);
  fast_clean.sample_rate_hz = 333300.0;
  fast_clean.duration_s = 0.8;
  sim::Scenario slow = cut_at_50khz(true);
  slow.duration_s = 0.8;
  Collector a, b, c;
  Pipeline pa(monitor_for(fast), a);
  Pipeline pb(monitor_for(fast_clean), b);
  Pipeline pc(monitor_for(slow), c);
  replay(pa, record(fast), 3333);
  replay(pb, record(fast_clean), 3333);
  replay(pc, record(slow), 1000);
  ASSERT_GT(a.revolutions.size(), 250u);
  int compared = 0;
  expect_accuracy_targets(a, b, true, compared);
  EXPECT_GT(compared, 250);
  const double scatter_fast = alpha_scatter_deg(a), scatter_slow = alpha_scatter_deg(c);
  EXPECT_LE(scatter_fast, scatter_slow);
  std::printf("333.3 kHz: %d revolutions; α per revolution ± %.3f° (50 kHz: ± %.3f°)\n", compared,
              scatter_fast, scatter_slow);
}

// Issue 3 §2: the causal filter (delay corrected) and the offline zero-phase option measure the
// same α; both compare the model like with like (the model goes through H or |H|²).
// (A dynamometer resonance close above the cut-off — 4.5 kHz against 3.3 kHz — leaks through
// both filters differently and moves α by degrees with the filter's details; the README's
// findings have the figures. Here it sits at 9 kHz.)
TEST(Pipeline, CausalAndZeroPhaseFilteringGiveTheSameAlpha) {
  sim::Scenario s = cut_at_50khz(true);
  s.model.effects.dynamometer.natural_hz = {9000.0, 9200.0, 12000.0};
  const Recording r = record(s);
  MonitorConfig zc = monitor_for(s);
  zc.filter_zero_phase = true;
  Collector causal, zero;
  Pipeline pc(monitor_for(s), causal);
  Pipeline pz(zc, zero);
  replay(pc, r, 1000);
  replay(pz, r, 1000, {}, /*finish=*/false);
  const std::size_t before_finish = zero.revolutions.size();
  pz.finish();
  EXPECT_GT(zero.revolutions.size(), before_finish);  // the held samples were measured too
  ASSERT_GT(zero.revolutions.size(), 150u);
  int compared = 0;
  double worst_time_us = 0.0;
  for (const auto& rz : zero.revolutions) {
    const RevolutionRecord* rc = at_time(causal.revolutions, rz.utime_us);
    if (rc == nullptr || rz.window_revolutions < 30 || rc->window_revolutions < 30) {
      continue;
    }
    ++compared;
    EXPECT_NEAR(rz.alpha_mean_deg, rc->alpha_mean_deg, 0.3) << rz.utime_us;
    EXPECT_NEAR(rz.delta_fy_mean_N, rc->delta_fy_mean_N, 0.02 * std::fabs(rc->delta_fy_mean_N));
    // The causal valleys, corrected by the group delay at the tooth-passing frequency, land
    // within a few microseconds of the zero-phase ones (the residual lateness is the filter's
    // phase curvature over the valley's harmonics).
    worst_time_us =
        std::max(worst_time_us, static_cast<double>(std::llabs(rz.utime_us - rc->utime_us)));
    // Like with like: the residual stays at the noise level in both modes.
    EXPECT_LT(rz.residual_rms_N[1], 0.05);
    EXPECT_LT(rc->residual_rms_N[1], 0.05);
  }
  EXPECT_GT(compared, 100);
  EXPECT_LE(worst_time_us, 20.0);
}

// The same stream in different block sizes gives the same results.
// At 50 kHz, and at 333.3 kHz where the measuring stages take every third sample (blocks of
// 137 samples start at every phase of the stride).
TEST(Pipeline, ResultsDoNotDependOnBlockSize) {
  for (const double fs : {50000.0, 333300.0}) {
    sim::Scenario s = cut_at_50khz(true);
    s.sample_rate_hz = fs;
    s.duration_s = 0.6;
    const Recording r = record(s);
    Collector a, b;
    Pipeline pa(monitor_for(s), a);
    Pipeline pb(monitor_for(s), b);
    replay(pa, r, static_cast<std::size_t>(fs / 1000.0));
    replay(pb, r, 137);
    ASSERT_GT(a.revolutions.size(), 200u) << fs;
    ASSERT_EQ(a.revolutions.size(), b.revolutions.size()) << fs;
    for (std::size_t i = 0; i < a.revolutions.size(); ++i) {
      EXPECT_EQ(a.revolutions[i].measured.alpha_deg, b.revolutions[i].measured.alpha_deg) << fs;
      EXPECT_EQ(a.revolutions[i].residual_rms_N, b.revolutions[i].residual_rms_N) << fs;
      EXPECT_EQ(a.revolutions[i].utime_us, b.revolutions[i].utime_us) << fs;
    }
    ASSERT_EQ(a.spindle.size(), b.spindle.size()) << fs;
  }
}

/// The residual RMS per axis the lockstep must show when the truth is `truth` and the
/// monitor's model `monitored`, computed without the pipeline: both models' steady states at the
/// actual speed (evaluator), through the causal filter (periodic response), the monitored one
/// shifted to the best correlation of the three mean-removed axes (as the alignment does), and
/// the filtered white noise σ·√Σh² added in quadrature.
std::array<double, 3> expected_residual_N(const sim::Scenario& truth,
                                          const model::ModelConfig& monitored, double noise_N,
                                          const signal::ButterworthDesign& filter) {
  const double rpm = sim::actual_rpm(truth);
  const int steps = 2880;  // a common fine grid for both
  auto filtered = [&](const model::ModelConfig& c) {
    model::SteadyStateWorkspace ws(c, steps);
    const auto& s = model::evaluate_steady_state(model::at_actual_speed(c, rpm), rpm, steps, ws,
                                                 model::SteadyStateOutput::kMean);
    std::array<std::vector<double>, 3> out = {s.mean.fx_N, s.mean.fy_N, s.mean.fz_N};
    model::PeriodicResponse response(steps);
    for (auto& axis : out) {
      response.apply(axis, rpm / 60.0, [&](double hz) { return filter.response(hz); });
    }
    return out;
  };
  const auto a = filtered(truth.model);
  const auto b = filtered(monitored);
  std::array<double, 3> mean_a{}, mean_b{};
  for (std::size_t k = 0; k < 3; ++k) {
    for (int i = 0; i < steps; ++i) {
      mean_a[k] += a[k][static_cast<std::size_t>(i)] / steps;
      mean_b[k] += b[k][static_cast<std::size_t>(i)] / steps;
    }
  }
  int best = 0;
  double best_c = -1e300;
  for (int shift = 0; shift < steps; ++shift) {
    double c = 0.0;
    for (std::size_t k = 0; k < 3; ++k) {
      for (int i = 0; i < steps; ++i) {
        c += (a[k][static_cast<std::size_t>(i)] - mean_a[k]) *
             (b[k][static_cast<std::size_t>((i + shift) % steps)] - mean_b[k]);
      }
    }
    if (c > best_c) {
      best_c = c;
      best = shift;
    }
  }
  signal::LowPassFilter impulse(filter);
  double h2 = 0.0;
  for (int n = 0; n < 4000; ++n) {
    const double h = impulse.step(n == 0 ? 1.0 : 0.0);
    h2 += h * h;
  }
  std::array<double, 3> out{};
  for (std::size_t k = 0; k < 3; ++k) {
    double d2 = 0.0;
    for (int i = 0; i < steps; ++i) {
      const double d =
          a[k][static_cast<std::size_t>(i)] - b[k][static_cast<std::size_t>((i + best) % steps)];
      d2 += d * d / steps;
    }
    out[k] = std::sqrt(d2 + noise_N * noise_N * h2);
  }
  return out;
}

/// RMS over the revolutions of the per-revolution residual RMS, per axis.
std::array<double, 3> measured_residual_N(const std::vector<RevolutionRecord>& revolutions) {
  std::array<double, 3> sum{};
  int n = 0;
  for (const auto& r : revolutions) {
    if (!r.model_valid) {
      continue;
    }
    for (std::size_t k = 0; k < 3; ++k) {
      sum[k] += r.residual_rms_N[k] * r.residual_rms_N[k];
    }
    ++n;
  }
  for (double& v : sum) {
    v = n > 0 ? std::sqrt(v / n) : std::nan("");
  }
  return sum;
}

sim::Scenario fine_cut() {
  sim::Scenario s;  // [000]'s cp-Ti slot, rigid: each revolution repeats
  s.sample_rate_hz = 50000.0;
  s.duration_s = 0.6;
  s.spindle.actual_rpm = 25252.0;
  s.model.effects.deflection.enabled = false;
  s.model.effects.accumulation.enabled = false;
  s.noise.enabled = true;
  s.noise.sigma_N = {0.02, 0.02, 0.02};
  // The cut is simulated finer than the monitor models it: 0.125° and 20 helix discs.
  s.model.resolution.steps_per_rev = 2880;
  s.model.effects.helix_lag.discs = 20;
  return s;
}

/// Replays `s` with the model revolution kept (the default) and measured anew on every turn,
/// and compares every turn after the model's last alignment.
void expect_kept_model_revolution_as_measured_anew(const sim::Scenario& s,
                                                   ToothEventKind expected_kind) {
  const Recording recording = record(s);
  Collector kept, anew;
  Pipeline p(monitor_for(s), kept);
  replay(p, recording, 1000);
  Pipeline q(monitor_for(s), anew);
  q.keep_model_revolution(false);
  replay(q, recording, 1000);
  ASSERT_TRUE(p.lockstep().aligned());
  EXPECT_EQ(p.event_template().kind, expected_kind);
  ASSERT_EQ(kept.revolutions.size(), anew.revolutions.size());
  const auto after_alignment = [&](const RevolutionRecord& r) {
    return r.model_valid && r.model.valid && r.model_offset_rad == p.lockstep().offset_rad();
  };
  double alpha_low_deg = 360.0, alpha_high_deg = 0.0, alpha_sum_deg = 0.0;
  double fy_low_N = 1e9, fy_high_N = -1e9, fy_sum_N = 0.0;
  int turns = 0;
  for (const auto& r : anew.revolutions) {
    if (after_alignment(r)) {
      alpha_low_deg = std::min(alpha_low_deg, r.model.alpha_deg);
      alpha_high_deg = std::max(alpha_high_deg, r.model.alpha_deg);
      alpha_sum_deg += r.model.alpha_deg;
      fy_low_N = std::min(fy_low_N, r.model.delta_fy_N);
      fy_high_N = std::max(fy_high_N, r.model.delta_fy_N);
      fy_sum_N += r.model.delta_fy_N;
      ++turns;
    }
  }
  ASSERT_GE(turns, 300);  // ~420 turns in the second
  double kept_alpha_sum_deg = 0.0, kept_fy_sum_N = 0.0, worst_event_samples = 0.0;
  int compared = 0, placed = 0;
  for (std::size_t i = 0; i < kept.revolutions.size(); ++i) {
    const RevolutionRecord& r = kept.revolutions[i];
    const RevolutionRecord& a = anew.revolutions[i];
    ASSERT_EQ(r.model_valid, a.model_valid) << r.revolution;
    if (r.model_valid) {  // the same model rows over the measured windows
      for (std::size_t k = 0; k < 3; ++k) {
        EXPECT_NEAR(r.residual_rms_N[k], a.residual_rms_N[k], 1e-9) << r.revolution;
      }
    }
    if (!after_alignment(r)) {
      continue;
    }
    ++compared;
    // The model's events where its valleys or pulses are on this turn (measured anew they move
    // with the turn's phase and the searches' starts).
    for (int k = 0; k <= r.model.flutes; ++k) {
      const auto uk = static_cast<std::size_t>(k);
      worst_event_samples = std::max(
          worst_event_samples, std::fabs(r.model.event_sample[uk] - a.model.event_sample[uk]));
    }
    kept_alpha_sum_deg += r.model.alpha_deg;
    kept_fy_sum_N += r.model.delta_fy_N;
    EXPECT_GE(r.model.alpha_deg, alpha_low_deg - 0.02) << r.revolution;
    EXPECT_LE(r.model.alpha_deg, alpha_high_deg + 0.02) << r.revolution;
    EXPECT_GE(r.model.delta_fy_N, fy_low_N - 0.001) << r.revolution;
    EXPECT_LE(r.model.delta_fy_N, fy_high_N + 0.001) << r.revolution;
    // A placed turn's model period is its speed's (its events' filtered period); the turns the
    // model revolution was measured on have their valleys' own.
    if (r.spindle_rpm > 0.0 && std::fabs(r.model.period_s * r.spindle_rpm / 60.0 - 1.0) <= 1e-9) {
      ++placed;
    }
  }
  const double kept_alpha_deg = kept_alpha_sum_deg / compared;
  const double kept_fy_N = kept_fy_sum_N / compared;
  std::printf(
      "measured anew every turn: model α %.3f–%.3f° (mean %.3f°), ΔFy %.4f–%.4f N (mean %.4f N); "
      "kept: mean α %.3f°, ΔFy %.4f N, events within %.3f samples of those measured anew, "
      "%d of %d turns placed\n",
      alpha_low_deg, alpha_high_deg, alpha_sum_deg / turns, fy_low_N, fy_high_N, fy_sum_N / turns,
      kept_alpha_deg, kept_fy_N, worst_event_samples, placed, compared);
  EXPECT_EQ(compared, turns);
  EXPECT_GE(placed, compared - 40);  // all but the turns the kept one was measured on
  // Within a quarter of a degree: the searches' starts and the turns' phases measured anew
  // spread α over 0.7–4.5° (a sample is 3° at 50 kHz, 1.4° at 333.3 kHz's measuring rate).
  EXPECT_NEAR(kept_alpha_deg, alpha_sum_deg / turns, 0.25);
  EXPECT_NEAR(kept_fy_N, fy_sum_N / turns, 0.002 * std::fabs(fy_sum_N / turns) + 1e-4);
  EXPECT_LT(worst_event_samples, 1.5);
}

// The model revolution is measured on the first turns of a model and alignment, and their mean
// placed on each later turn by its angle map, instead of measured anew on every turn: in cuts
// with noise and hum, at 50 and 333.3 kHz, with valleys and with pulses, the kept model's α and
// ΔFy are what measuring anew on every turn gives on average (which moves with the turn's
// sub-sample phase and the measured events the model's searches start from), α within a
// quarter of a degree, and every turn's within its spread; the residuals are the same.
TEST(Pipeline, AModelRevolutionKeptPerModelIsWhatMeasuringItEveryTurnGives) {
  sim::Scenario s = cut_at_50khz(true);
  expect_kept_model_revolution_as_measured_anew(s, ToothEventKind::kValley);
  s.sample_rate_hz = 333300.0;
  expect_kept_model_revolution_as_measured_anew(s, ToothEventKind::kValley);
  s = cut_at_50khz(true);
  s.model.process.operation = model::Operation::kDownMilling;  // 10 %: a pulse per flute
  s.model.process.radial_depth_mm = 0.1 * s.model.tool.diameter_mm;
  expect_kept_model_revolution_as_measured_anew(s, ToothEventKind::kCentroid);
}

// Issue 6 §7: the simulated truth differs from the lockstep model in discretisation (0.125° and
// 20 discs against 0.5° and 5): the residual is that known difference plus the filtered noise.
TEST(Pipeline, ResidualIsTheKnownDifferenceOfAFinerTruth) {
  const sim::Scenario s = fine_cut();
  MonitorConfig c = monitor_for(s);
  c.model.resolution.steps_per_rev = 720;
  c.model.effects.helix_lag.discs = 5;
  Collector out;
  Pipeline p(c, out);
  replay(p, record(s), 1000);
  const auto measured = measured_residual_N(out.revolutions);
  const auto expected = expected_residual_N(s, c.model, 0.02, p.filter());
  for (std::size_t k = 0; k < 2; ++k) {
    std::printf("axis %zu: residual %.4f N, expected %.4f N\n", k, measured[k], expected[k]);
    EXPECT_NEAR(measured[k], expected[k], 0.25 * expected[k]) << "axis " << k;
  }
}

// The lock aligns the model on its template average, whose angle is the tracker's; each
// revolution's samples are placed by its own tooth events, which a different estimator finds
// (on the simulated cuts the two offsets lay 2–6° apart). The model is aligned on the lock's
// first revolution and states no residual before: the first window's residuals are those of
// the later revolutions (19 and 36 times them at 50 and 333.3 kHz, 7 times for the 3-flute
// slot, while the template's offset held a window), from the lock's first revolution on.
TEST(Pipeline, TheLocksFirstWindowIsAlignedAsTheRest) {
  sim::Scenario fast = cut_at_50khz(true);
  fast.sample_rate_hz = 333300.0;
  fast.duration_s = 0.5;
  for (const sim::Scenario& s :
       {cut_at_50khz(true), fast, test::three_flute_cut_with_runout(0.6)}) {
    MonitorConfig c = monitor_for(s);
    c.model.resolution.steps_per_rev = 720;
    Collector out;
    Pipeline p(c, out);
    replay(p, record(s), 1000);
    ASSERT_EQ(out.count(PipelineEventKind::kLockAcquired), 1);
    const PipelineEvent* first = out.first(PipelineEventKind::kModelAligned);
    ASSERT_NE(first, nullptr);
    EXPECT_EQ(first->count, 1);  // on the first revolution measured
    double first_window = 0.0, later = 0.0;
    int n_first = 0, n_later = 0;
    for (const RevolutionRecord& r : out.revolutions) {
      if (r.revolution > 0 && r.measured.bounded) {
        EXPECT_TRUE(r.model_valid) << r.revolution;
      }
      if (!r.model_valid) {
        continue;
      }
      (r.revolution < c.sync_window_revolutions ? first_window : later) += r.residual_rms_N[0];
      ++(r.revolution < c.sync_window_revolutions ? n_first : n_later);
    }
    ASSERT_GE(n_first, c.sync_window_revolutions - 1);
    ASSERT_GT(n_later, 100);
    first_window /= n_first;
    later /= n_later;
    std::printf("%.1f kHz, %d flutes: residual fx %.4f N over the first window, %.4f N after\n",
                s.sample_rate_hz / 1e3, s.model.tool.flutes, first_window, later);
    EXPECT_LT(first_window, 1.3 * later);
  }
}

/// The 50 kHz cut with its first `knocked` revolutions replaced by the samples half a turn
/// later (a knock: the same valleys, the flutes' forces swapped — runout 1.82 µm against
/// 4 µm/tooth, one flute cuts far more), replayed with the lockstep model.
double median_of(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

/// A Collector that gives the run summary each revolution and event in the sink's order.
struct SummarizingCollector : Collector {
  RunSummary* summary = nullptr;
  void on_revolution(const RevolutionRecord& r) override {
    Collector::on_revolution(r);
    summary->add(r);
  }
  void on_event(const PipelineEvent& e) override {
    Collector::on_event(e);
    summary->add(e);
  }
};

/// The number of the first revolution `out` heard after `utime_us` (−1: none).
std::int64_t first_revolution_after(const Collector& out, std::int64_t utime_us) {
  const auto r =
      std::find_if(out.revolutions.begin(), out.revolutions.end(),
                   [utime_us](const RevolutionRecord& x) { return x.utime_us > utime_us; });
  return r == out.revolutions.end() ? -1 : r->revolution;
}

struct KnockedCut {
  sim::Scenario scenario = cut_at_50khz(true);
  MonitorConfig config;
  std::optional<RunSummary> summary;
  SummarizingCollector out;
  double per_rev = 0.0;         // samples a revolution (118.8)
  double after_knock_us = 0.0;  // a revolution after the knocked samples (low-pass delay)
  PipelineStatus status;
  /// The flutes' forces swapped (the samples half a turn on) over `knocked` revolutions from
  /// revolution `from` of the record; each window identified (handed over when due) if told; the
  /// cut stopped (amplifier noise alone, 0.01 N) over `quiet` revolutions from `quiet_from`.
  explicit KnockedCut(double knocked, double from = 0.0, bool identify = false,
                      double quiet_from = 0.0, double quiet = 0.0) {
    const sim::Scenario& s = scenario;
    per_rev = s.sample_rate_hz * 60.0 / s.spindle.actual_rpm;
    Recording r = knocked_record(s, knocked, from);
    const auto swapped = static_cast<std::size_t>((from + knocked) * per_rev);
    std::mt19937 noise(7);
    std::normal_distribution<double> amplifier(0.0, 0.01);
    for (auto i = static_cast<std::size_t>(quiet_from * per_rev);
         i < static_cast<std::size_t>((quiet_from + quiet) * per_rev); ++i) {
      r.fx[i] = amplifier(noise);
      r.fy[i] = amplifier(noise);
      r.fz[i] = amplifier(noise);
    }
    after_knock_us = 1e6 * (static_cast<double>(swapped) + per_rev) / s.sample_rate_hz;
    config = monitor_for(s);
    config.model.resolution.steps_per_rev = 720;
    out.summary = &summary.emplace(config);
    Pipeline p(config, out);
    if (!identify) {
      replay(p, r, 1000);
      status = p.status();
      return;
    }
    const signal::ButterworthDesign filter = p.filter();
    identify::Identifier identifier(
        config.model, [filter](double hz) { return filter.response(hz); }, identify::FitOptions{},
        [](const identify::IdentifiedWindow&) {}, identify::HandOver::kWait);
    p.attach_identifier(&identifier);
    replay(p, r, 1000);
    p.attach_identifier(nullptr);
    identifier.finish();
    status = p.status();
  }
  /// The cut's own residual on fx: the median after the first window.
  [[nodiscard]] double cut_residual_N() const {
    std::vector<double> later;
    for (const RevolutionRecord& rv : out.revolutions) {
      if (rv.model_valid && rv.revolution >= config.sync_window_revolutions) {
        later.push_back(rv.residual_rms_N[0]);
      }
    }
    EXPECT_GT(later.size(), 300U);
    if (later.empty()) {
      return 0.0;
    }
    std::nth_element(later.begin(), later.begin() + static_cast<std::ptrdiff_t>(later.size() / 2),
                     later.end());
    return later[later.size() / 2];
  }
  /// The first window's bounded revolutions wholly after the knocked samples: their worst fx
  /// residual, how many state one, how many there are; each from `modelled_from_us` on is
  /// expected to state one.
  struct AfterKnock {
    double worst_N = 0.0;
    int modelled = 0;
    int revolutions = 0;
  };
  [[nodiscard]] AfterKnock first_window_after_knock(std::int64_t modelled_from_us) const {
    AfterKnock a;
    for (const RevolutionRecord& rv : out.revolutions) {
      if (static_cast<double>(rv.utime_us) < after_knock_us || !rv.measured.bounded ||
          rv.revolution >= config.sync_window_revolutions) {
        continue;
      }
      ++a.revolutions;
      if (rv.utime_us >= modelled_from_us) {
        EXPECT_TRUE(rv.model_valid) << rv.revolution;
      }
      a.worst_N = std::max(a.worst_N, rv.model_valid ? rv.residual_rms_N[0] : 0.0);
      a.modelled += rv.model_valid ? 1 : 0;
    }
    return a;
  }
};

// A lock's first alignment rests on one revolution, checked against the lock's template: a
// first revolution unlike the cut (a tool entering, a knock) would put the model a pitch off,
// and every residual until the next alignment with it. Here the record's first 2.5 revolutions
// are knocked (KnockedCut). The first revolution, wholly swapped, is refused and the average
// starts again without it; the next (partly swapped, its peak within a quarter pitch) is taken
// alone, and every revolution after the swapped samples has a residual like the cut's. Taken,
// the first left the next three at 0.5-0.6 N (60x the cut's); refused but kept in the average,
// 15 revolutions up to 0.045 N.
TEST(Pipeline, AFirstRevolutionUnlikeTheCutDoesNotAlignTheModelAPitchOff) {
  const KnockedCut k(2.5);
  const Collector& out = k.out;
  ASSERT_EQ(out.count(PipelineEventKind::kLockAcquired), 1);
  // The first revolution (swapped) refused, and the average started again: the model aligned
  // on one later revolution alone, the first stating no residual.
  const PipelineEvent* aligned = out.first(PipelineEventKind::kModelAligned);
  ASSERT_NE(aligned, nullptr);
  ASSERT_FALSE(out.revolutions.empty());
  EXPECT_FALSE(out.revolutions.front().model_valid);
  EXPECT_EQ(aligned->count, 1);
  EXPECT_GT(static_cast<double>(aligned->utime_us - out.revolutions.front().utime_us),
            0.5e6 * k.per_rev / k.scenario.sample_rate_hz);
  const double cut_N = k.cut_residual_N();
  // Every one of them states a residual.
  const auto after = k.first_window_after_knock(std::numeric_limits<std::int64_t>::min());
  std::printf(
      "residual fx: worst %.4f N in the first window after the swapped revolutions "
      "(%d), the cut's %.4f N\n",
      after.worst_N, after.modelled, cut_N);
  EXPECT_GE(after.modelled, k.config.sync_window_revolutions - 5);
  EXPECT_LT(after.worst_N, 3.5 * cut_N);
}

// The same knock, nine and a half revolutions long: more of them than the lock's first window
// starts its average again for (kFirstAlignmentRestarts, 4). Each of the first four refused
// alignments starts the average again on the next revolution; the fifth keeps the template's
// alignment and lets the average grow, as it doubles, until it holds more of the cut than of the
// knock. With the bound, the model aligns on an average of several revolutions (16 here), within
// the first window, and states the cut's residual from then on. Without it (tried: a bound of
// 1,000), every knocked revolution started the average again, the first revolution after the
// knock aligned the model alone, and the first window's residuals reached 0.19 N, 20x the cut's.
TEST(Pipeline, ALongKnockAtTheLockStartsTheAverageAgainAtMostFourTimes) {
  const KnockedCut k(9.5);
  const Collector& out = k.out;
  ASSERT_EQ(out.count(PipelineEventKind::kLockAcquired), 1);
  const PipelineEvent* aligned = out.first(PipelineEventKind::kModelAligned);
  ASSERT_NE(aligned, nullptr);
  // Aligned on an average that grew past the restarts (one revolution, had it started again at
  // every knocked one), before a full window.
  EXPECT_GT(aligned->count, 1);
  EXPECT_LT(aligned->count, k.config.sync_window_revolutions);
  const double cut_N = k.cut_residual_N();
  // Every revolution wholly after the knock that states a residual states the cut's, and all of
  // them state one from the first alignment on.
  const auto after = k.first_window_after_knock(aligned->utime_us);
  std::printf(
      "first alignment on %lld revolutions; residual fx: worst %.4f N in the first window after "
      "the knock (%d of %d revolutions with a model), the cut's %.4f N\n",
      static_cast<long long>(aligned->count), after.worst_N, after.modelled, after.revolutions,
      cut_N);
  EXPECT_GT(after.modelled, 0);
  EXPECT_LT(after.worst_N, 3.5 * cut_N);
}

// A knock longer than the lock's windows (20.5 revolutions): the lock's template holds the
// knock, so flute 1, labelled CE1 there, is the weaker flute once the knock is over, and α and
// ΔFy come from the other edge (α 201.5° where the cut's is 158.5°). The first full window
// since the lock says so: the pipeline locks again and its template chooses CE1 afresh; α and
// ΔFy are the cut's from there on, the revolutions measured in between lose the part of one
// between the two CE1 events, and the run summary states α since the relabelling, with a
// warning. A knock shorter than the lock's windows relabels nothing.
TEST(Pipeline, AKnockLongerThanTheLocksWindowsRelabelsTheFlutes) {
  const KnockedCut knocked(20.5);
  const Collector& out = knocked.out;
  ASSERT_EQ(out.count(PipelineEventKind::kFlutesRelabelled), 1);
  const PipelineEvent& relabel = *out.first(PipelineEventKind::kFlutesRelabelled);
  EXPECT_EQ(relabel.count, 2);    // flute 2 of the lock's labelling
  EXPECT_GT(relabel.value, 1.1);  // held clearly more force than CE1
  EXPECT_EQ(out.count(PipelineEventKind::kLockAcquired), 2);
  // Before: α from the other edge; after: the cut's (truth 155°, as the short knock's below).
  std::vector<double> before, after;
  for (const RevolutionRecord& r : out.revolutions) {
    if (r.measured.valid) {
      (r.utime_us < relabel.utime_us ? before : after).push_back(r.measured.alpha_deg);
    }
  }
  std::printf(
      "relabelled at t = %.4f s (flute %lld, %.2f times CE1's force); valid revolutions "
      "%zu before, %zu after, %zu in all\n",
      1e-6 * static_cast<double>(relabel.utime_us), static_cast<long long>(relabel.count),
      relabel.value, before.size(), after.size(), out.revolutions.size());
  ASSERT_GE(before.size(), 20U);
  ASSERT_GE(after.size(), 300U);
  // The same cut without the knock: its α, its revolutions.
  const KnockedCut unknocked(0.0);
  std::vector<double> cut;
  for (const RevolutionRecord& r : unknocked.out.revolutions) {
    if (r.measured.valid) {
      cut.push_back(r.measured.alpha_deg);
    }
  }
  const double cut_alpha_deg = median_of(cut);
  std::printf(
      "alpha: %.2f deg before, %.2f after, the cut's %.2f; revolutions %zu against the "
      "cut's %zu\n",
      median_of(before), median_of(after), cut_alpha_deg, out.revolutions.size(),
      unknocked.out.revolutions.size());
  EXPECT_GT(median_of(before), 180.0);
  EXPECT_NEAR(median_of(after), cut_alpha_deg, 0.5);
  // The revolutions are continuous but for the part of one between the two CE1 events.
  EXPECT_GE(out.revolutions.size() + 2, unknocked.out.revolutions.size());

  const nlohmann::json j = knocked.summary->to_json();
  EXPECT_NEAR(j["alpha_deg"]["mean"].get<double>(), cut_alpha_deg, 0.5) << j["alpha_deg"];
  EXPECT_NE(test::warning_detail(j["warnings"], "flutes relabelled").find("flute 2 held 1."),
            std::string::npos)
      << j["warnings"];
  EXPECT_EQ(test::warning_detail(j["warnings"], "flute labelling"), "") << j["warnings"];

  const KnockedCut short_knock(2.5);
  EXPECT_EQ(short_knock.out.count(PipelineEventKind::kFlutesRelabelled), 0);
  EXPECT_EQ(short_knock.out.count(PipelineEventKind::kLockAcquired), 1);
}

// A knock after a good lock, while the alerts' baseline forms: one of 45 revolutions (a full
// window's flute forces swapped, the next window's a half at most) relabels nothing, where a
// single window's check had relabelled to the weaker flute for the rest of the lock (α 201.5°
// for the cut's 158.5°). One of 120 revolutions relabels twice: to the knock's CE1 once it has
// held two windows, and back to the cut's once the cut has held two windows again; α ends at
// the cut's, and the run summary states α over the revolutions since the last relabelling.
TEST(Pipeline, AKnockAfterAGoodLockRelabelsOnlyIfItLastsAndIsUndoneAfter) {
  const KnockedCut unknocked(0.0);
  std::vector<double> cut;
  for (const RevolutionRecord& r : unknocked.out.revolutions) {
    if (r.measured.valid) {
      cut.push_back(r.measured.alpha_deg);
    }
  }
  ASSERT_GT(cut.size(), 300U);
  const double cut_alpha_deg = median_of(cut);

  const KnockedCut short_knock(45.0, 150.0);
  EXPECT_EQ(short_knock.out.count(PipelineEventKind::kFlutesRelabelled), 0);
  EXPECT_EQ(short_knock.out.count(PipelineEventKind::kLockAcquired), 1);

  const KnockedCut long_knock(120.0, 60.0, true);
  const Collector& out = long_knock.out;
  ASSERT_EQ(out.count(PipelineEventKind::kFlutesRelabelled), 2);
  EXPECT_EQ(out.count(PipelineEventKind::kLockAcquired), 3);
  std::vector<std::int64_t> relabelled_us;
  for (const PipelineEvent& e : out.events) {
    if (e.kind == PipelineEventKind::kFlutesRelabelled) {
      EXPECT_EQ(e.count, 2);  // the other of two flutes, each time
      EXPECT_GT(e.value, kFluteLabellingMargin);
      relabelled_us.push_back(e.utime_us);
    }
  }
  const double knock_end_us = 1e6 * 180.0 * long_knock.per_rev / long_knock.scenario.sample_rate_hz;
  EXPECT_GT(static_cast<double>(relabelled_us[0]),
            1e6 * 60.0 * long_knock.per_rev / long_knock.scenario.sample_rate_hz);
  EXPECT_LT(static_cast<double>(relabelled_us[0]), knock_end_us);
  EXPECT_GT(static_cast<double>(relabelled_us[1]), knock_end_us);
  std::vector<double> after;
  for (const RevolutionRecord& r : out.revolutions) {
    if (r.measured.valid && r.utime_us > relabelled_us[1]) {
      after.push_back(r.measured.alpha_deg);
    }
  }
  std::printf(
      "relabelled at t = %.4f s and %.4f s (knock %.4f-%.4f s); alpha after: %.2f deg "
      "(%zu revolutions), the cut's %.2f\n",
      1e-6 * static_cast<double>(relabelled_us[0]), 1e-6 * static_cast<double>(relabelled_us[1]),
      60.0 * long_knock.per_rev / long_knock.scenario.sample_rate_hz, 1e-6 * knock_end_us,
      after.empty() ? 0.0 : median_of(after), after.size(), cut_alpha_deg);
  ASSERT_GE(after.size(), 60U);
  EXPECT_NEAR(median_of(after), cut_alpha_deg, 0.5);
  // The model takes no identified window from before a relabelling after it (each names the
  // flutes from another CE1): the revolutions after the relabelling's are its lock's.
  std::int64_t labelling_from = 0;
  int updates_after = 0;
  for (const PipelineEvent& e : out.events) {
    if (e.kind == PipelineEventKind::kFlutesRelabelled) {
      labelling_from = first_revolution_after(out, e.utime_us);
      ASSERT_GE(labelling_from, 0);
    } else if (e.kind == PipelineEventKind::kModelUpdated && labelling_from > 0) {
      EXPECT_GE(e.count - long_knock.config.sync_window_revolutions + 1, labelling_from)
          << "a window of revolution " << e.count << " in the labelling from " << labelling_from;
      ++updates_after;
    }
  }
  std::printf(
      "identified windows: %lld taken, %lld rejected, %lld superseded (%d taken after a "
      "relabelling)\n",
      static_cast<long long>(long_knock.status.identifications_taken),
      static_cast<long long>(long_knock.status.identifications_rejected),
      static_cast<long long>(long_knock.status.identifications_superseded), updates_after);
  EXPECT_GT(updates_after, 0);
  EXPECT_GE(long_knock.status.identifications_superseded, 1);
  // The status says so (millwatchd's pipeline_status5_t).
  EXPECT_EQ(long_knock.status.flutes_relabelled, 2);
  EXPECT_EQ(long_knock.status.relabelled_from_revolution, labelling_from);
  // The summary leaves out each relabelled lock's revolutions: the first lock's (the knock came
  // in it) and the second's (on the knock's CE1); it states the third's.
  const nlohmann::json j = long_knock.summary->to_json();
  std::printf("summary: alpha %.2f deg over %lld of %lld valid revolutions\n",
              j["alpha_deg"]["mean"].get<double>(), j["alpha_deg"]["revolutions"].get<long long>(),
              j["revolutions"].get<long long>());
  EXPECT_NEAR(j["alpha_deg"]["mean"].get<double>(), cut_alpha_deg, 0.5) << j["alpha_deg"];
  EXPECT_EQ(j["alpha_deg"]["revolutions"].get<std::size_t>(), after.size());
}

// Fits that wait for the model builder, or are in it, when the flutes are relabelled name the
// flutes from the CE1 before: live, neither reaches the model. The knock of revolutions 60–180
// relabels at revolution 120; the replay holds at revolution 113 until the fits of the windows
// ending at 30 and 60 are done (live, they come late), so that the first is taken into the
// builder (~9 revolutions a build) and the second waits for it when the relabelling comes.
TEST(Pipeline, FitsWaitingForOrInTheBuilderAtARelabellingAreNotTaken) {
  const sim::Scenario s = cut_at_50khz(true);
  const Recording r = knocked_record(s, 120.0, 60.0);
  const double per_rev = s.sample_rate_hz * 60.0 / s.spindle.actual_rpm;
  MonitorConfig c = monitor_for(s);
  c.model.resolution.steps_per_rev = 720;
  Collector out;
  Pipeline p(c, out);
  std::atomic<int> fitted = 0;
  const signal::ButterworthDesign filter = p.filter();
  identify::Identifier identifier(
      c.model, [filter](double hz) { return filter.response(hz); }, identify::FitOptions{},
      [&fitted](const identify::IdentifiedWindow&) { ++fitted; }, identify::HandOver::kWhenReady);
  p.attach_identifier(&identifier);
  constexpr std::size_t kBlock = 200;
  const auto hold_at =
      static_cast<std::int64_t>(113.0 * per_rev) / static_cast<std::int64_t>(kBlock);
  replay(p, r, kBlock, [&](std::int64_t seq, SampleBlock&) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (seq == hold_at && fitted < 2 && std::chrono::steady_clock::now() < until) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return true;
  });
  p.attach_identifier(nullptr);
  identifier.finish();
  ASSERT_GE(fitted, 2);  // else the held fits never came: nothing to test
  std::int64_t labelling_from = 0;
  int before = 0, after = 0;
  for (const PipelineEvent& e : out.events) {
    if (e.kind == PipelineEventKind::kFlutesRelabelled && labelling_from == 0) {
      labelling_from = first_revolution_after(out, e.utime_us);
      ASSERT_GE(labelling_from, 0);
    } else if (e.kind == PipelineEventKind::kModelUpdated) {
      const std::int64_t window_from = e.count - c.sync_window_revolutions + 1;
      ++(labelling_from == 0 ? before : after);
      if (labelling_from > 0) {
        EXPECT_GE(window_from, labelling_from) << "the window of revolution " << e.count;
      }
    }
  }
  const PipelineStatus status = p.status();
  std::printf(
      "relabelled from revolution %lld; model updates %d before, %d after; identified windows: "
      "%lld taken, %lld rejected, %lld superseded\n",
      static_cast<long long>(labelling_from), before, after,
      static_cast<long long>(status.identifications_taken),
      static_cast<long long>(status.identifications_rejected),
      static_cast<long long>(status.identifications_superseded));
  ASSERT_GT(labelling_from, 100);
  ASSERT_LT(labelling_from, 140);
  EXPECT_EQ(before, 0);  // the held fits were not taken before the relabelling
  // The one in the builder and the one waiting (the later windows' fits come after the replay).
  EXPECT_GE(status.identifications_superseded, 2);
}

// A fit of a window from before a lock, done late (live: the worker behind the cut) and taken
// part-way through a later window of the new lock: its alignment was measured in the old
// lock's angle zero, so the model takes the parameters and is aligned again when that window is
// full — on a whole window of this lock's revolutions, not on the few since it started — and
// the residuals stay at the cut's level throughout.
TEST(Pipeline, AFitFromBeforeALockTakenLateIsAlignedWhenTheWindowIsFull) {
  sim::Scenario s = cut_at_50khz(true);
  s.duration_s = 1.2;
  s.spindle.profile = sim::SpindleProfileKind::kStopStart;
  s.spindle.stop_s = 0.4;  // the second lock at ~0.70 s (revolution ~169)
  s.spindle.stop_ramp_s = 0.05;
  s.spindle.stop_hold_s = 0.2;
  MonitorConfig c = monitor_for(s);
  c.model.resolution.steps_per_rev = 720;
  Collector out;
  Pipeline p(c, out);
  // The replay waits 0.3 s into the cut (the first lock) for the worker's first fit, and the
  // worker, after it, until the replay is 0.8 s into the cut (~40 revolutions into the second
  // lock, in its second window); the replay waits there for the worker's next fit. That one is
  // of the oldest window waiting: at most two wait (the older dropped), the first lock's last
  // and the second lock's first, so it is the first lock's, and it is taken there.
  std::atomic<int> fitted = 0;
  std::atomic<bool> held = false;
  const auto wait_for = [](const std::function<bool()>& done) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(120);
    while (!done() && std::chrono::steady_clock::now() < until) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return done();
  };
  const signal::ButterworthDesign filter = p.filter();
  identify::Identifier identifier(
      c.model, [filter](double hz) { return filter.response(hz); }, identify::FitOptions{},
      [&](const identify::IdentifiedWindow&) {
        if (++fitted == 1) {
          wait_for([&] { return held.load(); });
        }
      },
      identify::HandOver::kWhenReady);
  p.attach_identifier(&identifier);
  constexpr std::size_t kBlock = 200;
  const auto block_at = [&](double t_s) {
    return static_cast<std::int64_t>(t_s * s.sample_rate_hz) / static_cast<std::int64_t>(kBlock);
  };
  bool first_in_time = false, second_in_time = false;
  replay(p, record(s), kBlock, [&](std::int64_t seq, SampleBlock&) {
    if (seq == block_at(0.3)) {
      first_in_time = wait_for([&] { return fitted >= 1; });
    } else if (seq == block_at(0.8)) {
      held = true;
      second_in_time = wait_for([&] { return fitted >= 2; });
    }
    return true;
  });
  p.attach_identifier(nullptr);
  identifier.finish();
  ASSERT_TRUE(first_in_time && second_in_time);
  const auto stop_us = static_cast<std::int64_t>(1e6 * s.spindle.stop_s);
  const auto stopped_us =
      static_cast<std::int64_t>(1e6 * (s.spindle.stop_s + s.spindle.stop_ramp_s));
  const std::int64_t second_lock_from = first_revolution_after(out, stopped_us);
  ASSERT_GT(second_lock_from, 0);
  const auto revolution_at = [&](std::int64_t utime_us) {
    return first_revolution_after(out, utime_us);  // (both shifted alike: differences hold)
  };
  const auto is = [](PipelineEventKind kind) {
    return [kind](const PipelineEvent& e) { return e.kind == kind; };
  };
  // Events in the order they came: the second lock, its first full window's alignment.
  const auto events_end = out.events.end();
  const auto second_lock = std::find_if(
      std::find_if(out.events.begin(), events_end, is(PipelineEventKind::kLockAcquired)) + 1,
      events_end, is(PipelineEventKind::kLockAcquired));
  ASSERT_NE(second_lock, events_end);
  const auto first_full = std::find_if(second_lock, events_end, [&](const PipelineEvent& e) {
    return e.kind == PipelineEventKind::kModelAligned && e.count == c.sync_window_revolutions;
  });
  ASSERT_NE(first_full, events_end);
  int driven = 0;
  std::int64_t taken_us = 0;
  for (auto e = first_full; e != events_end; ++e) {
    if (e->kind != PipelineEventKind::kModelUpdated || e->count >= second_lock_from) {
      continue;  // (a fit of this lock's windows comes with its own alignment)
    }
    ++driven;
    taken_us = e->utime_us;
    const auto aligned = std::find_if(e + 1, events_end, is(PipelineEventKind::kModelAligned));
    ASSERT_NE(aligned, events_end) << "never aligned after the fit of window " << e->count;
    EXPECT_EQ(aligned->count, c.sync_window_revolutions) << "aligned on a part of the window";
    const std::int64_t later = revolution_at(aligned->utime_us) - revolution_at(e->utime_us);
    EXPECT_GE(later, 0);
    EXPECT_LE(later, c.sync_window_revolutions);
  }
  ASSERT_GE(driven, 1);
  // The residuals after it, against the first lock's once its model was aligned on a full
  // window (the same cut; noise 0.02 N a sample).
  std::vector<double> level, after;
  for (const RevolutionRecord& r : out.revolutions) {
    if (!r.model_valid) {
      continue;
    }
    const double worst_N = std::max(r.residual_rms_N[0], r.residual_rms_N[1]);
    if (r.revolution >= c.sync_window_revolutions && r.utime_us < stop_us) {
      level.push_back(worst_N);
    } else if (r.utime_us > taken_us) {
      after.push_back(worst_N);
    }
  }
  ASSERT_GE(level.size(), 100U);
  ASSERT_GE(after.size(), 80U);
  std::nth_element(level.begin(), level.begin() + static_cast<std::ptrdiff_t>(level.size() / 2),
                   level.end());
  const double median_N = level[level.size() / 2];
  for (const double x : after) {
    EXPECT_LT(x, 3.0 * median_N);
  }
}

// A relabelling whose lock never comes (the cut stops at once) is over when the cut comes back:
// the lock then is the tracker's own, its labelling checked afresh, and the status names no
// revolution a relabelling's lock started.
TEST(Pipeline, ARelabellingWhoseLockNeverCameIsOverWhenTheCutComesBack) {
  const KnockedCut first(120.0, 60.0);
  const PipelineEvent* relabel = first.out.first(PipelineEventKind::kFlutesRelabelled);
  ASSERT_NE(relabel, nullptr);
  const double relabel_revolution =
      1e-6 * static_cast<double>(relabel->utime_us) * first.scenario.sample_rate_hz / first.per_rev;
  const KnockedCut stopped(120.0, 60.0, false, relabel_revolution + 2.0, 150.0);
  const Collector& out = stopped.out;
  std::printf(
      "relabelled at revolution %.1f; the cut stopped there for 150 revolutions: %d "
      "relabellings, %d locks\n",
      relabel_revolution, out.count(PipelineEventKind::kFlutesRelabelled),
      out.count(PipelineEventKind::kLockAcquired));
  ASSERT_EQ(out.count(PipelineEventKind::kFlutesRelabelled), 1);
  ASSERT_EQ(out.count(PipelineEventKind::kLockAcquired), 2);
  EXPECT_EQ(stopped.status.flutes_relabelled, 1);
  EXPECT_EQ(stopped.status.relabelled_from_revolution, 0);
}

// Issue 6 §7: a lockstep model that leaves runout out misses exactly what runout adds to the
// force: the residual is that known difference (far above the noise), flute by flute unequal.
// (Here runout 1.82 µm against 4 µm/tooth: flute 0 cuts at least 3 µm all along its half turn,
// flute 1 only a pulse in the middle of its own — nothing like the model's two equal pulses.)
TEST(Pipeline, ResidualOfAModelWithoutRunoutIsWhatRunoutAdds) {
  const sim::Scenario s = fine_cut();
  MonitorConfig c = monitor_for(s);
  c.model.resolution.steps_per_rev = 720;
  c.model.effects.helix_lag.discs = 5;
  c.model.effects.runout.enabled = false;
  Collector out;
  Pipeline p(c, out);
  replay(p, record(s), 1000);
  const auto measured = measured_residual_N(out.revolutions);
  const auto expected = expected_residual_N(s, c.model, 0.02, p.filter());
  for (std::size_t k = 0; k < 2; ++k) {
    std::printf("axis %zu: residual %.4f N, expected %.4f N\n", k, measured[k], expected[k]);
    EXPECT_GT(expected[k], 0.1);  // far above the filtered noise (≈ 0.007 N)
    EXPECT_NEAR(measured[k], expected[k], 0.15 * expected[k]) << "axis " << k;
  }
  // Per flute it is the short flute's period that the model misses most... or the long one's:
  // either way the two differ, the signature of runout.
  const auto& last = out.revolutions.back();
  ASSERT_TRUE(last.model_valid);
  const double a = last.residual_flute_rms_N[0];
  const double b = last.residual_flute_rms_N[1];
  EXPECT_GT(std::max(a, b), 1.3 * std::min(a, b));
}

// Issue 6 §4: the measured RMS is the in-plane resultant's, in newtons: √mean(Fx² + Fy²) of the
// filtered force, checked against the noise-free cut through the same filter.
TEST(Pipeline, MeasuredRmsIsTheResultantsInNewtons) {
  sim::Scenario s = fine_cut();
  s.noise.enabled = false;
  const Recording r = record(s);
  Collector out;
  Pipeline p(monitor_for(s), out);
  replay(p, r, 1000);
  signal::LowPassFilter lx(p.filter()), ly(p.filter());
  double sum = 0.0;
  int n = 0;
  for (std::size_t i = 0; i < r.t.size(); ++i) {
    const double x = lx.step(-r.fx[i]);
    const double y = ly.step(-r.fy[i]);
    if (r.t[i] > 0.1) {
      sum += x * x + y * y;
      ++n;
    }
  }
  const double truth = std::sqrt(sum / n);
  double rms = 0.0;
  int m = 0;
  for (const auto& rev : out.revolutions) {
    if (rev.model_valid && rev.utime_us > 100000) {
      rms += rev.measured_rms_N * rev.measured_rms_N;
      ++m;
    }
  }
  ASSERT_GT(m, 100);
  EXPECT_NEAR(std::sqrt(rms / m), truth, 0.01 * truth);
}

// Issue 10: a block going on from the last one has its samples checked as the filter reads them
// (Conditioner::filter_checked: on the grid at 333.3 kHz, every sample at 50 kHz), not in a
// pass of their own before. The two ways give the same run, bit for bit — revolutions, events,
// counters — on a cut with bad samples of every kind (NaN, infinite, implausible, saturated; at
// a block's first sample, its last, within it) and a lost block (a gap: the block after it goes
// the input check's way).
void expect_checked_in_filter_as_apart(double rate_hz) {
  sim::Scenario s = cut_at_50khz(true);
  s.sample_rate_hz = rate_hz;
  s.duration_s = 0.6;
  Recording r = record(s);
  const auto block = static_cast<std::size_t>(std::lround(rate_hz / 1000.0));  // 1 ms
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const std::array<std::pair<std::size_t, double>, 6> bad = {
      std::pair{99 * block, nan},       // a block's first sample, fx
      std::pair{120 * block - 1, inf},  // a block's last, fy below
      std::pair{150 * block + block / 3, -2e6},
      std::pair{180 * block + 7, 1500.0},  // saturated, kept
      std::pair{181 * block + 8, -1500.0},
      std::pair{400 * block + block / 2, nan}};
  for (std::size_t k = 0; k < bad.size(); ++k) {
    std::vector<double>& channel = k % 3 == 0 ? r.fx : k % 3 == 1 ? r.fy : r.fz;
    channel[bad[k].first] = bad[k].second;
  }
  MonitorConfig c = monitor_for(s);
  c.saturation_N = {1000.0, 1000.0, 1000.0};
  Collector in_filter, apart;
  Pipeline p(c, in_filter);
  Pipeline q(c, apart);
  q.check_samples_in_filter(false);
  const auto lose_one = [](std::int64_t seq, SampleBlock&) { return seq != 300; };
  replay(p, r, block, lose_one);
  replay(q, r, block, lose_one);
  ASSERT_GT(in_filter.revolutions.size(), 200u);
  ASSERT_EQ(in_filter.revolutions.size(), apart.revolutions.size());
  for (std::size_t i = 0; i < apart.revolutions.size(); ++i) {
    const RevolutionRecord& a = in_filter.revolutions[i];
    const RevolutionRecord& b = apart.revolutions[i];
    ASSERT_EQ(a.revolution, b.revolution);
    EXPECT_EQ(a.utime_us, b.utime_us) << a.revolution;
    EXPECT_EQ(a.spindle_rpm, b.spindle_rpm) << a.revolution;
    EXPECT_EQ(a.measured.valid, b.measured.valid) << a.revolution;
    EXPECT_EQ(a.measured.alpha_deg, b.measured.alpha_deg) << a.revolution;
    EXPECT_EQ(a.measured.delta_fy_N, b.measured.delta_fy_N) << a.revolution;
    EXPECT_EQ(a.measured.event_sample, b.measured.event_sample) << a.revolution;
    EXPECT_EQ(a.measured_rms_N, b.measured_rms_N) << a.revolution;
    EXPECT_EQ(a.model_valid, b.model_valid) << a.revolution;
    EXPECT_EQ(a.residual_rms_N, b.residual_rms_N) << a.revolution;
  }
  ASSERT_EQ(in_filter.events.size(), apart.events.size());
  for (std::size_t i = 0; i < apart.events.size(); ++i) {
    const PipelineEvent& a = in_filter.events[i];
    const PipelineEvent& b = apart.events[i];
    EXPECT_EQ(a.kind, b.kind) << i;
    EXPECT_EQ(a.sample, b.sample) << i;
    EXPECT_EQ(a.count, b.count) << i;
    EXPECT_EQ(a.value, b.value) << i;
    EXPECT_EQ(a.detail, b.detail) << i;
  }
  EXPECT_EQ(in_filter.spindle.size(), apart.spindle.size());
  EXPECT_EQ(in_filter.alerts.size(), apart.alerts.size());
  const InputCounters& a = p.status().input;
  const InputCounters& b = q.status().input;
  EXPECT_EQ(a.samples_accepted, b.samples_accepted);
  EXPECT_EQ(a.samples_dropped, b.samples_dropped);
  EXPECT_EQ(a.gaps, 1);
  EXPECT_EQ(b.gaps, 1);
  EXPECT_EQ(a.nonfinite_samples, 4);  // NaN, inf, implausible, NaN
  EXPECT_EQ(b.nonfinite_samples, 4);
  EXPECT_EQ(a.saturated_samples, 2);
  EXPECT_EQ(b.saturated_samples, 2);
  EXPECT_EQ(in_filter.count(PipelineEventKind::kNonFinite), 4);
  EXPECT_EQ(in_filter.count(PipelineEventKind::kSaturated), 2);
  std::printf("%zu revolutions, %zu events the same either way\n", apart.revolutions.size(),
              apart.events.size());
}

TEST(Pipeline, SamplesCheckedInTheFilterGiveWhatTheInputCheckGives) {
  for (const double rate_hz : {333300.0, 50000.0}) {
    SCOPED_TRACE(rate_hz);
    expect_checked_in_filter_as_apart(rate_hz);
  }
}

// Bad input is counted and reported; the pipeline keeps measuring.
TEST(Pipeline, BadSamplesGapsAndBadBlocksAreCountedAndSurvived) {
  const sim::Scenario s = cut_at_50khz(true);
  Recording r = record(s);
  r.fx[25437] = std::numeric_limits<double>::quiet_NaN();
  r.fy[35612] = std::numeric_limits<double>::infinity();
  MonitorConfig c = monitor_for(s);
  c.saturation_N = {1.5, 1.5, 1.5};  // the largest forces hit this "range"
  Collector out;
  Pipeline p(c, out);
  replay(p, r, 1000, [](std::int64_t seq, SampleBlock& b) {
    if (seq == 20) {
      b.utime_us -= 40000;  // out of order: older than expected
    }
    if (seq == 30) {
      b.sample_rate_hz = 20000.0;  // wrong rate
    }
    return seq != 40;  // block 40 is lost: a gap of 1000 samples before block 41
  });
  const PipelineStatus st = p.status();
  EXPECT_EQ(st.input.nonfinite_samples, 2);
  EXPECT_GT(st.input.saturated_samples, 0);
  EXPECT_EQ(st.input.out_of_order_blocks, 1);
  EXPECT_EQ(st.input.blocks_rejected, 2);
  // Discontinuities: block 20's slot (its samples came out of order), block 30's slot
  // (rejected at its time), the lost block 40.
  EXPECT_EQ(st.input.gaps, 3);
  // Dropped: block 20 (1000) and the hole it left (1000), block 30 (1000, once), block 40.
  EXPECT_EQ(st.input.samples_dropped, 1000 + 1000 + 1000 + 1000);
  EXPECT_EQ(out.count(PipelineEventKind::kBlockRejected), 2);
  EXPECT_EQ(out.count(PipelineEventKind::kGap), 3);
  EXPECT_EQ(out.count(PipelineEventKind::kNonFinite), 2);
  // Each at its own sample, not its block's first (sample 25,000 had been named for 25,437).
  std::vector<std::int64_t> nonfinite_at;
  for (const auto& e : out.events) {
    if (e.kind == PipelineEventKind::kNonFinite) {
      nonfinite_at.push_back(e.sample);
    }
  }
  EXPECT_EQ(nonfinite_at, (std::vector<std::int64_t>{25437, 35612}));
  // Short gaps are bridged: the spindle kept its lock through all of them.
  EXPECT_EQ(out.count(PipelineEventKind::kLockAcquired), 1);
  EXPECT_EQ(out.count(PipelineEventKind::kLockLost), 0);
  bool sensor_alert = false;
  for (const auto& a : out.alerts) {
    if (a.kind != AlertKind::kSensor) {
      continue;
    }
    sensor_alert = sensor_alert || a.active;
    // Its revolution is the last one reported before it (not a placeholder): the last that
    // started before it, or one or two before that (still open when it came).
    const RevolutionRecord* before = nullptr;
    for (const auto& rev : out.revolutions) {
      before = rev.utime_us <= a.utime_us ? &rev : before;
    }
    const std::int64_t last = before != nullptr ? before->revolution : 0;  // 0: none yet
    EXPECT_LE(a.revolution, last) << a.utime_us;
    EXPECT_GE(a.revolution, std::max<std::int64_t>(last - 2, 0)) << a.utime_us;
  }
  EXPECT_TRUE(sensor_alert);
  // Revolutions are measured again after the last gap (block 41 = 0.82 s).
  ASSERT_FALSE(out.revolutions.empty());
  EXPECT_GT(out.revolutions.back().utime_us, 900000);
}

// A sensor alert raised mid-cut (a lost block) names the revolution it came at — the last one
// reported — as every other alert does, and clears at the next clean health check.
TEST(Pipeline, ASensorAlertNamesTheRevolutionItCameAt) {
  sim::Scenario s = cut_at_50khz(true);
  s.duration_s = 1.6;  // health checks every 0.5 s: the one at 1 s raises, at 1.5 s clears
  const Recording r = record(s);
  Collector out;
  Pipeline p(monitor_for(s), out);
  replay(p, r, 1000, [](std::int64_t seq, SampleBlock&) { return seq != 30; });
  ASSERT_EQ(out.count(PipelineEventKind::kGap), 1);
  const Alert* raised = nullptr;
  const Alert* cleared = nullptr;
  for (const auto& a : out.alerts) {
    if (a.kind == AlertKind::kSensor) {
      (a.active ? raised : cleared) = &a;
    }
  }
  ASSERT_NE(raised, nullptr);
  ASSERT_NE(cleared, nullptr);
  for (const Alert* a : {raised, cleared}) {
    const RevolutionRecord* before = nullptr;  // the last revolution that started before it
    for (const auto& rev : out.revolutions) {
      before = rev.utime_us <= a->utime_us ? &rev : before;
    }
    ASSERT_NE(before, nullptr);
    EXPECT_GT(a->revolution, 200);  // the gap comes 0.6 s into the cut
    EXPECT_LE(a->revolution, before->revolution) << a->utime_us;
    // A revolution is reported once the samples after its end have come (its closing event's
    // search), and its time is the filter-delay-corrected one of its start: one or two that
    // started before the alert may still be open.
    EXPECT_GE(a->revolution, before->revolution - 2) << a->utime_us;
  }
  EXPECT_GT(cleared->revolution, raised->revolution);
  // Raised for the gap and cleared with no new one: both state the gaps.
  EXPECT_EQ(raised->quantity, "new_gaps");
  EXPECT_EQ(raised->value, 1.0);
  EXPECT_EQ(cleared->quantity, "new_gaps");
  EXPECT_EQ(cleared->value, 0.0);
}

// The health checks cover half a second each, the first one too, and the last part of a record
// is checked at its end: ten bad samples in the first block are 0.04 % of the first half second
// (under the 0.1 % limit: no alert; checked over the block alone they read 1 %), and a block
// lost in the last half second raises the sensor alert at the end.
TEST(Pipeline, HealthChecksCoverHalfASecondFromTheStartToTheEnd) {
  const sim::Scenario s = cut_at_50khz(true);
  Recording r = record(s);
  for (int i = 100; i < 110; ++i) {
    r.fx[static_cast<std::size_t>(i)] = std::numeric_limits<double>::quiet_NaN();
  }
  Collector early, late;
  Pipeline pe(monitor_for(s), early);
  replay(pe, r, 1000);
  EXPECT_EQ(pe.status().input.nonfinite_samples, 10);
  for (const auto& a : early.alerts) {
    EXPECT_NE(a.kind, AlertKind::kSensor) << a.message.data();
  }
  Pipeline pl(monitor_for(s), late);
  replay(pl, record(s), 1000, [](std::int64_t seq, SampleBlock&) { return seq != 45; });
  const Alert* raised = nullptr;
  for (const auto& a : late.alerts) {
    raised = a.kind == AlertKind::kSensor && a.active ? &a : raised;
  }
  ASSERT_NE(raised, nullptr);
  EXPECT_GT(raised->utime_us, 920000);  // at the end of the record, after the lost block
  // Raised for the gap, which its message says first (it had led with the bad samples' share,
  // below its limit, and ended "1 new gaps").
  EXPECT_EQ(std::string(raised->message.data())
                .rfind("sensor trouble: 1 new gap in the stream (samples lost); 0.000 % of recent "
                       "samples saturated or not finite (limit 0.100 %)",
                       0),
            0u)
      << raised->message.data();
  EXPECT_EQ(raised->quantity, "new_gaps");  // it had said bad_sample_fraction 0 (limit 0.001)
  EXPECT_EQ(raised->value, 1.0);
  EXPECT_EQ(raised->threshold, 0.0);
}

// A synchronous-average window is named by its last revolution, as identification names it
// (runout_estimate_t and sync_average2_t agree): the revolution reported last before it.
TEST(Pipeline, ASyncAverageIsNamedByItsLastRevolution) {
  struct Sink : test::Collector {
    std::vector<std::pair<std::int64_t, std::int64_t>> named;  // (its revolution, last reported)
    void on_sync_average(const SyncAverage&, const Lockstep*, std::int64_t revolution,
                         std::int64_t) override {
      named.emplace_back(revolution, revolutions.empty() ? -1 : revolutions.back().revolution);
    }
  } out;
  const sim::Scenario s = cut_at_50khz(true);
  Pipeline p(monitor_for(s), out);
  replay(p, record(s), 1000);
  ASSERT_GE(out.named.size(), 5u);
  for (const auto& [revolution, last] : out.named) {
    EXPECT_EQ(revolution, last);
  }
}

// A lock's template over more revolutions than the synchronous average's window (its windows
// follow one another, not slide) is the window's last revolutions: the template's average holds
// a full window, never the few revolutions past a multiple of it (or none: no template, no
// lock). Every window reported after holds its W revolutions.
TEST(Pipeline, ATemplateLongerThanTheWindowTakesItsLastRevolutions) {
  struct Sink : test::Collector {
    std::vector<int> held;  // revolutions in each reported average
    void on_sync_average(const SyncAverage& a, const Lockstep*, std::int64_t,
                         std::int64_t) override {
      held.push_back(a.revolutions());
    }
  };
  const sim::Scenario s = cut_at_50khz(true);
  const Recording r = record(s);
  Sink usual;
  Pipeline pu(monitor_for(s), usual);
  replay(pu, r, 1000);
  for (const int window : {2, 3, 4, 5, 7}) {
    MonitorConfig c = monitor_for(s);
    c.sync_window_revolutions = window;
    c.template_revolutions = 41;
    Sink out;
    Pipeline p(c, out);
    replay(p, r, 1000);
    EXPECT_EQ(out.count(PipelineEventKind::kNoTemplate), 0) << window;
    ASSERT_EQ(out.count(PipelineEventKind::kLockAcquired), 1) << window;
    EXPECT_GE(out.revolutions.size() + 5, usual.revolutions.size()) << window;
    ASSERT_GE(out.held.size(), 10u) << window;
    for (const int held : out.held) {
      EXPECT_EQ(held, window);
    }
    EXPECT_NEAR(out.revolutions.back().alpha_mean_deg, usual.revolutions.back().alpha_mean_deg, 0.3)
        << window;
  }
}

// Every window of revolutions is handed on as it fills, whatever the block size: blocks holding
// several windows' revolutions (calibrate read 4,096 samples at a time: at 50 kHz and 25,252 rpm,
// 34 revolutions; at 20 kHz and 31,831 rpm, 108) gave one window per block and left a third of
// the windows (or two thirds) unfitted.
TEST(Pipeline, EveryWindowOfRevolutionsWhateverTheBlockSize) {
  struct Sink : test::Collector {
    std::vector<std::int64_t> windows;  // their last revolutions
    void on_sync_average(const SyncAverage&, const Lockstep*, std::int64_t revolution,
                         std::int64_t) override {
      windows.push_back(revolution);
    }
  };
  const sim::Scenario s = cut_at_50khz(true);
  const Recording r = record(s);
  Sink small, large;
  Pipeline ps(monitor_for(s), small);
  Pipeline pl(monitor_for(s), large);
  replay(ps, r, 250);
  replay(pl, r, 8192);  // 70 revolutions a block
  const int window = monitor_for(s).sync_window_revolutions;
  ASSERT_GE(small.windows.size(), 5u);
  EXPECT_EQ(large.windows, small.windows);
  for (std::size_t i = 1; i < large.windows.size(); ++i) {
    EXPECT_EQ(large.windows[i] - large.windows[i - 1], window) << i;
  }
}

// At 333.3 kHz (measured on every third sample) a lost block of 1001 samples — not a whole
// number of strides — is bridged: the lock holds, the gap's event names input samples, and the
// revolutions after it are measured at the right times.
TEST(Pipeline, AGapAt333kHzIsBridgedOnTheStride) {
  sim::Scenario s = cut_at_50khz(true);
  s.sample_rate_hz = 333300.0;
  s.duration_s = 0.6;
  const Recording r = record(s);
  Collector whole, holed;
  Pipeline pw(monitor_for(s), whole);
  Pipeline ph(monitor_for(s), holed);
  replay(pw, r, 1001);
  replay(ph, r, 1001, [](std::int64_t seq, SampleBlock&) { return seq != 150; });
  EXPECT_EQ(ph.status().input.samples_dropped, 1001);
  ASSERT_EQ(holed.count(PipelineEventKind::kGap), 1);
  for (const auto& e : holed.events) {
    if (e.kind == PipelineEventKind::kGap) {
      EXPECT_EQ(e.sample, 151 * 1001);  // the first sample after the hole, in input samples
      EXPECT_EQ(e.count, 1001);
    }
  }
  EXPECT_EQ(holed.count(PipelineEventKind::kLockAcquired), 1);
  EXPECT_EQ(holed.count(PipelineEventKind::kLockLost), 0);
  // After the gap, the same revolutions at the same times as without it.
  int after = 0;
  for (const auto& rh : holed.revolutions) {
    if (rh.utime_us < 151 * 1001 * 3 + 20000) {  // µs: the hole ends at 0.4535 s
      continue;
    }
    const RevolutionRecord* rw = at_time(whole.revolutions, rh.utime_us);
    ASSERT_NE(rw, nullptr) << rh.utime_us;
    EXPECT_LE(std::llabs(rw->utime_us - rh.utime_us), 3) << rh.utime_us;
    EXPECT_NEAR(rw->measured.alpha_deg, rh.measured.alpha_deg, 0.5) << rh.utime_us;
    ++after;
  }
  EXPECT_GT(after, 40);
}

TEST(Pipeline, StopStartLosesAndRegainsTheLockAndReZeroesTheDrift) {
  sim::Scenario s = cut_at_50khz(true);
  s.drift.enabled = true;  // the feed hold re-zeroes it
  s.drift.rate_N_per_s = {0.2, -0.2, 0.1};
  s.duration_s = 2.0;
  s.spindle.profile = sim::SpindleProfileKind::kStopStart;
  s.spindle.stop_s = 0.6;
  s.spindle.stop_ramp_s = 0.05;
  s.spindle.stop_hold_s = 0.3;
  Collector out;
  Pipeline p(monitor_for(s), out);
  replay(p, record(s), 1000);
  EXPECT_GE(out.count(PipelineEventKind::kLockLost), 1);
  EXPECT_GE(out.count(PipelineEventKind::kLockAcquired), 2);
  int before = 0, after = 0;
  for (const auto& r : out.revolutions) {
    before += r.utime_us < 600000 ? 1 : 0;
    after += r.utime_us > 1100000 ? 1 : 0;
    EXPECT_FALSE(r.utime_us > 650000 && r.utime_us < 1000000) << "measured while stopped";
  }
  EXPECT_GT(before, 50);
  EXPECT_GT(after, 200);
  // After the stop, the drift of 0.2 N/s up to then is tared away: the peaks are the clean
  // ones again (the drift since the restart, 0.2 N/s for up to 1 s, is not).
  Collector clean;
  sim::Scenario c = s;
  c.drift.enabled = false;
  Pipeline pc(monitor_for(c), clean);
  replay(pc, record(c), 1000);
  int compared = 0;
  for (const auto& r : out.revolutions) {
    const RevolutionRecord* c_r = at_time(clean.revolutions, r.utime_us);
    if (r.utime_us > 1100000 && r.utime_us < 1400000 && c_r != nullptr) {
      const double drift_since_restart = 0.2 * std::hypot(1.0, 1.0) * (r.utime_us * 1e-6 - 0.95);
      EXPECT_NEAR(r.measured.peak_resultant_N[0], c_r->measured.peak_resultant_N[0],
                  drift_since_restart + 0.05);
      ++compared;
    }
  }
  EXPECT_GT(compared, 20);
}

// A lock's first revolutions all count as cutting (RevolutionStats' seed of the usual peak). A
// feed hold just before the lock is decided or a few revolutions after it must not make air
// revolutions cutting ones: the lock measures back to the start of the cut, so its first
// revolutions are the cut's; those after the hold are heard and found not cutting.
TEST(Pipeline, NoRevolutionIsReportedAfterTheToolLeavesTheWorkNearTheLock) {
  sim::Scenario s = cut_at_50khz(true);
  s.duration_s = 0.4;
  // When the lock is decided: the end of the block in which its event came (its time is the
  // centre of the tracker window it was measured in, about half a window earlier).
  constexpr std::size_t kBlock = 100;  // 2 ms
  Collector plain;
  std::int64_t decided_block = -1;
  {
    Pipeline p(monitor_for(s), plain);
    replay(p, record(s), kBlock, [&](std::int64_t seq, SampleBlock&) {
      const bool locked = std::any_of(plain.events.begin(), plain.events.end(), [](const auto& e) {
        return e.kind == PipelineEventKind::kLockAcquired;
      });
      if (locked && decided_block < 0) {
        decided_block = seq - 1;
      }
      return true;
    });
  }
  ASSERT_GT(decided_block, 0);
  const double decided_s =
      static_cast<double>((decided_block + 1) * static_cast<std::int64_t>(kBlock)) /
      s.sample_rate_hz;
  const double turn_s = 60.0 / s.spindle.actual_rpm;
  for (int k = -3; k <= 6; ++k) {  // the feed held k revolutions after the lock is decided
    sim::Scenario c = s;
    c.spindle.profile = sim::SpindleProfileKind::kStopStart;
    c.spindle.stop_s = decided_s + k * turn_s;
    c.spindle.stop_ramp_s = 0.1;  // the spindle runs down in air for 21 revolutions
    c.spindle.stop_hold_s = 1.0;
    Collector out;
    Pipeline p(monitor_for(c), out);
    replay(p, record(c), 1000);
    for (const auto& r : out.revolutions) {
      EXPECT_LT(1e-6 * static_cast<double>(r.utime_us), c.spindle.stop_s)
          << "a revolution starting after the feed hold at " << c.spindle.stop_s << " s";
    }
    // Locked, every revolution before the hold measured (from the cut's start, at t = 0; the
    // last may be cut short), and those after it heard and found not cutting.
    EXPECT_EQ(out.count(PipelineEventKind::kLockAcquired), 1) << k;
    EXPECT_GE(static_cast<double>(out.revolutions.size()), c.spindle.stop_s / turn_s - 2.0) << k;
    EXPECT_EQ(out.count(PipelineEventKind::kCuttingStopped), 1) << k;
  }
}

void steady_state_allocates_nothing(const sim::Scenario& s);

TEST(Pipeline, SteadyStateAllocatesNothing) {
  for (const double fs : {50000.0, 333300.0}) {  // 333.3 kHz: the measuring stride on
    sim::Scenario s = cut_at_50khz(true);
    s.sample_rate_hz = fs;
    s.duration_s = fs > 100000.0 ? 0.6 : 1.0;
    steady_state_allocates_nothing(s);
  }
}

void steady_state_allocates_nothing(const sim::Scenario& s) {
  const Recording r = record(s);
  for (const bool zero_phase : {false, true}) {
    Collector out;
    out.revolutions.reserve(1000);
    out.spindle.reserve(1000);
    out.events.reserve(100);
    out.alerts.reserve(100);
    MonitorConfig c = monitor_for(s);
    c.filter_zero_phase = zero_phase;
    Pipeline p(c, out);
    Recording head = r;
    const std::size_t half = r.t.size() / 2;
    head.t.resize(half);
    head.fx.resize(half);
    head.fy.resize(half);
    head.fz.resize(half);
    replay(p, head, 1000);
    ASSERT_EQ(p.status().state, "measuring");
    test::AllocationCounter counter;
    for (std::size_t i = half; i < r.t.size(); i += 1000) {
      const std::size_t n = std::min<std::size_t>(1000, r.t.size() - i);
      SampleBlock b{std::llround(r.t[i] * 1e6),
                    0,
                    r.sample_rate_hz,
                    std::span(r.fx).subspan(i, n),
                    std::span(r.fy).subspan(i, n),
                    std::span(r.fz).subspan(i, n)};
      p.process(b);
    }
    p.finish();
    EXPECT_EQ(counter.allocations(), 0)
        << (zero_phase ? "zero-phase" : "causal") << " at " << s.sample_rate_hz << " Hz";
    EXPECT_GT(out.revolutions.size(), 120u);
    // The model in lockstep ran through the steady half (kept or measured on each turn).
    EXPECT_TRUE(!out.revolutions.empty() && out.revolutions.back().model_valid &&
                out.revolutions.back().model.valid);
  }
}

}  // namespace
}  // namespace millwatch::monitor
