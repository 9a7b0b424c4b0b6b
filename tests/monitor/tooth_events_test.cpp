// find_valley, the search behind every tooth event (the measured ring's and the lockstep model's
// rows): it finds a clean valley anywhere in its window, and reads its signal only within the
// samples the caller has. find_quiet_middle, the model's event where its force pauses. The
// template's choice of event (valleys or pulse centroids) and the commanded geometry's pauses
// between flutes. The tracker gives up revolutions whose bounds it can only guess.

#include "core/monitor/tooth_events.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "core/monitor/sample_ring.hpp"

namespace millwatch::monitor {
namespace {

// An asymmetric valley, (u − v)²·(1 + (u − v)/400) around vertex v, given only the samples the
// search asks for (center ± (half + 3·fit)): found at its vertex wherever it sits in the window.
// first_minimum() finds the sample one scan with a strict `<` finds, on windows of 1 to 40
// samples drawn from few values (ties, ±0), with NaNs and infinities among them, at the start
// too.
TEST(FirstMinimum, IsTheSampleOneStrictScanFinds) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const std::array<double, 9> values = {3.0, 1.0, -2.0, 0.0, -0.0, nan, inf, -inf, 1.0};
  std::mt19937 rng(19);
  std::uniform_int_distribution<std::size_t> pick(0, values.size() - 1);
  std::uniform_int_distribution<int> kind(0, 2);
  int windows = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const int length = 1 + trial % 40;
    std::vector<double> x(static_cast<std::size_t>(length));
    for (double& v : x) {
      // Mostly finite values, so that the minimum moves along the window.
      v = kind(rng) == 0 ? values[pick(rng)] : std::uniform_real_distribution<double>(-5, 5)(rng);
    }
    const std::int64_t from = 100 + trial % 7;
    const auto detect = [&](std::int64_t n) { return x[static_cast<std::size_t>(n - from)]; };
    std::int64_t best = from;
    double lowest = detect(from);
    for (std::int64_t n = from + 1; n < from + length; ++n) {
      if (detect(n) < lowest) {
        lowest = detect(n);
        best = n;
      }
    }
    ASSERT_EQ(first_minimum(detect, from, from + length - 1), best) << trial;
    ++windows;
  }
  EXPECT_EQ(windows, 20000);
}

TEST(FindValley, FindsACleanValleyAnywhereInItsWindow) {
  const std::int64_t center = 5000;
  for (const int fit : {2, 5, 9, 17}) {
    for (const std::int64_t half : {3, 12, 30}) {
      const std::int64_t oldest = center - half - 3 * fit;
      const std::int64_t newest = center + half + 3 * fit;
      for (double offset = -static_cast<double>(half) + 1.0;
           offset <= static_cast<double>(half) - 1.0; offset += 0.37) {
        const double vertex = static_cast<double>(center) + offset;
        const auto valley = [&](std::int64_t n) {
          const double u = static_cast<double>(n) - vertex;
          return 1.0 + u * u * (1.0 + u / 400.0);
        };
        const EventSearch e =
            find_valley(valley, oldest, newest, static_cast<double>(center), half, fit);
        ASSERT_EQ(e.status, EventSearch::Status::kFound) << fit << " " << half << " " << offset;
        EXPECT_NEAR(e.position, vertex, 1e-6) << fit << " " << half << " " << offset;
      }
    }
  }
}

// The same at the narrowest fits, with the valley anywhere, on the window's edges included: a
// fit of ± 0 samples too, whose search keeps a sample of room more than 3·0 for the fits a
// sample either side of the window.
TEST(FindValley, ReadsOnlyTheSamplesItIsGivenAtAnyFitWidth) {
  const std::int64_t center = 100;
  for (const int fit : {0, 1, 2, 5}) {
    for (const std::int64_t half : {1, 5, 12}) {
      for (std::int64_t bottom = center - half - 2; bottom <= center + half + 2; ++bottom) {
        // The tightest span the search takes without waiting or giving up, and 3·fit either
        // side (less, at a fit of 0: the search must wait).
        const std::int64_t room = std::max<std::int64_t>(3 * fit, fit + 1);
        for (const std::int64_t given : {room, std::int64_t{3} * fit}) {
          const std::int64_t oldest = center - half - given, newest = center + half + given;
          int outside = 0;
          const auto valley = [&](std::int64_t n) {
            outside += n < oldest || n > newest ? 1 : 0;
            const double u = static_cast<double>(n - bottom);
            return 1.0 + u * u;
          };
          const EventSearch e =
              find_valley(valley, oldest, newest, static_cast<double>(center), half, fit);
          EXPECT_EQ(outside, 0) << "fit " << fit << ", half " << half << ", bottom " << bottom
                                << ", " << given << " samples of room";
          if (given == room) {
            EXPECT_NE(e.status, EventSearch::Status::kWait);
            EXPECT_NE(e.status, EventSearch::Status::kGone);
          }
        }
      }
    }
  }
}

