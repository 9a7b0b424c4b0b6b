// Issue 6: the monitor measures every revolution it can and says plainly when it cannot —
// through speed ramps, on short cuts, at every sample rate, for interrupted cuts and more
// flutes, through a feed hold. The truth is the simulator's: its spindle profile and the
// revolutions it cut.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "core/signal/butterworth_lowpass.hpp"
#include "tests/support/recording.hpp"

namespace millwatch::monitor {
namespace {

using test::Collector;
using test::Recording;

/// The true spindle speed at time t (rpm), interpolated between the truth's revolutions.
double true_rpm_at(const Recording& r, double t_s) {
  for (std::size_t i = 0; i + 1 < r.truth.size(); ++i) {
    if (r.truth[i + 1].start_s >= t_s) {
      const double w = (t_s - r.truth[i].start_s) / (r.truth[i + 1].start_s - r.truth[i].start_s);
      return r.truth[i].spindle_rpm + w * (r.truth[i + 1].spindle_rpm - r.truth[i].spindle_rpm);
    }
  }
  return r.truth.back().spindle_rpm;
}

/// Middle of a measured revolution, s.
double middle_s(const RevolutionRecord& r) {
  return 1e-6 * static_cast<double>(r.utime_us) + 0.5 * r.measured.period_s;
}

/// A 2-flute slot in cp-Ti as [000] (4 µm/tooth, runout 1.82 µm at 0.58 rad), with the
/// measurement errors of a real chain.
sim::Scenario slot(double sample_rate_hz, double duration_s) {
  sim::Scenario s;
  s.sample_rate_hz = sample_rate_hz;
  s.duration_s = duration_s;
  s.spindle.actual_rpm = 25252.0;
  s.model.effects.dynamometer.enabled = true;
  s.model.effects.dynamometer.natural_hz = {4500.0, 4600.0, 6000.0};
  s.noise.enabled = true;
  s.noise.sigma_N = {0.015, 0.015, 0.015};
  s.quantisation.enabled = true;
  s.hum.enabled = true;
  return s;
}

/// slot() at 50 kHz for `duration_s`, the spindle ramping from `from_rpm` at `rpm_per_s` from
/// the first sample for `ramp_s` (then steady), commanded at the ramp's middle.
sim::Scenario slot_on_a_ramp(double duration_s, double from_rpm, double rpm_per_s, double ramp_s) {
  sim::Scenario s = slot(50000.0, duration_s);
  s.spindle.profile = sim::SpindleProfileKind::kRamp;
  s.spindle.actual_rpm = from_rpm;
  s.spindle.ramp_end_rpm = from_rpm + rpm_per_s * ramp_s;
  s.spindle.ramp_start_s = 0.0;
  s.spindle.ramp_end_s = ramp_s;
  s.model.process.spindle_rpm = from_rpm + 0.5 * rpm_per_s * ramp_s;
  return s;
}

struct RampFigures {
  int measured = 0;
  int present = 0;
  double worst_rpm_error = 0.0;
  double rms_rpm_error = 0.0;
};

RampFigures run_ramp(const sim::Scenario& s, double from_s, double to_s) {
  const Recording r = test::record(s);
  Collector out;
  Pipeline p(test::monitor_for(s), out);
  test::replay(p, r, 1000);
  RampFigures f;
  f.present = test::complete_cutting_revolutions(r);
  f.measured = static_cast<int>(out.revolutions.size());
  double sum_sq = 0.0;
  int n = 0;
  for (const auto& rev : out.revolutions) {
    const double t = middle_s(rev);
    if (t < from_s || t > to_s) {
      continue;
    }
    const double error = rev.spindle_rpm - true_rpm_at(r, t);
    f.worst_rpm_error = std::max(f.worst_rpm_error, std::fabs(error));
    sum_sq += error * error;
    ++n;
  }
  f.rms_rpm_error = n > 0 ? std::sqrt(sum_sq / n) : 0.0;
  return f;
}

// Issue 6 §1: a spindle ramping from 23,500 to 26,500 rpm between 0.1 and 0.9 s (25,000
// commanded, 50 kHz, 1 s): every revolution is measured, each with its own speed.
TEST(EveryRevolution, ASpeedRampIsMeasuredRevolutionByRevolution) {
  sim::Scenario s = slot(50000.0, 1.0);
  s.model.effects.dynamometer.enabled = false;
  s.spindle.profile = sim::SpindleProfileKind::kRamp;
  s.spindle.actual_rpm = 23500.0;
  s.spindle.ramp_end_rpm = 26500.0;
  s.spindle.ramp_start_s = 0.1;
  s.spindle.ramp_end_s = 0.9;
  const RampFigures f = run_ramp(s, 0.0, 1.0);
  std::printf(
      "ramp 23,500 → 26,500 rpm: %d of %d revolutions measured; rpm error worst %.1f, "
      "rms %.1f\n",
      f.measured, f.present, f.worst_rpm_error, f.rms_rpm_error);
  EXPECT_GE(f.measured, f.present - 2);
  EXPECT_LE(f.measured, f.present + 1);
  EXPECT_LT(f.rms_rpm_error, 0.001 * 25000.0);
  EXPECT_LT(f.worst_rpm_error, 0.004 * 25000.0);
}

// A cut that starts on a ramp (5,000 and 10,000 rpm/s from 23,000 rpm, commanded at the ramp's
// middle): the lock comes 13 and 22 revolutions in, and the tooth events walk back to the first
// revolution and measure forward from a fit to the CE1 events found on the way. Over 14 a
// straight line was fitted (a parabola's end slope is noisy over few events): its period is the
// span's middle one, 7 revolutions of the ramp ahead of the first (0.39 % off, 90 rpm). A
// parabola is now taken wherever its curvature stands out of the events' scatter: the back-filled
// revolutions state their speed as well as those measured as the cut goes: all within 0.05 %
// (0.025 %, 0.036 %).
TEST(EveryRevolution, ACutStartedOnARampIsBackFilledAtItsOwnSpeed) {
  for (const double rate : {5000.0, 10000.0}) {
    const sim::Scenario s = slot_on_a_ramp(0.3, 23000.0, rate, 0.5);
    const Recording r = test::record(s);
    Collector out;
    Pipeline p(test::monitor_for(s), out);
    test::replay(p, r, 1000);
    const PipelineEvent* lock = out.first(PipelineEventKind::kLockAcquired);
    ASSERT_NE(lock, nullptr) << rate;
    const double lock_s = static_cast<double>(lock->sample) / s.sample_rate_hz;
    int before_lock = 0;
    double worst = 0.0;
    for (const auto& rev : out.revolutions) {
      const double t = middle_s(rev);
      worst = std::max(worst, std::fabs(rev.spindle_rpm / true_rpm_at(r, t) - 1.0));
      before_lock += t < lock_s ? 1 : 0;
    }
    std::printf(
        "%.0f rpm/s: locked at %.3f s, %d revolutions back-filled, %zu of %d measured, "
        "worst %.3f %% off\n",
        rate, lock_s, before_lock, out.revolutions.size(), test::complete_cutting_revolutions(r),
        100.0 * worst);
    EXPECT_GE(before_lock, 12) << rate;
    EXPECT_GE(static_cast<int>(out.revolutions.size()), test::complete_cutting_revolutions(r) - 2);
    EXPECT_LT(worst, 0.0005) << rate;
  }
}

// A cut at about 10,000 rpm that starts on a 4,000 rpm/s ramp (a slower spindle: its tracker
// windows of 10 revolutions are 60 ms, over which the ramp moves the speed 2.4 %, beyond the 1 %
// two windows must agree within). The tracker locked only as the ramp ended (0.64 s), and the
// tooth events could walk back only as far as the ring reaches: 90 of 153 revolutions. It now
// takes three windows on one line of speed for a ramp: locked at 0.13 s, every revolution
// measured from the first, each within 0.5 % of the spindle's speed (0.28 %).
TEST(EveryRevolution, ASlowSpindleRampingFromTheStartIsMeasuredFromItsFirstRevolution) {
  const sim::Scenario s = slot_on_a_ramp(0.8, 10000.0, 4000.0, 0.6);
  const Recording r = test::record(s);
  Collector out;
  Pipeline p(test::monitor_for(s), out);
  test::replay(p, r, 1000);
  const PipelineEvent* lock = out.first(PipelineEventKind::kLockAcquired);
  ASSERT_NE(lock, nullptr);
  const double lock_s = static_cast<double>(lock->sample) / s.sample_rate_hz;
  double worst = 0.0;
  for (const auto& rev : out.revolutions) {
    worst = std::max(worst, std::fabs(rev.spindle_rpm / true_rpm_at(r, middle_s(rev)) - 1.0));
  }
  const int present = test::complete_cutting_revolutions(r);
  std::printf("locked at %.3f s; %zu of %d revolutions measured, worst %.2f %% off\n", lock_s,
              out.revolutions.size(), present, 100.0 * worst);
  EXPECT_LT(lock_s, 0.2);
  EXPECT_GE(static_cast<int>(out.revolutions.size()), present - 3);
  EXPECT_LT(worst, 0.005);
  EXPECT_EQ(out.count(PipelineEventKind::kLockLost), 0);
}

// Issue 6 §1: ±5,000 rpm/s.
TEST(EveryRevolution, FollowsFiveThousandRpmPerSecond) {
  for (const double end_rpm : {27500.0, 22500.0}) {
    sim::Scenario s = slot(50000.0, 1.0);
    s.spindle.profile = sim::SpindleProfileKind::kRamp;
    s.spindle.actual_rpm = 25000.0;
    s.spindle.ramp_end_rpm = end_rpm;
    s.spindle.ramp_start_s = 0.2;
    s.spindle.ramp_end_s = 0.7;
    const RampFigures f = run_ramp(s, 0.0, 1.0);
    std::printf(
        "ramp 25,000 → %.0f rpm in 0.5 s: %d of %d revolutions; rpm error worst %.1f, "
        "rms %.1f\n",
        end_rpm, f.measured, f.present, f.worst_rpm_error, f.rms_rpm_error);
    EXPECT_GE(f.measured, f.present - 2) << end_rpm;
    EXPECT_LT(f.rms_rpm_error, 0.002 * 25000.0) << end_rpm;
    EXPECT_LT(f.worst_rpm_error, 0.006 * 25000.0) << end_rpm;
  }
}

// Issue 6 §2: steady cuts of 0.2 s and more measure at least 90 % of their complete
// revolutions, at 20, 50 and 333.3 kHz.
TEST(EveryRevolution, ShortSteadyCutsAreMeasuredFromTheirFirstRevolution) {
  for (const double fs : {20000.0, 50000.0, 333300.0}) {
    for (const double duration : {0.2, 0.3, 0.5}) {
      const sim::Scenario s = slot(fs, duration);
      const Recording r = test::record(s);
      Collector out;
      Pipeline p(test::monitor_for(s), out);
      test::replay(p, r, fs > 100000.0 ? 3333 : 1000);
      const int present = test::complete_cutting_revolutions(r);
      const auto measured = static_cast<int>(out.revolutions.size());
      std::printf("steady %.1f s at %.1f kHz: %d of %d revolutions measured; %.1f of %.1f heard\n",
                  duration, fs / 1000.0, measured, present, p.status().cutting_revolutions,
                  duration * 25252.0 / 60.0);
      EXPECT_GE(measured, static_cast<int>(std::ceil(0.9 * present))) << fs << " " << duration;
      EXPECT_LE(measured, present + 1);
      // The turns heard while cutting (the summary's revolutions_cutting), to the record's end.
      const double turned = duration * 25252.0 / 60.0;
      EXPECT_NEAR(p.status().cutting_revolutions, turned, 1.0) << fs << " " << duration;
      // The first revolution measured starts within two revolutions of the record's start.
      ASSERT_FALSE(out.revolutions.empty());
      EXPECT_LT(out.revolutions.front().utime_us, std::llround(2.0 * 60.0 / 25252.0 * 1e6) + 200);
      // Each measured with its own speed.
      for (const auto& rev : out.revolutions) {
        EXPECT_NEAR(rev.spindle_rpm, 25252.0, 0.003 * 25252.0) << fs << " " << rev.utime_us;
      }
    }
  }
}

// The turns heard while cutting across a break in the stream (0.1 s lost: longer than a bridged
// gap, so the tracker starts afresh): the part-hop heard before the break counts too, and the
// total stays within a revolution of what the spindle turned in the samples that came.
TEST(EveryRevolution, TurnsHeardAcrossABreakInTheStream) {
  const sim::Scenario s = slot(50000.0, 1.0);
  const Recording r = test::record(s);
  Collector out;
  Pipeline p(test::monitor_for(s), out);
  test::replay(p, r, 1000, [](std::int64_t seq, SampleBlock&) { return seq < 20 || seq >= 25; });
  const double turned = 0.9 * 25252.0 / 60.0;
  std::printf("a 0.1 s break: %.1f of %.1f turns heard\n", p.status().cutting_revolutions, turned);
  EXPECT_NEAR(p.status().cutting_revolutions, turned, 1.0);
  EXPECT_EQ(out.count(PipelineEventKind::kGap), 1);
}

// Issue 6 §2: a record too short for the tracker's windows says so, with the length it needs.
TEST(EveryRevolution, ARecordTooShortSaysWhatItNeeds) {
  const sim::Scenario s = slot(50000.0, 0.015);
  const Recording r = test::record(s);
  Collector out;
  Pipeline p(test::monitor_for(s), out);
  test::replay(p, r, 500);
  EXPECT_TRUE(out.revolutions.empty());
  const PipelineEvent* e = out.first(PipelineEventKind::kRecordTooShort);
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->count, 750);
  // Two windows of 10 revolutions at 25,000 rpm: 2 × 0.024 s.
  EXPECT_NEAR(e->value, 0.048, 1e-9);
}

// A record broken into stretches shorter than the tracker needs (40 ms kept, 80 ms lost: each
// break too long to bridge, so the tracker starts afresh) is too short where it counts, though
// its samples add up to far more: it says so, with its longest stretch, not "no steady signal".
TEST(EveryRevolution, ARecordOfShortStretchesSaysItsLongestStretchIsTooShort) {
  const sim::Scenario s = slot(50000.0, 1.0);
  const Recording r = test::record(s);
  Collector out;
  Pipeline p(test::monitor_for(s), out);
  test::replay(p, r, 1000, [](std::int64_t seq, SampleBlock&) { return seq % 6 < 2; });
  EXPECT_TRUE(out.revolutions.empty());
  EXPECT_EQ(out.count(PipelineEventKind::kNoSteadySignal), 0);
  const PipelineEvent* e = out.first(PipelineEventKind::kRecordTooShort);
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->count, 2000);
  EXPECT_NEAR(e->value, 0.048, 1e-9);
  EXPECT_NE(std::string(e->detail).find("the longest stretch between breaks"), std::string::npos)
      << e->detail;
}

