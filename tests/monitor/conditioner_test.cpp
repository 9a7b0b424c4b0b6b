// The conditioner against its own sample-by-sample path (push(): axis map, one filter step per
// channel, the tare), which is what the block path must give: push_block() hands on the same
// mapped, filtered, tared values bit for bit in runs of any length. With a stride (the
// pipeline's measuring grid) it filters the grid's samples alone (signal::GridLowPass) and the
// tare and its envelope follow them: the same values on the grid to rounding and the tare's
// few samples of lead, whatever the runs — checked with an offset the tare has learnt while
// quiet, and a cut during which it stands.

#include "core/monitor/conditioner.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <numbers>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "core/signal/butterworth_lowpass.hpp"

namespace millwatch::monitor {
namespace {

struct Output {
  std::vector<double> fx, fy, fz;
  std::array<double, 3> tare_N{};   // at the end
  std::vector<double> envelope_sq;  // at the end of each block
};

constexpr double kRate_hz = 333300.0;
constexpr std::int64_t kBlock = 333;
constexpr std::int64_t kCutStart = 180 * kBlock;  // on a block's edge: 0.18 s quiet
constexpr std::int64_t kSamples = kCutStart + 20 * kBlock;

MonitorConfig config() {
  MonitorConfig c;
  c.sample_rate_hz = kRate_hz;
  c.axis_map.sign = {-1.0, 1.0, -1.0};
  c.axis_map.source = {1, 0, 2};  // x from the second channel, y from the first
  return c;
}

/// Instrument channels: an offset (what the tare learns) and, from kCutStart, a cut. In the
/// model frame the offset is (2, 3, −1.5) N.
std::array<double, 3> reading(std::int64_t n) {
  const double t = static_cast<double>(n) / kRate_hz;
  const double cut = n >= kCutStart ? 40.0 * std::sin(2.0 * std::numbers::pi * 840.0 * t) : 0.0;
  return {3.0 + cut, -2.0 + 0.5 * cut, 1.5 - 0.25 * cut};
}

/// Quiet before the cut (the tare learns the offset), cutting after (the tare stands); the
/// pipeline says so between blocks.
void set_state(Conditioner& c, std::int64_t n) {
  c.set_quiet(n < kCutStart, 50.0);
}

Output sample_by_sample() {
  Conditioner c(config(), signal::ButterworthDesign::lowpass(kRate_hz, 3300.0, 4));
  Output o;
  for (std::int64_t n = 0; n < kSamples; ++n) {
    set_state(c, n);
    c.push(n, reading(n), [&](std::int64_t, double x, double y, double z) {
      o.fx.push_back(x);
      o.fy.push_back(y);
      o.fz.push_back(z);
    });
    if ((n + 1) % kBlock == 0) {
      o.envelope_sq.push_back(c.envelope_sq_N2());
    }
  }
  o.tare_N = c.tare_N();
  return o;
}

/// Changes block `index`'s instrument channels (x, y, z) before they are pushed.
using Tamper = std::function<void(std::int64_t index, std::vector<double>& x,
                                  std::vector<double>& y, std::vector<double>& z)>;

/// A block's way in with filter_checked(): each block is offered to it with `limit` (by input
/// channel) first, and pushed by push_block() when refused, after `repair` if any (as the
/// pipeline does, after the input check); `refused` counts those.
struct Checked {
  std::array<double, 3> limit{};
  Tamper repair;
  int refused = 0;
};

/// push_block() in blocks of 333 and runs of up to `run` samples, sample n numbered origin + n;
/// what the caller reads: every sample on the stride's grid (NaN elsewhere).
Output in_blocks(int stride, std::size_t run, std::int64_t origin = 0, Checked* checked = nullptr,
                 const Tamper& tamper = {}) {
  Conditioner c(config(), signal::ButterworthDesign::lowpass(kRate_hz, 3300.0, 4));
  c.set_stride(stride);
  Output o;
  o.fx.assign(kSamples, NAN);
  o.fy.assign(kSamples, NAN);
  o.fz.assign(kSamples, NAN);
  std::vector<double> x, y, z;
  for (std::int64_t first = 0; first < kSamples; first += kBlock) {
    x.clear();
    y.clear();
    z.clear();
    for (std::int64_t n = first; n < first + kBlock; ++n) {
      const auto r = reading(n);
      x.push_back(r[0]);
      y.push_back(r[1]);
      z.push_back(r[2]);
    }
    if (tamper) {
      tamper(first / kBlock, x, y, z);
    }
    set_state(c, first);
    const auto limit = [run](std::int64_t) { return run; };
    const auto out = [&](std::int64_t n, std::size_t count, const double* fx, const double* fy,
                         const double* fz) {
      ASSERT_LE(count, static_cast<std::size_t>(kBlock));
      for (std::size_t i = 0; i < count; ++i) {
        const std::int64_t s = n + static_cast<std::int64_t>(i);
        if (s % stride == 0) {
          const auto at = static_cast<std::size_t>(s - origin);
          o.fx[at] = fx[i];
          o.fy[at] = fy[i];
          o.fz[at] = fz[i];
        }
      }
    };
    if (checked != nullptr && c.filter_checked(origin + first, x, y, z, checked->limit)) {
      c.hand_on_checked(limit, out);
    } else {
      if (checked != nullptr) {
        ++checked->refused;
        if (checked->repair) {
          checked->repair(first / kBlock, x, y, z);
        }
      }
      c.push_block(origin + first, x, y, z, limit, out);
    }
    o.envelope_sq.push_back(c.envelope_sq_N2());
  }
  o.tare_N = c.tare_N();
  return o;
}

TEST(Conditioner, BlocksGiveTheSampleBySampleValues) {
  const Output truth = sample_by_sample();
  // The tare learnt the offset while quiet (time constant 0.05 s) and stood during the cut: the
  // comparisons below are of tared values.
  EXPECT_NEAR(truth.tare_N[0], 2.0, 0.1);
  EXPECT_NEAR(truth.tare_N[1], 3.0, 0.15);
  EXPECT_NEAR(truth.tare_N[2], -1.5, 0.1);
  for (const std::size_t run : {1U, 7U, 1000U}) {
    const Output o = in_blocks(1, run);
    for (std::int64_t n = 0; n < kSamples; ++n) {
      const auto i = static_cast<std::size_t>(n);
      ASSERT_EQ(o.fx[i], truth.fx[i]) << "run " << run << " at " << n;
      ASSERT_EQ(o.fy[i], truth.fy[i]) << "run " << run << " at " << n;
      ASSERT_EQ(o.fz[i], truth.fz[i]) << "run " << run << " at " << n;
    }
    EXPECT_EQ(o.tare_N, truth.tare_N);
  }
}

// On a grid: the filter's values to rounding, tared by a tare that learnt the same offset at
// the same rate (a grid step's gain), a few samples ahead: within 1e-4 N of push()'s, where a
// sample off the grid would be ~0.6 N off during the cut. And the same whatever the runs, bit
// for bit; with sample numbers from 0, and from a negative one off the grid (−100,001).
TEST(Conditioner, AStrideGivesTheSampleBySampleValuesOnTheGrid) {
  const Output truth = sample_by_sample();
  for (const std::int64_t origin : {std::int64_t{0}, std::int64_t{-100001}}) {
    for (const int stride : {3, 6, signal::kMaxGridStride}) {
      const Output reference = in_blocks(stride, 1000, origin);
      for (const std::size_t run : {1U, 7U, 1000U}) {
        const Output o = in_blocks(stride, run, origin);
        int compared = 0;
        for (std::int64_t n = 0; n < kSamples; ++n) {
          const auto i = static_cast<std::size_t>(n);
          if ((origin + n) % stride != 0) {
            continue;
          }
          // The grid's tare leads by up to stride − 1 samples of its gain, 1/(0.05 s·333.3 kHz),
          // times what it has left to learn: up to 3.6 N while quiet, ~0.1 N by the cut.
          const double lead = stride / (0.05 * kRate_hz);
          const double tolerance = lead * (n < kCutStart ? 3.7 : 0.35);
          ASSERT_NEAR(o.fx[i], truth.fx[i], tolerance)
              << "stride " << stride << " run " << run << " at " << n;
          ASSERT_NEAR(o.fy[i], truth.fy[i], tolerance)
              << "stride " << stride << " run " << run << " at " << n;
          ASSERT_NEAR(o.fz[i], truth.fz[i], tolerance)
              << "stride " << stride << " run " << run << " at " << n;
          ASSERT_EQ(o.fx[i], reference.fx[i])
              << "stride " << stride << " run " << run << " at " << n;
          ASSERT_EQ(o.fy[i], reference.fy[i])
              << "stride " << stride << " run " << run << " at " << n;
          ASSERT_EQ(o.fz[i], reference.fz[i])
              << "stride " << stride << " run " << run << " at " << n;
          compared += n >= kCutStart ? 1 : 0;
        }
        EXPECT_GE(compared, (kSamples - kCutStart) / stride);
        for (std::size_t a = 0; a < 3; ++a) {
          EXPECT_NEAR(o.tare_N[a], truth.tare_N[a], 1e-4) << "stride " << stride << " axis " << a;
          EXPECT_EQ(o.tare_N[a], reference.tare_N[a]) << "stride " << stride << " axis " << a;
        }
      }
    }
  }
}

/// Output a and b the same, bit for bit (NaN where neither is on the grid).
void expect_same(const Output& a, const Output& b, const std::string& what) {
  for (std::size_t i = 0; i < a.fx.size(); ++i) {
    for (const auto& [p, q] :
         {std::pair{a.fx[i], b.fx[i]}, std::pair{a.fy[i], b.fy[i]}, std::pair{a.fz[i], b.fz[i]}}) {
      ASSERT_TRUE(p == q || (std::isnan(p) && std::isnan(q))) << what << " at " << i;
    }
  }
  EXPECT_EQ(a.tare_N, b.tare_N) << what;
  EXPECT_EQ(a.envelope_sq, b.envelope_sq) << what;
}

// Blocks whose samples are all within their limits, filtered with their check and handed on
// by hand_on_checked(), give what push_block() gives, bit for bit: values, runs, tare,
// envelope; every sample measured (stride 1: blocks longer than push_block()'s chunks), on
// every grid, and from any sample number.
TEST(Conditioner, FilterCheckedHandsOnWhatPushBlockDoes) {
  for (const std::int64_t origin : {std::int64_t{0}, std::int64_t{-100001}}) {
    for (const int stride : {1, 3, 6, signal::kMaxGridStride}) {
      for (const std::size_t run : {1U, 7U, 1000U}) {
        Checked checked{{1e6, 1e6, 1e6}, {}};
        const Output o = in_blocks(stride, run, origin, &checked);
        EXPECT_EQ(checked.refused, 0);
        expect_same(o, in_blocks(stride, run, origin),
                    "stride " + std::to_string(stride) + " run " + std::to_string(run));
      }
    }
  }
}

// Each sample is held to its input channel's limit, whatever model axis the axis map makes of
// it (x from the second channel, y from the first): 50 N is beyond the second channel's 40 N
// but within the first's 100 N, 1,001 N beyond the third's 1,000 N; a NaN is beyond every
// limit. A block refused (the first, whose first sample settles the filter; one while quiet;
// one while cutting) leaves the conditioner as it was: push_block() then gives everything
// after as if the block had gone that way alone — repaired as the input check repairs it (a
// NaN replaced by a good value), the first block's filter settled on what it was repaired to.
TEST(Conditioner, FilterCheckedRefusesASampleBeyondItsInputChannelsLimit) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  struct Change {
    std::size_t channel;
    double value;
    bool refused;
  };
  for (const Change change :
       {Change{1, 50.0, true}, Change{0, 50.0, false}, Change{2, 1001.0, true},
        Change{2, 999.0, false}, Change{0, nan, true}}) {
    for (const int stride : {1, 3, 6}) {
      for (const std::size_t at : {std::size_t{0}, std::size_t{160}, std::size_t{kBlock - 1}}) {
        const Tamper tamper = [&](std::int64_t index, std::vector<double>& x,
                                  std::vector<double>& y, std::vector<double>& z) {
          if (index == 0 || index == 5 || index == 185) {
            (change.channel == 0 ? x : change.channel == 1 ? y : z)[at] = change.value;
          }
        };
        const Tamper repair = [&](std::int64_t, std::vector<double>& x, std::vector<double>& y,
                                  std::vector<double>& z) {
          for (auto* channel : {&x, &y, &z}) {
            for (double& v : *channel) {
              v = std::isnan(v) ? 7.0 : v;
            }
          }
        };
        Checked checked{{100.0, 40.0, 1000.0}, repair};
        const Output o = in_blocks(stride, 7, 0, &checked, tamper);
        EXPECT_EQ(checked.refused, change.refused ? 3 : 0) << change.channel << " " << change.value;
        const Tamper repaired = [&](std::int64_t index, std::vector<double>& x,
                                    std::vector<double>& y, std::vector<double>& z) {
          tamper(index, x, y, z);
          repair(index, x, y, z);
        };
        expect_same(o, in_blocks(stride, 7, 0, nullptr, repaired),
                    "channel " + std::to_string(change.channel) + " value " +
                        std::to_string(change.value) + " stride " + std::to_string(stride));
      }
    }
  }
}

// filter_checked() takes blocks of up to kCheckedBlock samples, on a grid or not: longer ones,
// and any under zero-phase filtering, are left to push_block() (refused, the conditioner
// untouched).
TEST(Conditioner, FilterCheckedTakesBlocksUpToItsLength) {
  const std::vector<double> quiet(Conditioner::kCheckedBlock + 1, 1.0);
  const std::span<const double> all(quiet), most = all.first(Conditioner::kCheckedBlock);
  const std::array<double, 3> limit = {1e6, 1e6, 1e6};
  const auto design = signal::ButterworthDesign::lowpass(kRate_hz, 3300.0, 4);
  Conditioner on_grid(config(), design);
  on_grid.set_stride(3);
  EXPECT_FALSE(on_grid.filter_checked(0, all, all, all, limit));
  EXPECT_TRUE(on_grid.filter_checked(0, most, most, most, limit));
  Conditioner every(config(), design);
  EXPECT_FALSE(every.filter_checked(0, all, all, all, limit));
  EXPECT_TRUE(every.filter_checked(0, most, most, most, limit));
  MonitorConfig zero_phase = config();
  zero_phase.filter_zero_phase = true;
  Conditioner both_ways(zero_phase, design);
  EXPECT_FALSE(both_ways.filter_checked(0, most, most, most, limit));
}

// On a grid, push() is a block of one sample: the grid's samples alone come out, the values of
// push_block() in runs of one, bit for bit.
TEST(Conditioner, OnAGridPushIsABlockOfOneSample) {
  const Output blocks = in_blocks(3, 1);
  Conditioner c(config(), signal::ButterworthDesign::lowpass(kRate_hz, 3300.0, 4));
  c.set_stride(3);
  int heard = 0;
  for (std::int64_t n = 0; n < kSamples; ++n) {
    set_state(c, n);
    c.push(n, reading(n), [&](std::int64_t s, double x, double y, double z) {
      ASSERT_EQ(s, n);
      ASSERT_EQ(s % 3, 0);
      const auto i = static_cast<std::size_t>(s);
      ASSERT_EQ(x, blocks.fx[i]) << "at " << s;
      ASSERT_EQ(y, blocks.fy[i]) << "at " << s;
      ASSERT_EQ(z, blocks.fz[i]) << "at " << s;
      ++heard;
    });
  }
  EXPECT_EQ(heard, (kSamples + 2) / 3);
  EXPECT_EQ(c.tare_N(), blocks.tare_N);
}

/// The envelope e = max(x², e·d) of push()'s tared values over the samples on a stride's grid
/// alone (the others only decay it), at the end of each block: what the grid's should be.
std::vector<double> grid_envelope(const Output& truth, int stride) {
  const double revolution_hz = config().model.process.spindle_rpm / 60.0;
  const double d = std::exp(-2.0 / (2.0 * kRate_hz / revolution_hz));
  std::vector<double> out;
  double e = 0.0;
  for (std::int64_t n = 0; n < kSamples; ++n) {
    const auto i = static_cast<std::size_t>(n);
    e *= d;
    if (n % stride == 0) {
      e = std::max(e, truth.fx[i] * truth.fx[i] + truth.fy[i] * truth.fy[i]);
    }
    if ((n + 1) % kBlock == 0) {
      out.push_back(e);
    }
  }
  return out;
}

// During the cut the block path keeps the envelope as four interleaved recursions (SSE2 pairs
// where the CPU has them) over each run: the same peak, sample by sample, as push()'s one
// recursion e = max(x², e·d), up to the rounding of the powers of d (which depends on how the
// samples fall into runs). On a grid it is that recursion over the grid's samples (which lag
// the last samples of a block, where the force rises, by up to stride − 1 samples: a few % of
// the square): within the tare's difference of the same recursion over push()'s values there.
TEST(Conditioner, TheEnvelopeInBlocksIsTheSampleBySampleOne) {
  const Output truth = sample_by_sample();
  for (const std::size_t run : {1U, 7U, 1000U}) {
    const Output all = in_blocks(1, run);
    ASSERT_EQ(all.envelope_sq.size(), truth.envelope_sq.size());
    for (std::size_t b = static_cast<std::size_t>(kCutStart / kBlock); b < all.envelope_sq.size();
         ++b) {
      EXPECT_GT(truth.envelope_sq[b], 100.0);  // a cut's (tens of newtons)², not the offset's
      EXPECT_NEAR(all.envelope_sq[b], truth.envelope_sq[b], 1e-12 * truth.envelope_sq[b])
          << "run " << run << " block " << b;
    }
    for (const int stride : {3, 6, signal::kMaxGridStride}) {
      const Output grid = in_blocks(stride, run);
      const std::vector<double> expected = grid_envelope(truth, stride);
      ASSERT_EQ(grid.envelope_sq.size(), expected.size());
      for (std::size_t b = static_cast<std::size_t>(kCutStart / kBlock);
           b < grid.envelope_sq.size(); ++b) {
        EXPECT_NEAR(grid.envelope_sq[b], expected[b], 2e-5 * expected[b])
            << "stride " << stride << " run " << run << " block " << b;
      }
    }
  }
}

}  // namespace
}  // namespace millwatch::monitor