// A W: two parabolic arms 16 samples apart, parted by a ridge of 64 (about a sixth of the
// window's span). Where the arms are about as deep (the right one shallower by 0.04: the
// ringing of a dynamometer between pulses), the valley found is the arm the prediction lies in
// — the lowest sample would flip between them with the noise. An arm shallower by 150 (29 % of
// the span) is a shoulder: the lowest is taken. So is a one-sample dip on a steep flank (no
// valley a fit of ± 3 samples sees as one); and a window whose lowest sample is on its edge
// finds no valley, whatever arm lies nearer the prediction.
TEST(FindValley, KeepsTheArmOfAWItsPredictionLiesIn) {
  const std::int64_t center = 1000, half = 20;
  const int fit = 3;
  // Samples for a search around any prediction within ± 10 of the centre.
  const std::int64_t oldest = center - half - 3 * fit - 10, newest = center + half + 3 * fit + 10;
  const auto w = [&](double right_bottom) {
    return [=](std::int64_t n) {
      const double u = static_cast<double>(n - center);
      return std::min((u + 8.0) * (u + 8.0), (u - 8.0) * (u - 8.0) + right_bottom);
    };
  };
  for (const double side : {-1.0, 1.0}) {
    const double predicted = static_cast<double>(center) + side * 6.5;
    const EventSearch e = find_valley(w(0.04), oldest, newest, predicted, half, fit);
    ASSERT_EQ(e.status, EventSearch::Status::kFound) << side;
    EXPECT_NEAR(e.position, static_cast<double>(center) + side * 8.0, 1e-6) << side;
  }
  const EventSearch shoulder =
      find_valley(w(150.0), oldest, newest, static_cast<double>(center) + 6.5, half, fit);
  ASSERT_EQ(shoulder.status, EventSearch::Status::kFound);
  EXPECT_NEAR(shoulder.position, static_cast<double>(center) - 8.0, 1e-6);
  // A window from u = −5 to 17 around a prediction at u = 6: its lowest sample is on its left
  // edge (9, the deeper arm's flank; the valley lies beyond), the right arm inside is 12 deep.
  // The valley is not in this window: not found, as when the lowest sample alone decided.
  const EventSearch beyond =
      find_valley(w(12.0), oldest, newest, static_cast<double>(center) + 6.0, 11, fit);
  EXPECT_EQ(beyond.status, EventSearch::Status::kNotFound);
  // A flank with a dip of one sample (a ripple of sparse samples), the valley 6 samples before.
  const auto dip = [&](std::int64_t n) {
    const double u = static_cast<double>(n - center);
    return (u + 6.0) * (u + 6.0) - (n == center ? 20.0 : 0.0);
  };
  const EventSearch sparse =
      find_valley(dip, oldest, newest, static_cast<double>(center), half, fit);
  ASSERT_EQ(sparse.status, EventSearch::Status::kFound);
  EXPECT_NEAR(sparse.position, static_cast<double>(center) - 6.0, 1e-6);
}