// A sample lost here and there (a damaged row skipped, a DAQ's dropped sample): the gap is
// filled on the line between its neighbours and the filters run on. Bridged like a long gap,
// the filters restarted and their settling hid the tooth events for milliseconds: one bad row
// of PHM 2010's cut 315 (0.1 s) took its revolutions from 15 to 4, here three lost samples in
// 0.4 s cost 6 of 166. Now every revolution of the clean replay is measured, α as in it.
TEST(EveryRevolution, ALostSampleCostsNoRevolution) {
  const sim::Scenario s = slot(50000.0, 0.4);
  const Recording r = test::record(s);
  Collector clean, holed;
  Pipeline p(test::monitor_for(s), clean);
  test::replay(p, r, 1000);
  Pipeline q(test::monitor_for(s), holed);
  test::replay(q, r, 1000, [](std::int64_t seq, SampleBlock& b) {
    if (seq % 5 == 0 && seq > 0) {  // blocks at 0.1, 0.2 and 0.3 s lose their first sample
      b.utime_us += 20;
      b.fx_N = b.fx_N.subspan(1);
      b.fy_N = b.fy_N.subspan(1);
      b.fz_N = b.fz_N.subspan(1);
    }
    return true;
  });
  ASSERT_GT(clean.revolutions.size(), 150u);
  ASSERT_EQ(holed.count(PipelineEventKind::kGap), 3);
  EXPECT_EQ(
      std::string(holed.first(PipelineEventKind::kGap)->detail).rfind("filled on the line", 0), 0u);
  const auto mean_alpha = [](const Collector& c) {
    double sum = 0.0;
    int n = 0;
    for (const auto& rev : c.revolutions) {
      if (rev.measured.valid) {
        sum += rev.measured.alpha_deg;
        ++n;
      }
    }
    return n > 0 ? sum / n : 0.0;
  };
  std::printf("%zu revolutions with the lost samples, %zu without; alpha %.3f and %.3f deg\n",
              holed.revolutions.size(), clean.revolutions.size(), mean_alpha(holed),
              mean_alpha(clean));
  EXPECT_EQ(holed.revolutions.size(), clean.revolutions.size());
  EXPECT_NEAR(mean_alpha(holed), mean_alpha(clean), 0.05);
}

