#include "core/monitor/revolution_meter.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "core/monitor/sync_average.hpp"
#include "core/monitor/valley_template.hpp"
#include "tests/support/allocation_counter.hpp"

namespace millwatch::monitor {
namespace {

constexpr double kPi = std::numbers::pi;

/// A two-flute force over one revolution of spindle angle θ: flute 0 cuts [0, θ0), flute 1
/// [θ0, 2π), each a smooth pulse (1 − cos)/2 of its own amplitude; Fx and Fy follow the pulse.
/// With a1/a0 = ((2π − θ0)/θ0)² both sides of each valley have the same curvature, so the
/// valleys are locally symmetric; otherwise the curvature jumps at the valley.
struct TwoFluteSignal {
  double theta0 = 0.98 * kPi;  // flute 0's share of the revolution: α = 2π − θ0 for flute 1
  double a0 = 1.2;
  double a1 = 1.2 * (2 * kPi - 0.98 * kPi) * (2 * kPi - 0.98 * kPi) / (0.98 * kPi * 0.98 * kPi);
  double resultant(double theta) const {
    theta = std::fmod(theta, 2 * kPi);
    if (theta < 0) {
      theta += 2 * kPi;
    }
    if (theta < theta0) {
      return a0 * 0.5 * (1 - std::cos(2 * kPi * theta / theta0));
    }
    return a1 * 0.5 * (1 - std::cos(2 * kPi * (theta - theta0) / (2 * kPi - theta0)));
  }
};

struct Feed {
  SampleRing ring{4, 1 << 14};
  std::int64_t next = 0;
  void push(double fx, double fy, double fz) {
    const double v[4] = {fx, fy, fz, std::hypot(fx, fy)};
    ring.push(next++, v);
  }
};

// These synthetic pulses are unfiltered, so their valleys are sharper than a low-pass-filtered
// force's: the tests fix the fit's half-width at 3 samples instead of the automatic pitch/7.

TEST(RevolutionMeter, MeasuresPeriodsAlphaAndPeaksOfAKnownSignal) {
  const double fs = 50000.0;
  const double f_spindle = 25252.0 / 60.0;
  const double phase0 = 0.7;  // tracker angle zero is arbitrary
  const TwoFluteSignal sig;
  PhaseModel phase{0.0, phase0, f_spindle, fs, true};

  // Template from the synchronous average of the first revolutions.
  SyncAverage avg(360, 20);
  Feed feed;
  for (int n = 0; n < 20000; ++n) {
    const double theta = phase.angle_at(n) - phase0;  // the signal's own angle
    const double r = sig.resultant(theta);
    const double fx = -0.6 * r;
    const double fy = 0.8 * r;
    feed.push(fx, fy, 0.1 * r);
    const double tracker_angle = std::fmod(phase.angle_at(n), 2 * kPi);
    avg.add(tracker_angle, {fx, fy, 0.1 * r, r});
    if (n > 0 &&
        std::floor(phase.angle_at(n) / (2 * kPi)) > std::floor(phase.angle_at(n - 1) / (2 * kPi))) {
      avg.end_revolution();
    }
  }
  std::vector<double> resultant;
  avg.average(3, resultant);
  const ValleyTemplate t = find_valley_template(resultant, 2);
  ASSERT_TRUE(t.valid);
  // CE1 is the flute with the larger pulse (the signal's flute 1, from θ0), then flute 0.
  EXPECT_NEAR(std::remainder(t.angle_rad[0] - phase0 - sig.theta0, 2 * kPi), 0.0, 0.01);
  EXPECT_NEAR(std::remainder(t.angle_rad[1] - phase0, 2 * kPi), 0.0, 0.01);

  RevolutionMeter meter({2, fs, 0.3, 3, 0.05}, 0);
  meter.set_template(t);
  int count = 0;
  double alpha_sum = 0.0;
  meter.advance(feed.ring, phase, [&](const RevolutionMeasurement& m) {
    ++count;
    EXPECT_TRUE(m.valid);
    // 3 % of a sample is 0.6 µs at 50 kHz
    EXPECT_NEAR(m.period_s, 1.0 / f_spindle, 0.03 / fs);
    EXPECT_NEAR(m.flute_period_s[0], (2 * kPi - sig.theta0) / (2 * kPi * f_spindle), 0.03 / fs);
    alpha_sum += m.alpha_deg;
    EXPECT_NEAR(m.peak_resultant_N[0], sig.a1, 2e-3 * sig.a1);
    EXPECT_NEAR(m.peak_resultant_N[1], sig.a0, 2e-3 * sig.a0);
    EXPECT_NEAR(m.peak_N[0][0], -0.6 * sig.a1, 2e-3);
    EXPECT_NEAR(m.peak_N[1][1], 0.8 * sig.a0, 2e-3);
    EXPECT_NEAR(m.delta_fy_N, 0.8 * (sig.a1 - sig.a0), 3e-3);
  });
  EXPECT_GE(count, 15);
  EXPECT_NEAR(alpha_sum / count, sig.theta0 * 180.0 / kPi, 0.005);

  // Steady state allocates nothing.
  for (int n = 0; n < 2000; ++n) {
    const double r = sig.resultant(phase.angle_at(feed.next) - phase0);
    feed.push(-0.6 * r, 0.8 * r, 0.1 * r);
  }
  test::AllocationCounter counter;
  meter.advance(feed.ring, phase, [](const RevolutionMeasurement&) {});
  EXPECT_EQ(counter.allocations(), 0);
}

// A valley between pulses of different curvature (a kink in the second derivative, sharper
// than any low-pass-filtered force) is located with a bias of a fraction of a sample by the
// local cubic fit over a tenth of a pitch; the bias is the same on a clean and a noisy signal.
TEST(RevolutionMeter, KinkedValleysAreLocatedWithinAFractionOfASample) {
  const double fs = 50000.0;
  const double f = 420.0;
  TwoFluteSignal sig;
  sig.a1 = 0.7;  // curvature jumps by 1.8× at the valleys
  Feed feed;
  for (int n = 0; n < 20000; ++n) {
    const double r = sig.resultant(2 * kPi * f * n / fs);
    feed.push(0.5 * r, 0.5 * r, 0.0);
  }
  PhaseModel phase{0.0, 0.0, f, fs, true};
  ValleyTemplate t;
  t.flutes = 2;
  t.angle_rad = {0.0, sig.theta0};
  t.valid = true;
  RevolutionMeter meter({2, fs, 0.3, 3, 0.05}, 0);
  meter.set_template(t);
  int count = 0;
  meter.advance(feed.ring, phase, [&](const RevolutionMeasurement& m) {
    ++count;
    EXPECT_NEAR(m.flute_period_s[0], sig.theta0 / (2 * kPi * f), 0.75 / fs);
    EXPECT_NEAR(m.period_s, 1.0 / f, 0.03 / fs);
  });
  EXPECT_GT(count, 100);
}

// The valley search follows the signal when the tracker's phase drifts slowly against it.
TEST(RevolutionMeter, FollowsSlowPhaseDriftOfTheTracker) {
  const double fs = 50000.0;
  const double f_true = 420.0;
  const TwoFluteSignal sig;
  // The tracker believes 0.02 % more speed: 0.07° of drift per revolution, 36° over the record.
  PhaseModel phase{0.0, 0.0, f_true * 1.0002, fs, true};
  ValleyTemplate t;
  t.flutes = 2;
  t.angle_rad = {sig.theta0, 2 * kPi};
  t.valid = true;
  RevolutionMeter meter({2, fs, 0.3, 3, 0.2}, 0);
  meter.set_template(t);
  Feed feed;
  int count = 0, valid = 0;
  for (int n = 0; n < 60000; ++n) {
    const double r = sig.resultant(2 * kPi * f_true * n / fs);
    feed.push(0.5 * r, 0.5 * r, 0.0);
    if (n % 1000 == 999) {
      meter.advance(feed.ring, phase, [&](const RevolutionMeasurement& m) {
        ++count;
        valid += m.valid ? 1 : 0;
        if (m.valid) {
          EXPECT_NEAR(m.period_s, 1.0 / f_true, 0.05 / fs);
        }
      });
    }
  }
  EXPECT_GT(count, 495);
  EXPECT_EQ(valid, count);
}

}  // namespace
}  // namespace millwatch::monitor