// Signals with ripples, a slope, a slow wave and noise (a fixed seed): the fit re-centres on
// its vertex up to three times, a fit's width each, and a vertex that kept walking used to take
// the fit past the samples the search was given — up to a fit's width beyond them, on about one
// signal in 7,000 (the lockstep model's rows hold no more: a read before them was outside their
// buffer). Every read stays within [oldest, newest], and so does a valley found.
TEST(FindValley, ReadsOnlyTheSamplesItIsGiven) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const std::int64_t center = 1000;
  int outside = 0, found = 0;
  for (int trial = 0; trial < 100000; ++trial) {
    const int fit = 2 + static_cast<int>(rng() % 18);
    const auto half = static_cast<std::int64_t>(1 + rng() % 40);
    const std::int64_t oldest = center - half - 3 * fit;
    const std::int64_t newest = center + half + 3 * fit;
    const double ripple = 2.0 + uniform(rng) * 3.0 * fit;
    const double wave = 2.0 + uniform(rng) * 6.0 * fit;
    const double phase1 = uniform(rng) * 6.3, phase2 = uniform(rng) * 6.3;
    const double noise = uniform(rng) * 0.5, slope = (uniform(rng) - 0.5) * 0.2;
    const double wave_amplitude = uniform(rng);
    const double predicted = static_cast<double>(center) + uniform(rng) - 0.5;
    std::int64_t lo = center, hi = center;
    const auto signal = [&](std::int64_t n) {
      lo = std::min(lo, n);
      hi = std::max(hi, n);
      const double u = static_cast<double>(n - center);
      const auto hash = static_cast<std::uint64_t>(n) * 0x9E3779B97F4A7C15ULL;
      return 3.0 + std::cos(2.0 * std::numbers::pi * u / ripple + phase1) +
             wave_amplitude * std::cos(2.0 * std::numbers::pi * u / wave + phase2) + slope * u +
             noise * static_cast<double>(hash >> 40) / 16777216.0;
    };
    const EventSearch e = find_valley(signal, oldest, newest, predicted, half, fit);
    if (lo < oldest || hi > newest) {
      ++outside;
      ADD_FAILURE() << "trial " << trial << " (fit " << fit << ", half " << half << ") read [" << lo
                    << ", " << hi << "] of [" << oldest << ", " << newest << "]";
    }
    if (e.status == EventSearch::Status::kFound) {
      ++found;
      EXPECT_GE(e.position, static_cast<double>(oldest)) << "trial " << trial;
      EXPECT_LE(e.position, static_cast<double>(newest)) << "trial " << trial;
    }
    if (outside > 5) {
      break;
    }
  }
  EXPECT_EQ(outside, 0);
  EXPECT_GT(found, 10000);  // the sweep is not all noise: many of its valleys are found
}

// Three pulses a revolution, 43 % of each pitch between them a W (two minima at 2 % of the
// pulses' height, 26° apart, a rebound to 15 % between): the ringing of a dynamometer after
// an interrupted cut. Above the 10 % of an unknown cut it is no pause (valleys); where the
// commanded cut pauses, the 25 % it is allowed there makes it one (pulse centroids, each the
// middle of its symmetric pulse, between the pauses' middles). The W's two minima are equal: the
// first flute's window takes the earlier, before bin 0, so it sorts last among the flutes'
// valleys (its pause's middle was once put a quarter pitch off, and the centroids 12° late).
TEST(ToothEventTemplate, AWBetweenPulsesIsAPauseWhereTheCutPauses) {
  constexpr int kBins = 360;
  std::vector<double> avg(kBins);
  for (int k = 0; k < kBins; ++k) {
    const double within = std::fmod(k, 120.0);  // degrees into the pitch; pulse centred at 60
    const double pulse = std::max(0.0, std::cos((within - 60.0) * std::numbers::pi / 68.0));
    const double gap = within < 60.0 ? within : 120.0 - within;  // from the pause's middle
    // Minima of 2 % at ±13° from the pause's middle, the rebound of 15 % at its middle.
    const double w = 0.02 + 0.13 * std::pow(std::cos(gap * std::numbers::pi / 26.0), 2);
    avg[static_cast<std::size_t>(k)] = gap <= 26.0 ? std::max(pulse, w) : pulse;
  }
  const ToothEventTemplate strict = find_tooth_event_template(avg, 3);
  ASSERT_TRUE(strict.valid);
  EXPECT_EQ(strict.kind, ToothEventKind::kValley);
  const ToothEventTemplate paused = find_tooth_event_template(avg, 3, true);
  ASSERT_TRUE(paused.valid);
  EXPECT_EQ(paused.kind, ToothEventKind::kCentroid);
  for (int j = 0; j < 3; ++j) {
    const double deg = paused.event_rad[static_cast<std::size_t>(j)] * 180.0 / std::numbers::pi;
    EXPECT_NEAR(std::remainder(deg - 60.0, 120.0), 0.0, 1.0) << j;
  }
}