// Issue 6 §10: during a feed hold (the spindle decelerates to rest, dwells, restarts) nothing
// is measured, the pipeline says "no cutting", and it measures again within 0.1 s of the
// restart.
TEST(EveryRevolution, AFeedHoldIsNotMeasuredAndTheRestartIsReacquiredQuickly) {
  sim::Scenario s = slot(50000.0, 1.5);
  s.spindle.profile = sim::SpindleProfileKind::kStopStart;
  s.spindle.stop_s = 0.5;
  s.spindle.stop_ramp_s = 0.05;
  s.spindle.stop_hold_s = 0.2;
  const double restart_s = 0.5 + 0.05 + 0.2 + 0.05;  // back at speed: cutting resumes
  const Recording r = test::record(s);
  Collector out;
  Pipeline p(test::monitor_for(s), out);
  bool said_no_cutting = false;
  std::int64_t next = 0;
  test::replay(p, r, 1000, [&](std::int64_t, SampleBlock& b) {
    if (b.utime_us > 650000 && b.utime_us < 740000 && p.status().state == "no cutting") {
      said_no_cutting = true;
      // The spindle stands: no speed is stated (not the last revolution's 25,252 rpm).
      EXPECT_EQ(p.status().spindle_rpm, 0.0) << b.utime_us;
    }
    next = b.utime_us;
    return true;
  });
  EXPECT_TRUE(said_no_cutting);
  // No lock while the spindle slows, stands or speeds up.
  double relock_s = 0.0;
  for (const auto& e : out.events) {
    if (e.kind == PipelineEventKind::kLockAcquired) {
      const double t = 1e-6 * static_cast<double>(e.utime_us);
      EXPECT_FALSE(t > 0.505 && t < restart_s) << "locked at " << t << " s while stopped";
      if (t > restart_s && relock_s == 0.0) {
        relock_s = t;
      }
    }
  }
  // The tracker's lock (at its window's centre) comes within 0.1 s of the restart, and the
  // revolutions since the restart are all measured.
  ASSERT_GT(relock_s, 0.0);
  std::printf("feed hold: locked again %.3f s after the restart\n", relock_s - restart_s);
  EXPECT_LT(relock_s - restart_s, 0.1);
  int before = 0, during = 0, after = 0;
  for (const auto& rev : out.revolutions) {
    const double t = 1e-6 * static_cast<double>(rev.utime_us);
    before += t < 0.5 ? 1 : 0;
    during += t > 0.502 && t < restart_s - 0.002 ? 1 : 0;
    after += t > restart_s ? 1 : 0;
  }
  EXPECT_EQ(during, 0);
  EXPECT_GE(before, test::complete_cutting_revolutions(r) * 0 + 200);
  const int present_after = static_cast<int>((r.duration_s - restart_s) * 25252.0 / 60.0);
  EXPECT_GE(after, present_after - 3);
}

