// The low-pass on a grid against the filter it computes another way: LowPassFilter::step()
// sample by sample (itself checked against the analytic response and scipy's sosfilt in
// butterworth_lowpass_test.cpp). On every grid sample the values agree to rounding, in either
// arithmetic (multiply-adds where the CPU has FMA, or multiplies and adds); in each, they do
// not depend on how the stream is cut into blocks, nor on the kernel, bit for bit; nothing off
// the grid is written.

#include "core/signal/grid_lowpass.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/signal/butterworth_lowpass.hpp"
#include "core/signal/cpu_features.hpp"

namespace millwatch::signal {
namespace {

constexpr double kRate_hz = 333300.0;
constexpr std::size_t kSamples = 20000;
constexpr std::int64_t kFirst = 1000007;  // the stretch's first sample: off most grids
const std::array<double, 3> kSign = {-1.0, 1.0, -1.0};
using Arithmetic = GridLowPass::Arithmetic;
constexpr std::array<Arithmetic, 2> kArithmetics = {Arithmetic::kAuto, Arithmetic::kPlain};
constexpr std::array<GridLowPass::Kernel, 3> kKernels = {
    GridLowPass::Kernel::kAuto, GridLowPass::Kernel::kScalar, GridLowPass::Kernel::kNoAvx512};

std::string name(Arithmetic arithmetic) {
  return arithmetic == Arithmetic::kPlain ? " (multiplies and adds)" : " (the CPU's arithmetic)";
}

/// A cut as the instrument channels read it: an offset, tooth passing at 840 Hz with its
/// harmonics (a cusp), 25 kHz chatter above the cut-off, and a deterministic hash as noise.
std::array<std::vector<double>, 3> cut() {
  std::array<std::vector<double>, 3> x;
  std::uint64_t h = 0x9e3779b97f4a7c15ULL;
  for (std::size_t i = 0; i < kSamples; ++i) {
    const double t = static_cast<double>(i) / kRate_hz;
    const double tooth = std::fabs(std::sin(std::numbers::pi * 840.0 * t));
    const double chatter = std::sin(2.0 * std::numbers::pi * 25000.0 * t);
    for (std::size_t a = 0; a < 3; ++a) {
      h ^= h << 13;
      h ^= h >> 7;
      h ^= h << 17;
      const double noise = static_cast<double>(h >> 11) * 0x1.0p-53 - 0.5;
      x[a].push_back(3.0 - static_cast<double>(a) + (40.0 - 15.0 * static_cast<double>(a)) * tooth +
                     2.0 * chatter + 0.3 * noise);
    }
  }
  return x;
}

/// What step() gives, from the steady state of the first input.
std::array<std::vector<double>, 3> sample_by_sample(const ButterworthDesign& d,
                                                    const std::array<std::vector<double>, 3>& x) {
  std::array<std::vector<double>, 3> y;
  for (std::size_t a = 0; a < 3; ++a) {
    LowPassFilter f(d);
    f.settle(kSign[a] * x[a][0]);
    for (const double v : x[a]) {
      y[a].push_back(f.step(kSign[a] * v));
    }
  }
  return y;
}

/// A grid filter settled on the cut's first sample, and where it writes (NaN where it does not).
struct GridRun {
  GridRun(const ButterworthDesign& d, int stride, const std::array<std::vector<double>, 3>& x,
          Arithmetic arithmetic = Arithmetic::kAuto)
      : filter(d, stride, kSign, arithmetic) {
    filter.settle(kFirst, {x[0][0], x[1][0], x[2][0]});
    for (auto& c : y) {
      c.assign(kSamples, std::numeric_limits<double>::quiet_NaN());
    }
  }
  /// The output from sample `from` on.
  std::array<double*, 3> out(std::size_t from) {
    return {y[0].data() + from, y[1].data() + from, y[2].data() + from};
  }
  GridLowPass filter;
  std::array<std::vector<double>, 3> y;
};

/// The input from sample `from` on.
std::array<const double*, 3> in(const std::array<std::vector<double>, 3>& x, std::size_t from) {
  return {x[0].data() + from, x[1].data() + from, x[2].data() + from};
}

/// The grid filter over the cut in blocks of `block` samples (NaN where it writes nothing).
std::array<std::vector<double>, 3> on_grid(const ButterworthDesign& d, int stride,
                                           const std::array<std::vector<double>, 3>& x,
                                           std::size_t block,
                                           GridLowPass::Kernel kernel = GridLowPass::Kernel::kAuto,
                                           Arithmetic arithmetic = Arithmetic::kAuto) {
  GridRun run(d, stride, x, arithmetic);
  for (std::size_t from = 0; from < kSamples; from += block) {
    run.filter.process(in(x, from), run.out(from), std::min(block, kSamples - from), kernel);
  }
  return run.y;
}

bool on_the_grid(std::size_t i, int stride) {
  return (kFirst + static_cast<std::int64_t>(i)) % stride == 0;
}

/// y and `whole` the same on every grid sample, bit for bit.
void expect_same_on_grid(const std::array<std::vector<double>, 3>& y,
                         const std::array<std::vector<double>, 3>& whole, int stride,
                         const std::string& what) {
  for (std::size_t i = 0; i < kSamples; ++i) {
    for (std::size_t a = 0; a < 3; ++a) {
      if (on_the_grid(i, stride)) {
        ASSERT_EQ(y[a][i], whole[a][i]) << what << " channel " << a << " at " << i;
      }
    }
  }
}

TEST(GridLowPass, GivesTheFiltersValuesOnEveryGridSample) {
  const auto x = cut();
  for (const int order : {1, 2, 3, 4}) {
    const ButterworthDesign d = ButterworthDesign::lowpass(kRate_hz, 3300.0, order);
    const auto truth = sample_by_sample(d, x);
    for (const int stride : {1, 2, 3, 5, 6, 8, 9, kMaxGridStride}) {
      for (const Arithmetic arithmetic : kArithmetics) {
        const auto y = on_grid(d, stride, x, 256, GridLowPass::Kernel::kAuto, arithmetic);
        int compared = 0;
        for (std::size_t i = 0; i < kSamples; ++i) {
          for (std::size_t a = 0; a < 3; ++a) {
            if (!on_the_grid(i, stride)) {
              ASSERT_TRUE(std::isnan(y[a][i])) << "written off the grid at " << i;
              continue;
            }
            // The peak is ~40 N: 1e-11 N is ~3e-13 of it, rounding summed in another order.
            ASSERT_NEAR(y[a][i], truth[a][i], 1e-11)
                << "order " << order << " stride " << stride << name(arithmetic) << " channel " << a
                << " at " << i;
            ++compared;
          }
        }
        EXPECT_GE(compared, 3 * static_cast<int>(kSamples) / stride);
      }
    }
  }
}

TEST(GridLowPass, IsTheSameWhateverTheBlocksAndTheKernel) {
  const auto x = cut();
  const ButterworthDesign d = ButterworthDesign::lowpass(kRate_hz, 3300.0, 4);
  for (const int stride : {2, 3, 5, 6, 8, 9}) {  // unrolled up to 8, a loop beyond
    for (const Arithmetic arithmetic : kArithmetics) {
      const auto whole = on_grid(d, stride, x, kSamples, GridLowPass::Kernel::kAuto, arithmetic);
      for (const std::size_t block : {1U, 2U, 5U, 333U}) {
        for (const auto kernel : kKernels) {
          expect_same_on_grid(on_grid(d, stride, x, block, kernel, arithmetic), whole, stride,
                              "stride " + std::to_string(stride) + " block " +
                                  std::to_string(block) + name(arithmetic));
        }
      }
    }
  }
}

/// Each channel's largest |x| over the cut: a limit every input is within (equal counts).
std::array<double, 3> largest(const std::array<std::vector<double>, 3>& x) {
  std::array<double, 3> m{};
  for (std::size_t a = 0; a < 3; ++a) {
    for (const double v : x[a]) {
      m[a] = std::max(m[a], std::fabs(v));
    }
  }
  return m;
}

// process_checked() on inputs within their limits (the largest reaching it exactly) filters
// as process() does, bit for bit, whatever the blocks and the kernel.
TEST(GridLowPass, ProcessCheckedIsProcessWhileEveryInputIsWithin) {
  const auto x = cut();
  const std::array<double, 3> limit = largest(x);
  const ButterworthDesign d = ButterworthDesign::lowpass(kRate_hz, 3300.0, 4);
  for (const int stride : {1, 2, 3, 5, 6, 8, 9, kMaxGridStride}) {
    for (const Arithmetic arithmetic : kArithmetics) {
      const auto whole = on_grid(d, stride, x, kSamples, GridLowPass::Kernel::kAuto, arithmetic);
      for (const std::size_t block : {1U, 5U, 333U, 4096U}) {
        for (const auto kernel : kKernels) {
          GridRun run(d, stride, x, arithmetic);
          for (std::size_t from = 0; from < kSamples; from += block) {
            ASSERT_TRUE(run.filter.process_checked(in(x, from), run.out(from),
                                                   std::min(block, kSamples - from), limit, kernel))
                << "stride " << stride << " block " << block << " from " << from;
          }
          expect_same_on_grid(run.y, whole, stride,
                              "stride " + std::to_string(stride) + " block " +
                                  std::to_string(block) + name(arithmetic));
        }
      }
    }
  }
}

// One input not within its channel's limit — a NaN, an infinity, the next double above the
// limit either side, or another channel's largest value where it exceeds this channel's —
// anywhere in a block (a stride's first input or a later one, the inputs a block leaves for the
// next stride, those that complete the last block's): process_checked() says so and leaves the
// filter as it was, so that the block filtered again (as the monitor does once the input check
// has replaced the sample) gives every later value as if the refused call had not been made.
TEST(GridLowPass, ProcessCheckedRefusesAnInputBeyondItsLimitAndLeavesTheFilterAsItWas) {
  const auto x = cut();
  const std::array<double, 3> limit = largest(x);  // ~45, ~27 and ~12 N
  const ButterworthDesign d = ButterworthDesign::lowpass(kRate_hz, 3300.0, 4);
  const double inf = std::numeric_limits<double>::infinity();
  int refused = 0;
  for (const int stride : {3, 6, 9}) {
    for (const Arithmetic arithmetic : kArithmetics) {
      const auto whole = on_grid(d, stride, x, kSamples, GridLowPass::Kernel::kAuto, arithmetic);
      for (const std::size_t block : {5U, 333U}) {
        const std::size_t tampered_from = 7 * block;  // the eighth block
        for (const std::size_t at : {std::size_t{0}, std::size_t{1}, block / 2, block - 1}) {
          for (std::size_t a = 0; a < 3; ++a) {
            const std::array<double, 5> bad = {std::numeric_limits<double>::quiet_NaN(), inf, -inf,
                                               std::nextafter(limit[a], inf),
                                               -std::nextafter(limit[a], inf)};
            std::vector<double> values(bad.begin(), bad.end());
            if (a > 0) {
              values.push_back(limit[0]);  // within channel 0's limit, beyond this one's
            }
            for (const double v : values) {
              for (const auto kernel : kKernels) {
                GridRun run(d, stride, x, arithmetic);
                for (std::size_t from = 0; from < kSamples; from += block) {
                  const std::size_t n = std::min(block, kSamples - from);
                  if (from == tampered_from) {
                    std::array<std::vector<double>, 3> t;
                    for (std::size_t c = 0; c < 3; ++c) {
                      t[c].assign(in(x, from)[c], in(x, from)[c] + n);
                    }
                    t[a][at] = v;
                    ASSERT_FALSE(run.filter.process_checked({t[0].data(), t[1].data(), t[2].data()},
                                                            run.out(from), n, limit, kernel))
                        << "stride " << stride << " block " << block << " at " << at << " channel "
                        << a << " value " << v;
                    ++refused;
                  }
                  ASSERT_TRUE(
                      run.filter.process_checked(in(x, from), run.out(from), n, limit, kernel));
                }
                expect_same_on_grid(run.y, whole, stride,
                                    "stride " + std::to_string(stride) + " block " +
                                        std::to_string(block) + " refused at " +
                                        std::to_string(at) + name(arithmetic));
              }
            }
          }
        }
      }
    }
  }
  EXPECT_EQ(refused, 3 * 2 * 2 * 4 * (5 + 6 + 6) * 3);
}

TEST(GridLowPass, HoldsAConstantInputWithoutATransient) {
  const ButterworthDesign d = ButterworthDesign::lowpass(kRate_hz, 3300.0, 4);
  for (const Arithmetic arithmetic : kArithmetics) {
    GridLowPass g(d, 3, kSign, arithmetic);
    g.settle(kFirst, {5.0, -2.0, 0.25});
    std::array<std::vector<double>, 3> x = {std::vector<double>(999, 5.0),
                                            std::vector<double>(999, -2.0),
                                            std::vector<double>(999, 0.25)};
    std::array<std::vector<double>, 3> y = {std::vector<double>(999, 0.0),
                                            std::vector<double>(999, 0.0),
                                            std::vector<double>(999, 0.0)};
    g.process({x[0].data(), x[1].data(), x[2].data()}, {y[0].data(), y[1].data(), y[2].data()},
              999);
    for (std::size_t i = 0; i < 999; ++i) {
      if (on_the_grid(i, 3)) {
        EXPECT_NEAR(y[0][i], -5.0, 5e-12);  // rounding, ~1e-13 of the level
        EXPECT_NEAR(y[1][i], -2.0, 2e-12);
        EXPECT_NEAR(y[2][i], -0.25, 2.5e-13);
      }
    }
  }
}

// Multiply-adds where the CPU has FMA (AVX2 and FMA3; this one: see the test's output), unless
// asked for multiplies and adds.
TEST(GridLowPass, ComputesInMultiplyAddsWhereTheCpuHasThem) {
  const ButterworthDesign d = ButterworthDesign::lowpass(kRate_hz, 3300.0, 4);
  EXPECT_EQ(GridLowPass(d, 3, kSign).fused(), cpu_has_fma());
  EXPECT_FALSE(GridLowPass(d, 3, kSign, Arithmetic::kPlain).fused());
  // What the other tests covered here: without FMA, the plain arithmetic alone; without
  // AVX-512, the multiply-adds' AVX2 kernel alone.
  std::printf("this CPU: FMA %s, AVX-512 %s\n",
              cpu_has_fma() ? "yes" : "no (multiply-adds untested)",
              cpu_has_avx512vl() ? "yes" : "no (its kernel untested)");
}

TEST(GridLowPass, SaysWhatItCannotRun) {
  const ButterworthDesign order5 = ButterworthDesign::lowpass(kRate_hz, 3300.0, 5);
  const ButterworthDesign order4 = ButterworthDesign::lowpass(kRate_hz, 3300.0, 4);
  EXPECT_FALSE(GridLowPass::supports(order5, 3));
  EXPECT_FALSE(GridLowPass::supports(order4, 0));
  EXPECT_FALSE(GridLowPass::supports(order4, kMaxGridStride + 1));
  EXPECT_FALSE(GridLowPass::supports(ButterworthDesign{}, 3));
  EXPECT_TRUE(GridLowPass::supports(order4, 3));
  EXPECT_THROW(GridLowPass(order5, 3, kSign), std::invalid_argument);
  EXPECT_THROW(GridLowPass(order4, kMaxGridStride + 1, kSign), std::invalid_argument);
}

}  // namespace
}  // namespace millwatch::signal