// The lockstep model's valley where its force pauses (find_quiet_middle): between two pulses
// of straight flanks, heights h1 and h2 and half-width w, the quiet stretch below q ends where
// each flank crosses q — w·(1 − q/h) from its pulse's centre — and its middle is found to
// rounding wherever the pulses sit between samples (the ends are interpolated, so that it moves
// with them), though a ripple below q rides on the stretch. A stretch shorter than asked, one
// that runs past the samples given, one whose middle lies beyond the search and one beside a
// NaN are no pause's middle.
TEST(FindQuietMiddle, IsThePausesMiddleToASampleFraction) {
  const double h1 = 10.0, h2 = 7.0, w = 20.0, q = 3.0, pitch = 96.0;
  for (int step = 0; step < 40; ++step) {
    const double c1 = 100.0 + step * 0.137;  // the first pulse's centre
    const double c2 = c1 + pitch;
    const auto detect = [&](std::int64_t n) {
      const auto u = static_cast<double>(n);
      const double pulses = std::max(0.0, h1 * (1.0 - std::fabs(u - c1) / w)) +
                            std::max(0.0, h2 * (1.0 - std::fabs(u - c2) / w));
      // A ripple well inside the pause, below q (a filter's ringing).
      const bool inside = u > c1 + w + 2.0 && u < c2 - w - 2.0;
      return pulses + (inside ? 0.4 * q * (1.0 + std::sin(0.9 * u)) : 0.0);
    };
    const double start = c1 + w * (1.0 - q / h1), end = c2 - w * (1.0 - q / h2);
    const double middle = 0.5 * (start + end);
    const double predicted = 0.5 * (c1 + c2) + 7.0;  // off the middle, within the search
    const EventSearch e = find_quiet_middle(detect, 0, 400, predicted, 29, q, 0.2 * pitch);
    ASSERT_EQ(e.status, EventSearch::Status::kFound) << step;
    EXPECT_NEAR(e.position, middle, 1e-9) << step;

    // Asked for a longer pause than there is (end − start = 69.5 samples).
    EXPECT_EQ(find_quiet_middle(detect, 0, 400, predicted, 29, q, 0.75 * pitch).status,
              EventSearch::Status::kNotFound);
    // The samples given end inside the pause: its middle is not known.
    EXPECT_EQ(find_quiet_middle(detect, 0, static_cast<std::int64_t>(c2) - 30, predicted, 29, q,
                                0.2 * pitch)
                  .status,
              EventSearch::Status::kNotFound);
    // Predicted on a pulse: the lowest sample within ± 5 of it is no quiet one.
    EXPECT_EQ(find_quiet_middle(detect, 0, 400, c2, 5, q, 0.2 * pitch).status,
              EventSearch::Status::kNotFound);
    const auto nan_beside = [&](std::int64_t n) {
      return n == static_cast<std::int64_t>(std::ceil(end)) ? std::nan("") : detect(n);
    };
    EXPECT_EQ(find_quiet_middle(nan_beside, 0, 400, predicted, 29, q, 0.2 * pitch).status,
              EventSearch::Status::kNotFound);
    // Predicted at the pause's end with a narrow search: its middle lies beyond the search (as
    // beside a flute that does not cut, whose pause is two pitches long): no event there.
    EXPECT_EQ(find_quiet_middle(detect, 0, 400, end - 3.0, 10, q, 0.2 * pitch).status,
              EventSearch::Status::kNotFound);
  }
}