/// Each flute's mean peak in-plane force, the truth: the simulated cut without measurement
/// errors, through the pipeline's low-pass filter, its largest resultant within one pitch
/// around the instant the flute is half-way through its engagement (spindle angle from the
/// simulator's steady speed, plus half the helix lag and the filter's delay). Flute j of the
/// model, in the order of rotation.
std::vector<double> true_flute_peaks(sim::Scenario s) {
  s.noise.enabled = s.quantisation.enabled = s.hum.enabled = s.drift.enabled = false;
  const Recording r = test::record(s);
  const MonitorConfig config = test::monitor_for(s);
  Collector unused;
  const Pipeline p(config, unused);
  std::array<signal::LowPassFilter, 2> lowpass = {signal::LowPassFilter(p.filter()),
                                                  signal::LowPassFilter(p.filter())};
  const auto& c = s.model;
  const int flutes = c.tool.flutes;
  const double f_hz = sim::actual_rpm(s) / 60.0;
  const double radius_mm = 0.5 * c.tool.diameter_mm;
  const double engaged_rad =
      std::acos((radius_mm - c.process.radial_depth_mm) / radius_mm);  // [000] eq 28
  double mid_rad = 0.5 * std::numbers::pi;                             // slot
  if (c.process.operation == model::Operation::kUpMilling) {
    mid_rad = 0.5 * engaged_rad;
  } else if (c.process.operation == model::Operation::kDownMilling) {
    mid_rad = std::numbers::pi - 0.5 * engaged_rad;
  }
  const double lag_rad =
      c.process.axial_depth_mm * std::tan(c.tool.helix_deg * std::numbers::pi / 180.0) / radius_mm;
  const double delay_s = p.filter().group_delay_s(f_hz * flutes);
  std::vector<double> resultant(r.t.size());
  for (std::size_t n = 0; n < r.t.size(); ++n) {
    const double x = -r.fx[n];  // the default axis map: the dynamometer reads −F
    const double y = -r.fy[n];
    if (n == 0) {
      lowpass[0].settle(x);
      lowpass[1].settle(y);
    }
    resultant[n] = std::hypot(lowpass[0].step(x), lowpass[1].step(y));
  }
  std::vector<double> sum(static_cast<std::size_t>(flutes), 0.0);
  int revolutions = 0;
  const double fs = s.sample_rate_hz;
  for (int rev = 3;; ++rev) {
    bool complete = true;
    std::vector<double> peak(static_cast<std::size_t>(flutes), 0.0);
    for (int j = 0; j < flutes && complete; ++j) {
      const double angle = mid_rad + 0.5 * lag_rad + 2.0 * std::numbers::pi * j / flutes;
      const double centre_s = (rev + angle / (2.0 * std::numbers::pi)) / f_hz + delay_s;
      const double half_s = 0.5 / (f_hz * flutes);
      const auto from = static_cast<std::size_t>((centre_s - half_s) * fs);
      const auto to = static_cast<std::size_t>((centre_s + half_s) * fs);
      complete = to + 1 < resultant.size();
      for (std::size_t n = from; complete && n <= to; ++n) {
        peak[static_cast<std::size_t>(j)] =
            std::max(peak[static_cast<std::size_t>(j)], resultant[n]);
      }
    }
    if (!complete) {
      break;
    }
    for (int j = 0; j < flutes; ++j) {
      sum[static_cast<std::size_t>(j)] += peak[static_cast<std::size_t>(j)];
    }
    ++revolutions;
  }
  for (double& v : sum) {
    v /= revolutions;
  }
  return sum;
}

/// Largest relative difference between the monitor's mean flute peaks (CE1 first) and the
/// truth's (model flute order), over the best cyclic matching of the two labellings.
double worst_flute_peak_error(const std::vector<RevolutionRecord>& revolutions,
                              const std::vector<double>& truth) {
  const auto flutes = truth.size();
  std::vector<double> measured(flutes, 0.0);
  int n = 0;
  for (const auto& r : revolutions) {
    if (!r.measured.valid) {
      continue;
    }
    for (std::size_t j = 0; j < flutes; ++j) {
      measured[j] += r.measured.peak_resultant_N[j];
    }
    ++n;
  }
  double best = 1e9;
  for (std::size_t shift = 0; shift < flutes; ++shift) {
    double worst = 0.0;
    for (std::size_t j = 0; j < flutes; ++j) {
      const double m = measured[j] / n;
      const double t = truth[(j + shift) % flutes];
      worst = std::max(worst, std::fabs(m - t) / t);
    }
    best = std::min(best, worst);
  }
  return best;
}

struct Shape {
  const char* name;
  int flutes;
  double diameter_mm;
  model::Operation operation;
  double radial_depth_mm;
  double rpm;
  double sample_rate_hz;
  double runout_um;
};

sim::Scenario shape_scenario(const Shape& k) {
  sim::Scenario s;
  s.sample_rate_hz = k.sample_rate_hz;
  s.duration_s = 0.4;
  s.seed = 5;
  auto& m = s.model;
  m.tool.flutes = k.flutes;
  m.tool.diameter_mm = k.diameter_mm;
  m.process.operation = k.operation;
  m.process.radial_depth_mm = k.radial_depth_mm;
  m.process.spindle_rpm = k.rpm;
  m.process.feed_per_tooth_um = 3.0;
  m.process.axial_depth_mm = 0.05;
  m.effects.runout.offset_um = k.runout_um;
  m.effects.helix_lag.discs = 5;
  s.noise.enabled = true;
  s.noise.sigma_N = {0.015, 0.015, 0.015};
  s.quantisation.enabled = true;
  s.quantisation.range_N = {10.0, 10.0, 10.0};
  return s;
}

// Issue 6 §8: 1 to 8 flutes, slot, up- and down-milling down to 10 % radial immersion, 20 to
// 333.3 kHz: every revolution is measured, tooth periods add up to the revolution, and the
// tooth event suits the cut (valleys where the force is continuous, pulse centroids where it
// returns to zero between teeth).
TEST(EveryRevolution, EveryCutShapeIsMeasured) {
  using model::Operation;
  const Shape shapes[] = {
      {"1-flute slot", 1, 0.5, Operation::kSlot, 0.5, 20000.0, 50000.0, 0.0},
      {"2-flute slot", 2, 0.4, Operation::kSlot, 0.4, 25000.0, 50000.0, 1.82},
      {"2-flute down 10 %", 2, 0.4, Operation::kDownMilling, 0.04, 25000.0, 333300.0, 0.5},
      {"2-flute up 50 %", 2, 0.4, Operation::kUpMilling, 0.2, 25000.0, 20000.0, 1.0},
      {"3-flute slot", 3, 0.6, Operation::kSlot, 0.6, 20000.0, 50000.0, 0.5},
      {"3-flute down 30 %", 3, 0.5, Operation::kDownMilling, 0.15, 30000.0, 50000.0, 0.3},
      {"3-flute up 60 %", 3, 1.0, Operation::kUpMilling, 0.6, 15000.0, 20000.0, 0.5},
      {"4-flute slot at 20 kHz", 4, 1.0, Operation::kSlot, 1.0, 15000.0, 20000.0, 0.5},
      {"4-flute up 10 %", 4, 1.0, Operation::kUpMilling, 0.1, 15000.0, 20000.0, 0.3},
      {"6-flute slot", 6, 1.0, Operation::kSlot, 1.0, 12000.0, 50000.0, 0.3},
      {"8-flute slot", 8, 2.0, Operation::kSlot, 2.0, 10000.0, 50000.0, 0.3},
  };
  for (const Shape& k : shapes) {
    const sim::Scenario s = shape_scenario(k);
    const Recording r = test::record(s);
    Collector out;
    Pipeline p(test::monitor_for(s), out);
    test::replay(p, r, 1000);
    const int present = test::complete_cutting_revolutions(r);
    const auto measured = static_cast<int>(out.revolutions.size());
    int valid = 0;
    for (const auto& rev : out.revolutions) {
      valid += rev.measured.valid ? 1 : 0;
      double sum = 0.0;
      for (int j = 0; j < k.flutes; ++j) {
        sum += rev.measured.flute_period_s[static_cast<std::size_t>(j)];
      }
      EXPECT_NEAR(sum, rev.measured.period_s, 1e-12) << k.name;
      EXPECT_NEAR(rev.spindle_rpm, k.rpm, 0.003 * k.rpm) << k.name;
    }
    std::printf("%-24s %s: %d of %d revolutions, %d valid\n", k.name,
                to_string(p.event_template().kind), measured, present, valid);
    EXPECT_GE(measured, static_cast<int>(std::ceil(0.9 * present))) << k.name;
    EXPECT_GE(valid, static_cast<int>(std::ceil(0.9 * present))) << k.name;
    const bool interrupted =
        k.operation != Operation::kSlot && k.radial_depth_mm < 0.31 * k.diameter_mm;
    if (interrupted || k.flutes == 1) {
      EXPECT_EQ(p.event_template().kind, ToothEventKind::kCentroid) << k.name;
    }
    if (k.operation == Operation::kSlot && k.flutes >= 2) {
      EXPECT_EQ(p.event_template().kind, ToothEventKind::kValley) << k.name;
    }
  }
}

// A 3-flute down-milling cut at a third of the diameter pauses 41 % of each pitch, but through a
// dynamometer ringing at 4.5–6 kHz the in-plane force between two pulses is a W: it swings
// through zero twice, 26° apart, rebounding to 15 % of the pulses' height between. The two
// minima's depths trade places from flute to flute and from revolution to revolution, so valley
// events jumped between them (without runout 15 of 599 revolutions kept every event; with it α
// scattered by 9.4°). The commanded geometry says the flutes pause, so the template takes the
// pause under ringing for a pause and measures pulse centroids: every revolution, and α at the
// symmetric tool's 120° (the truth by symmetry) with the runout's change from it small and steady.
TEST(EveryRevolution, RingingBetweenPulsesDoesNotHideThePause) {
  for (const double runout_um : {0.0, 1.2}) {
    Shape k{"3-flute down 33 %",
            3,
            0.6,
            model::Operation::kDownMilling,
            0.2,
            36000.0,
            50000.0,
            runout_um};
    sim::Scenario s = shape_scenario(k);
    s.duration_s = 0.5;
    s.model.effects.runout.enabled = runout_um > 0.0;
    s.model.effects.runout.angle_rad = 1.9;
    s.model.effects.dynamometer.enabled = true;
    s.model.effects.dynamometer.natural_hz = {4500.0, 4600.0, 6000.0};
    s.model.effects.dynamometer.damping_ratio = {0.06, 0.06, 0.06};
    ASSERT_TRUE(pauses_between_flutes(s.model));
    const Recording r = test::record(s);
    Collector out;
    Pipeline p(test::monitor_for(s), out);
    test::replay(p, r, 1000);
    const int present = test::complete_cutting_revolutions(r);
    int valid = 0;
    double sum = 0.0, sum_sq = 0.0;
    for (const auto& rev : out.revolutions) {
      if (rev.measured.valid) {
        ++valid;
        sum += rev.measured.alpha_deg;
        sum_sq += rev.measured.alpha_deg * rev.measured.alpha_deg;
      }
    }
    ASSERT_GT(valid, 1);
    const double mean = sum / valid;
    const double sd = std::sqrt(std::max(0.0, sum_sq / valid - mean * mean));
    std::printf("runout %.1f µm, %s events: %d of %d revolutions valid, α %.2f ± %.2f°\n",
                runout_um, to_string(p.event_template().kind), valid, present, mean, sd);
    EXPECT_EQ(p.event_template().kind, ToothEventKind::kCentroid) << runout_um;
    EXPECT_GE(valid, static_cast<int>(std::ceil(0.95 * present))) << runout_um;
    EXPECT_LT(sd, 0.5) << runout_um;
    if (runout_um == 0.0) {
      EXPECT_NEAR(mean, 120.0, 0.3);
    } else {
      EXPECT_GT(std::fabs(mean - 120.0), 0.5);  // the runout's mark on α, seen
      EXPECT_LT(std::fabs(mean - 120.0), 5.0);
    }
  }
}

/// A 6-flute D 2 mm end mill down-milling at half its diameter (12,000 rpm commanded, runout
/// 1.5 µm) through a dynamometer ringing at 4.5–6 kHz: between the pulses of 1.1–1.3 kHz the
/// ringing leaves W-shaped valleys.
sim::Scenario six_flutes_through_a_ringing_dynamometer(double sample_rate_hz, double duration_s) {
  Shape k{"6-flute down 50 %", 6, 2.0, model::Operation::kDownMilling, 1.0, 12000.0, 0.0, 1.5};
  k.sample_rate_hz = sample_rate_hz;
  sim::Scenario s = shape_scenario(k);
  s.duration_s = duration_s;
  s.model.tool.helix_deg = 40.0;
  s.model.process.feed_per_tooth_um = 4.0;
  s.model.process.axial_depth_mm = 0.2;
  s.model.effects.runout.angle_rad = 4.0;
  s.model.effects.dynamometer.enabled = true;
  s.model.effects.dynamometer.natural_hz = {4500.0, 4600.0, 6000.0};
  s.model.effects.dynamometer.damping_ratio = {0.06, 0.06, 0.06};
  return s;
}