// The commanded cut pauses between flutes when the pitch exceeds the engaged arc (with the helix
// lag) by a fifth of a pitch: a slot never; 3 flutes down-milling a third of the diameter (arc
// 70.5° + lag against 120°) and 4 flutes at 10 % (36.9° against 90°) do; 4 flutes up-milling
// half the diameter (90° against 90°) and 3 flutes at 60 % (101.5° against 120°: 15 %) do not.
TEST(ToothEventTemplate, TheCommandedGeometrySaysWhereTheFlutesPause) {
  const auto pauses = [](int flutes, model::Operation op, double diameter_mm, double a_e_mm) {
    model::ModelConfig c;
    c.tool.flutes = flutes;
    c.tool.diameter_mm = diameter_mm;
    c.process.operation = op;
    c.process.radial_depth_mm = a_e_mm;
    return pauses_between_flutes(c);
  };
  using model::Operation;
  EXPECT_FALSE(pauses(2, Operation::kSlot, 0.4, 0.4));
  EXPECT_TRUE(pauses(1, Operation::kSlot, 0.4, 0.4));  // 360° pitch against a 180° arc
  EXPECT_TRUE(pauses(3, Operation::kDownMilling, 0.6, 0.2));
  EXPECT_TRUE(pauses(4, Operation::kUpMilling, 1.0, 0.1));
  EXPECT_FALSE(pauses(4, Operation::kUpMilling, 1.0, 0.5));
  EXPECT_FALSE(pauses(3, Operation::kUpMilling, 1.0, 0.6));
}

// Two flutes, 120 samples a revolution, valleys of (1.2 − cos 2θ)² at 0 and π. From revolution
// 10 on, CE1's valley is gone (a hump over ±0.45π, CE2's valley kept): the revolutions that
// follow have no bounds, only the filter's extrapolation, and the tracker stops after
// kCoastRevolutions of them instead of stating bounds it never measured (CE2's events would
// otherwise keep it going for ever: lost_after counts revolutions without any event).
TEST(ToothEventTracker, GivesUpRevolutionsWhoseClosingCe1EventItCannotFind) {
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  constexpr int kPeriod = 120;
  constexpr int kRevolutions = 40;
  constexpr int kGoneFrom = 10;
  SampleRing ring(4, kPeriod * kRevolutions);
  for (std::int64_t n = 0; n < kPeriod * kRevolutions; ++n) {
    const double theta = kTwoPi * static_cast<double>(n) / kPeriod;
    const double off_ce1 = std::remainder(theta, kTwoPi);  // angle from CE1's valley
    double detect = std::pow(1.2 - std::cos(2.0 * theta), 2.0);
    if (n >= kGoneFrom * kPeriod && std::fabs(off_ce1) < 0.45 * std::numbers::pi) {
      detect = 4.84 + 0.5 * std::cos(off_ce1);
    }
    const std::array<double, 4> row{0.0, 0.0, 0.0, detect};
    ring.push(n, row.data());
  }
  ToothEventConfig config;
  config.flutes = 2;
  config.sample_rate_hz = 50000.0;
  ToothEventTracker tracker(config);
  ToothEventTemplate tmpl;
  tmpl.flutes = 2;
  tmpl.kind = ToothEventKind::kValley;
  tmpl.event_rad = {0.0, std::numbers::pi};
  tmpl.boundary_rad = tmpl.event_rad;
  tmpl.valid = true;
  signal::PhaseModel phase;
  phase.sample_rate_hz = config.sample_rate_hz;
  phase.spindle_hz = config.sample_rate_hz / kPeriod;
  phase.valid = true;
  ASSERT_TRUE(tracker.start(tmpl, phase, 5.0 * kPeriod, 0, ring, 3));
  int valid = 0, unbounded = 0;
  tracker.advance(ring, [&](const RevolutionEvents& r) {
    valid += r.valid ? 1 : 0;
    unbounded += r.bounded ? 0 : 1;
  });
  EXPECT_FALSE(tracker.active());
  EXPECT_GE(valid, kGoneFrom - 2);  // every revolution before, but those the start walked past
  // The revolution that closes on the first missing CE1 event, and the coasted ones after it.
  EXPECT_EQ(unbounded, kCoastRevolutions);
  // Stopped on its own, and says why, once.
  EXPECT_EQ(tracker.take_loss(), ToothEventLoss::kCoasted);
  EXPECT_EQ(tracker.take_loss(), ToothEventLoss::kNone);
}

}  // namespace
}  // namespace millwatch::monitor