// Tooth events that stop on their own say so: the slot above, its force held at a steady
// 1.4 N (a stuck amplifier: as strong as the cut, but no valleys) from 0.5 s. The events find
// no valley for lost_after revolutions and stop; the pipeline's state falls back to tracking.
// That used to pass without an event: the user saw the revolutions end and, had the cut come
// back, a second "spindle locked" with no "lost" between them.
TEST(EveryRevolution, ToothEventsLostOnTheirOwnAreSaid) {
  const sim::Scenario s = slot(50000.0, 1.0);
  Recording r = test::record(s);
  for (std::size_t i = 0; i < r.t.size(); ++i) {
    if (r.t[i] >= 0.5) {
      r.fx[i] = -1.0;
      r.fy[i] = 1.0;
      r.fz[i] = 0.0;
    }
  }
  Collector out;
  Pipeline p(test::monitor_for(s), out);
  test::replay(p, r, 1000);
  const PipelineEvent* lost = out.first(PipelineEventKind::kLockLost);
  ASSERT_NE(lost, nullptr);
  std::printf("lost at %.3f s: %s\n", static_cast<double>(lost->sample) / s.sample_rate_hz,
              std::string(lost->detail).c_str());
  EXPECT_EQ(out.count(PipelineEventKind::kLockLost), 1);
  EXPECT_EQ(lost->detail, to_string(ToothEventLoss::kBarren));
  EXPECT_NEAR(static_cast<double>(lost->sample) / s.sample_rate_hz, 0.5, 0.02);
  // The events' last stated speed: the step in the force bends the last valleys before it.
  EXPECT_NEAR(lost->value, 25252.0, 0.02 * 25252.0);
  int after = 0;
  for (const auto& rev : out.revolutions) {
    if (static_cast<double>(rev.utime_us) * 1e-6 > 0.5 + 60.0 / 25252.0) {
      ++after;
      // The revolutions it took to give up: no valley, and no speed (the events' filter only
      // predicted one; it had stated 25,532 rpm there).
      EXPECT_FALSE(rev.measured.valid);
      EXPECT_EQ(rev.spindle_rpm, 0.0);
    }
  }
  EXPECT_LE(after, 5);
  EXPECT_NE(p.status().state, "measuring");
}

// A dead in-plane channel (an amplifier off, a cable out: Fy exactly 0, or its amplifier's noise
// alone). The tracker still hears the cut on Fx and locks, but the tooth events are the in-plane
// resultant's valleys: on Fx² alone they are Fx's zero crossings, and a real cut (PHM 2010 cut
// 315 with Fy zeroed) stated 20 revolutions of ~17 turned, at 12,400-17,800 rpm for 10,422. The
// lock's synchronous average shows the channel carries no cutting force: no events, said why.
TEST(EveryRevolution, AnInPlaneChannelWithoutCuttingForceIsSaidAndNothingMeasuredOnIt) {
  const sim::Scenario s = slot(50000.0, 0.5);
  for (const bool noisy : {false, true}) {
    Recording r = test::record(s);
    std::mt19937_64 rng(5);
    std::normal_distribution<double> amplifier_noise(0.0, 0.015);
    for (double& fy : r.fy) {
      fy = noisy ? amplifier_noise(rng) : 0.0;
    }
    Collector out;
    Pipeline p(test::monitor_for(s), out);
    test::replay(p, r, 1000);
    const PipelineEvent* refused = out.first(PipelineEventKind::kNoTemplate);
    ASSERT_NE(refused, nullptr) << noisy;
    EXPECT_EQ(std::string(refused->detail).rfind("fy carries no cutting force", 0), 0u)
        << refused->detail;
    EXPECT_TRUE(out.revolutions.empty()) << noisy;
    EXPECT_EQ(out.count(PipelineEventKind::kNoSteadySignal), 0) << noisy;
    EXPECT_NEAR(refused->value, 25252.0, 0.002 * 25252.0);  // the tracker's lock on Fx
    // Live, the operator hears it as sensor trouble, naming the channel.
    bool alerted = false;
    for (const Alert& a : out.alerts) {
      if (a.kind == AlertKind::kSensor && a.active &&
          std::string(a.message.data()).find("fy carries no cutting force while fx does") !=
              std::string::npos) {
        alerted = true;
        // Its value is what raised it: fy's synchronous range against fx's, under 2 %.
        EXPECT_EQ(a.quantity, "sync_range_ratio");
        EXPECT_GE(a.value, 0.0);
        EXPECT_LT(a.value, a.threshold);
        EXPECT_EQ(a.threshold, 0.02);
      }
    }
    EXPECT_TRUE(alerted) << noisy;
  }
}

// A spindle run off its commanded speed beyond the tracker's search (± 15 %: an override of
// 70 % or 160 %, a wrong speed in the sidecar): no speed is stated and no revolution measured —
// before, the 40,000 rpm cut was measured at 26,665 rpm ("± 110 rev to rev"), an alias whose
// harmonics fell on the tooth-passing lines, and the 17,500 rpm one at 25,752 rpm — and the
// monitor says where the cut's strongest line is and what speeds it means, the truth's among
// them. Told the truth's speed, it measures the cut.
TEST(EveryRevolution, ASpindleOffItsCommandedSpeedIsSaidAndNoSpeedStated) {
  for (const double true_rpm : {17500.0, 33000.0, 40000.0}) {
    sim::Scenario s = slot(50000.0, 0.4);
    s.spindle.actual_rpm = true_rpm;
    const Recording r = test::record(s);
    Collector out;
    Pipeline p(test::monitor_for(s), out);  // commanded 25,000 rpm
    test::replay(p, r, 1000);
    EXPECT_TRUE(out.revolutions.empty()) << true_rpm;
    EXPECT_EQ(out.count(PipelineEventKind::kLockAcquired), 0) << true_rpm;
    EXPECT_EQ(out.count(PipelineEventKind::kNoSteadySignal), 0) << true_rpm;  // not "irregular"
    const PipelineEvent* e = out.first(PipelineEventKind::kSpeedOutOfRange);
    ASSERT_NE(e, nullptr) << true_rpm;
    EXPECT_EQ(out.count(PipelineEventKind::kSpeedOutOfRange), 1) << true_rpm;  // once
    EXPECT_LT(e->utime_us, 100000) << true_rpm;  // within 0.1 s of the cut's start
    // The line is the spindle's or the tooth-passing one; the words name both readings.
    const double as_spindle = 60.0 * e->value, as_tooth = 30.0 * e->value;
    EXPECT_TRUE(std::fabs(as_spindle / true_rpm - 1.0) < 0.005 ||
                std::fabs(as_tooth / true_rpm - 1.0) < 0.005)
        << true_rpm << " rpm: line at " << e->value << " Hz";
    const std::string words = describe_line_outside_search(*e, test::monitor_for(s));
    char reading[32];
    std::snprintf(reading, sizeof reading, "%.0f rpm",
                  std::fabs(as_spindle / true_rpm - 1.0) < 0.005 ? as_spindle : as_tooth);
    EXPECT_NE(words.find(reading), std::string::npos) << words;
    EXPECT_NE(words.find("25000 rpm commanded"), std::string::npos) << words;

    s.model.process.spindle_rpm = true_rpm;  // the user sets the speed the spindle ran at
    Collector told;
    Pipeline q(test::monitor_for(s), told);
    test::replay(q, r, 1000);
    EXPECT_GT(told.revolutions.size(), 0.85 * 0.4 * true_rpm / 60.0) << true_rpm;
    std::vector<double> rpm;
    for (const RevolutionRecord& rev : told.revolutions) {
      rpm.push_back(60.0 / rev.measured.period_s);
      EXPECT_NEAR(rpm.back(), true_rpm, 0.02 * true_rpm);  // 75 samples a turn at 40,000 rpm
    }
    std::nth_element(rpm.begin(), rpm.begin() + static_cast<std::ptrdiff_t>(rpm.size() / 2),
                     rpm.end());
    EXPECT_NEAR(rpm[rpm.size() / 2], true_rpm, 0.001 * true_rpm);
    EXPECT_EQ(told.count(PipelineEventKind::kSpeedOutOfRange), 0) << true_rpm;
  }
}

/// The 6-flute cut above at 333.3 kHz with a narrow valley search (0.2 pitch), the spindle
/// jumping 11,000 → 13,000 rpm in `jump_s` from 0.3 s.
sim::Scenario six_flutes_jumping(double jump_s) {
  sim::Scenario s = six_flutes_through_a_ringing_dynamometer(333300.0, 1.0);
  s.spindle.profile = sim::SpindleProfileKind::kRamp;
  s.spindle.actual_rpm = 11000.0;
  s.spindle.ramp_end_rpm = 13000.0;
  s.spindle.ramp_start_s = 0.3;
  s.spindle.ramp_end_s = 0.3 + jump_s;
  return s;
}

/// The monitor on a recording of six_flutes_jumping(): the narrow valley search.
void replay_narrow(const sim::Scenario& s, const Recording& r, Collector& out) {
  MonitorConfig c = test::monitor_for(s);
  c.search_fraction_of_pitch = 0.2;
  Pipeline p(c, out);
  test::replay(p, r, 4096);
}

// A jump of 2,000 rpm in 50 ms (40,000 rpm/s): the tooth events follow it. Their filter
// shortens its memory when the CE1 events leave their predictions twice in a row to the same
// side, and a revolution whose closing CE1 is missed no longer carries the period's change on
// (it ran the events off to 17,700 rpm once the jump had ended). Every revolution that states
// a speed (all but those whose closing CE1 was missed) states it within 2 % of the spindle's
// over it (1.35 %; 2.4 % while coasting revolutions stated the filter's prediction), those measured
// through the jump within 1.5 % (1.0 %), and the tracker's check compares its window with the
// revolution at the window's centre (with the newest one it lost the events at 11,064 rpm against
// 11,743 rpm stated, both right).
TEST(EveryRevolution, ToothEventsFollowASpeedJumpOf40000RpmPerSecond) {
  const sim::Scenario s = six_flutes_jumping(0.05);
  const Recording r = test::record(s);
  Collector out;
  replay_narrow(s, r, out);
  double worst = 0.0, worst_in_jump = 0.0;
  int in_jump = 0, unstated = 0;
  for (const auto& rev : out.revolutions) {
    if (rev.spindle_rpm == 0.0) {  // coasted (its closing CE1 missed): no speed stated
      EXPECT_FALSE(rev.measured.bounded);
      ++unstated;
      continue;
    }
    const double t0 = static_cast<double>(rev.utime_us) * 1e-6;
    const double error = std::fabs(rev.spindle_rpm / true_rpm_at(r, middle_s(rev)) - 1.0);
    worst = std::max(worst, error);
    if (t0 > 0.3 && t0 < 0.345 && rev.measured.valid) {
      ++in_jump;
      worst_in_jump = std::max(worst_in_jump, error);
    }
  }
  std::printf(
      "%zu revolutions stated (%d without a speed), worst %.2f %% off the spindle's speed; "
      "through the jump %d measured, worst %.2f %%; %d locks lost\n",
      out.revolutions.size(), unstated, 100.0 * worst, in_jump, 100.0 * worst_in_jump,
      out.count(PipelineEventKind::kLockLost));
  EXPECT_LT(worst, 0.02);
  // The coast-out after the jump (kCoastRevolutions, below) and a CE1 missed here and there: 8.
  EXPECT_LE(unstated, kCoastRevolutions + 4);
  EXPECT_GE(in_jump, 8);  // of the ~9 turns the jump takes
  EXPECT_LT(worst_in_jump, 0.015);
  // Not lost on the speed check. After the jump the 11,000 rpm template's CE1 valley (an arm of
  // a W at 13,000 rpm) is missed for kCoastRevolutions and the events stop on their own, said
  // as such; the next lock takes a template at the new speed.
  for (const PipelineEvent& e : out.events) {
    if (e.kind == PipelineEventKind::kLockLost) {
      EXPECT_EQ(e.detail, to_string(ToothEventLoss::kCoasted)) << e.value;
    }
  }
}

// Tooth events that run off: the same jump in 20 ms (100,000 rpm/s). The events' filter
// cannot follow: they lose the valleys and coast on at ~11,150 rpm. (On a 0.3 s ramp, before
// the W's arms were kept and the filter's memory shortened, its closing CE1 events went missing
// or fell on the ringing's other minima and it ran on the ramp's rate to 16,500 rpm, stating 210
// revolutions where the spindle turned 202.) A consistent tracker window that disagrees with the
// events' speed at its centre by more than 3 % loses them, and the next lock finds them afresh.
TEST(EveryRevolution, ToothEventsThatLeaveTheSpindleSpeedAreLost) {
  const sim::Scenario s = six_flutes_jumping(0.02);
  const Recording r = test::record(s);
  Collector out;
  replay_narrow(s, r, out);
  double fastest_rpm = 0.0;
  for (const auto& rev : out.revolutions) {
    fastest_rpm = std::max(fastest_rpm, rev.spindle_rpm);
  }
  const int turned = static_cast<int>(r.truth.size());
  std::printf("%zu revolutions stated of %d turned, the fastest at %.0f rpm; %d locks lost\n",
              out.revolutions.size(), turned, fastest_rpm, out.count(PipelineEventKind::kLockLost));
  EXPECT_LE(static_cast<int>(out.revolutions.size()), turned);
  EXPECT_LT(fastest_rpm, 13000.0 * 1.06);  // caught within a tracker hop of its drift
  const PipelineEvent* lost = out.first(PipelineEventKind::kLockLost);
  ASSERT_NE(lost, nullptr);
  EXPECT_EQ(lost->count, 13000);  // the tracker's speed, the events' beyond 3 % of it
  EXPECT_GT(std::fabs(lost->value - 13000.0), 0.03 * 13000.0);
}

// W-shaped valleys: at 13,000 rpm the ringing leaves two minima ~15° apart in some of the
// cut above's tooth periods, about as deep. The lowest sample flipped between them with the
// noise (a flute's period 45° or 75° where all are ~60°: α bimodal through a ramp, 53 ± 8°),
// and a template found at 13,000 rpm put the model's events on the early arm (its α 45.8°).
// The valley the prediction lies in is kept where the two are about as deep (nearest_basin()),
// in the template as in the tracker: every flute's period stays near a sixth of the
// revolution, α near 60° for the measurement and the model alike.
TEST(EveryRevolution, WShapedValleysKeepTheArmTheirFlutesAreOn) {
  for (const bool ramp : {false, true}) {
    sim::Scenario s = six_flutes_through_a_ringing_dynamometer(50000.0, ramp ? 0.8 : 0.4);
    s.spindle.actual_rpm = 13000.0;
    if (ramp) {
      s.spindle.profile = sim::SpindleProfileKind::kRamp;
      s.spindle.actual_rpm = 11000.0;
      s.spindle.ramp_end_rpm = 13000.0;
      s.spindle.ramp_start_s = 0.15;
      s.spindle.ramp_end_s = 0.45;
    }
    const Recording r = test::record(s);
    Collector out;
    Pipeline p(test::monitor_for(s), out);
    test::replay(p, r, 1000);
    int valid = 0, model_valid = 0, off_pitch = 0;
    double sum = 0.0, sum_sq = 0.0, model_sum = 0.0;
    for (const auto& rev : out.revolutions) {
      if (!rev.measured.valid) {
        continue;
      }
      ++valid;
      sum += rev.measured.alpha_deg;
      sum_sq += rev.measured.alpha_deg * rev.measured.alpha_deg;
      for (int j = 0; j < 6; ++j) {
        const double share = rev.measured.flute_period_s[static_cast<std::size_t>(j)] /
                             (rev.measured.period_s / 6.0);
        off_pitch += std::fabs(share - 1.0) > 0.1 ? 1 : 0;  // a 15° slip is 25 %
      }
      if (rev.model_valid && rev.model.valid) {
        ++model_valid;
        model_sum += rev.model.alpha_deg;
      }
    }
    const int measured = static_cast<int>(out.revolutions.size());
    const int present = test::complete_cutting_revolutions(r);
    ASSERT_GT(valid, 10);
    ASSERT_GT(model_valid, 10);
    const double mean = sum / valid;
    const double sd = std::sqrt(std::max(0.0, sum_sq / valid - mean * mean));
    const double model_mean = model_sum / model_valid;
    std::printf(
        "%s: %d of %d revolutions with every event (%d stated), %d flute periods off their "
        "pitch; "
        "α %.2f ± %.2f° (model %.2f°)\n",
        ramp ? "ramp 11,000 → 13,000 rpm" : "13,000 rpm", valid, present, measured, off_pitch, mean,
        sd, model_mean);
    EXPECT_GE(valid, static_cast<int>(std::ceil(0.97 * present))) << ramp;
    EXPECT_EQ(off_pitch, 0) << ramp;
    EXPECT_NEAR(mean, 60.0, 1.5) << ramp;
    EXPECT_LT(sd, 1.0) << ramp;
    EXPECT_NEAR(model_mean, 60.0, 1.5) << ramp;
  }
}

// Issue 6 §8: per-flute peaks against the simulated truth, 3 and 4 flutes in side milling at
// 20 and 50 kHz (the force returns to zero between teeth in the first two).
TEST(EveryRevolution, PerFlutePeaksMatchTheTruthInSideMilling) {
  using model::Operation;
  const Shape shapes[] = {
      {"3-flute down 30 % at 50 kHz", 3, 0.5, Operation::kDownMilling, 0.15, 30000.0, 50000.0, 0.3},
      {"4-flute up 10 % at 20 kHz", 4, 1.0, Operation::kUpMilling, 0.1, 15000.0, 20000.0, 0.3},
      {"3-flute up 60 % at 20 kHz", 3, 1.0, Operation::kUpMilling, 0.6, 15000.0, 20000.0, 0.5},
      {"4-flute down 50 % at 50 kHz", 4, 1.0, Operation::kDownMilling, 0.5, 15000.0, 50000.0, 0.5},
  };
  for (const Shape& k : shapes) {
    const sim::Scenario s = shape_scenario(k);
    const Recording r = test::record(s);
    Collector out;
    Pipeline p(test::monitor_for(s), out);
    test::replay(p, r, 1000);
    const std::vector<double> truth = true_flute_peaks(s);
    const double worst = worst_flute_peak_error(out.revolutions, truth);
    std::printf("%-28s per-flute peaks within %.1f %% of the truth\n", k.name, 100.0 * worst);
    EXPECT_LT(worst, 0.03) << k.name;
  }
}

// A short gap in the stream (a lost block, bridged: the lock holds) leaves the revolutions it
// cuts through without samples. A revolution is reported only when every sample of its flute
// windows came — none is measured on the gap's rows (the ring's rows from a lap before) — and the
// revolutions reported around the gap agree with the same cut without it. Gaps of 5 to 34 ms at
// several phases of the revolution.
TEST(EveryRevolution, NoRevolutionIsMeasuredOnSamplesAGapLost) {
  const sim::Scenario s = slot(50000.0, 0.8);
  const Recording r = test::record(s);
  Collector whole;
  Pipeline pw(test::monitor_for(s), whole);
  test::replay(pw, r, 250);
  int reported_near_gaps = 0;
  for (const std::int64_t block : {250, 330, 410, 560, 1700}) {
    for (const std::int64_t lost : {std::int64_t{14000} / block, std::int64_t{24000} / block}) {
      Collector out;
      Pipeline p(test::monitor_for(s), out);
      test::replay(p, r, static_cast<std::size_t>(block),
                   [lost](std::int64_t seq, SampleBlock&) { return seq != lost; });
      ASSERT_EQ(out.count(PipelineEventKind::kGap), 1) << block << " " << lost;
      ASSERT_EQ(out.count(PipelineEventKind::kLockLost), 0) << block << " " << lost;
      const std::int64_t gap_first = lost * block;  // input = measuring samples at 50 kHz
      const std::int64_t gap_last = gap_first + block - 1;
      for (const auto& rev : out.revolutions) {
        const auto& m = rev.measured;
        const auto from = static_cast<std::int64_t>(std::ceil(m.boundary_sample[0]));
        const auto to = static_cast<std::int64_t>(
            std::floor(m.boundary_sample[static_cast<std::size_t>(m.flutes)]));
        EXPECT_TRUE(to < gap_first || from > gap_last)
            << "blocks of " << block << ", block " << lost << " lost (samples " << gap_first << "–"
            << gap_last << "): a revolution measured on samples " << from << "–" << to;
        if (to < gap_first - 2000 || from > gap_last + 2000) {
          continue;
        }
        ++reported_near_gaps;
        const RevolutionRecord* w = nullptr;
        for (const auto& x : whole.revolutions) {
          if (std::llabs(x.utime_us - rev.utime_us) <= 40) {
            w = &x;
          }
        }
        ASSERT_NE(w, nullptr) << block << " " << lost << " " << rev.utime_us;
        for (int j = 0; j < m.flutes; ++j) {
          const auto uj = static_cast<std::size_t>(j);
          EXPECT_NEAR(m.peak_resultant_N[uj], w->measured.peak_resultant_N[uj],
                      0.03 * w->measured.peak_resultant_N[uj])
              << block << " " << lost << " " << rev.utime_us << " flute " << j;
        }
      }
    }
  }
  EXPECT_GT(reported_near_gaps, 100);
}

}  // namespace
}  // namespace millwatch::monitor
