#pragma once
// The causal low-pass of three force channels, read only on a grid: every stride-th sample (the
// monitor's measuring grid, every third at 333.3 kHz). The stages after the low-pass read no
// other sample, so this filter computes no other: it advances the state a stride at a time by
// the look-ahead of the filter's state-space form,
//
//   z(g + k) = A^k·z(g) + Σ_{j<k} A^(k−1−j)·B·x(g + j),   y(g) = C·z(g) + D·x(g),
//
// where z holds the delay elements of the cascade's sections (direct form II transposed, the
// state LowPassFilter keeps) in the sections' modal basis, and A, B, C, D are read off one step
// of that cascade. Section 2 follows section 1, so in LowPassFilter's basis A^k is block lower
// triangular (12 multiplies a stride); section 2's delay elements taken as w = z₂ + K·z₁, with K
// solving the Sylvester equation A₂·K − K·A₁ = M (M: section 1's drive of section 2), evolve by
// A₂ alone, and A^k is block diagonal: 8 multiplies, and C reads w's first element with weight
// 1 (an add). The chain of dependent operations is then two multiply-adds a stride (without FMA
// a multiply and two adds) instead of a multiply and an add a sample, which is what bounds
// LowPassFilter::step (its recursion's latency), and it computes one sample in k.
//
// The values on the grid are the filter's, up to rounding (they are summed in another order:
// within ~1e-13 of the signal's peak, tests/signal/grid_lowpass_test.cpp), and they do not depend
// on how the stream is cut into blocks, bit for bit: the state always advances by whole strides
// from a grid sample, the inputs of a stride that a block leaves unfinished wait for the next
// block. Where the CPU has FMA (AVX2 and FMA3) it computes in multiply-adds (24 operations a
// stride of 3, 23 of them multiplies, instead of 42 without FMA; with AVX-512's 32
// registers, fewer constants read from the stack); other CPUs, or Arithmetic::kPlain, in
// multiplies and adds (bench/HISTORY.md, the seventy-seventh and seventy-ninth stops). Either way
// the vector kernels (three channels side by side in one register, each compiled for its
// instruction set and run only where the CPU has it) do the same operations in the same order as
// the scalar one: the same results, bit for bit. The two arithmetics differ by rounding (~1e-13 of
// the peak): a replay on a CPU with FMA and on one without agree to that.
//
// Designs with at most two sections (orders 1–4; the monitor's is order 4) and strides up to
// kMaxGridStride; supports() says which. Set up once; settle() and process() allocate nothing.

#include <array>
#include <cstddef>
#include <cstdint>

#include "core/signal/butterworth_lowpass.hpp"

namespace millwatch::signal {

inline constexpr int kMaxGridStride = 16;

class GridLowPass {
 public:
  /// The fastest kernel this CPU runs in the arithmetic chosen (AVX where it has it; in
  /// multiply-adds, AVX-512's registers where it has them), the scalar one, or the fastest
  /// without AVX-512 (for the tests): the same results.
  enum class Kernel { kAuto, kScalar, kNoAvx512 };
  /// The arithmetic: multiply-adds where the CPU has FMA (kAuto), or multiplies and adds
  /// (kPlain, the one arithmetic before; the tests run both).
  enum class Arithmetic { kAuto, kPlain };

  /// Four delay elements: section 1's z0, z1, then section 2's in the modal basis,
  /// w = z₂ + K·z₁ (the file comment).
  using State = std::array<double, 4>;

  GridLowPass() = default;

  /// @param design at most two sections (supports())
  /// @param stride 1..kMaxGridStride: the grid is every sample whose number is a multiple of it
  /// @param sign each channel's input is taken as sign[a]·x (the axis map's ±1, exact)
  /// @throws std::invalid_argument if the design or the stride is not supported.
  GridLowPass(const ButterworthDesign& design, int stride, const std::array<double, 3>& sign,
              Arithmetic arithmetic = Arithmetic::kAuto);

  /// Whether a design and a stride can run on a grid.
  [[nodiscard]] static bool supports(const ButterworthDesign& design, int stride);
  /// Whether it computes in multiply-adds (Arithmetic).
  [[nodiscard]] bool fused() const { return fused_; }

  /// Starts a stretch at sample `n`: each channel as if its input had been `raw[a]` for ever
  /// (LowPassFilter::settle of sign[a]·raw[a]: no start-up transient).
  void settle(std::int64_t n, const std::array<double, 3>& raw);

  /// Filters the next `count` samples (from the settled one, or after the last processed):
  /// out[a][i] = the filter's output for every i whose sample number is a multiple of the stride;
  /// out[a] is not written elsewhere. `in` and `out` may not overlap.
  void process(const std::array<const double*, 3>& in, const std::array<double*, 3>& out,
               std::size_t count, Kernel kernel = Kernel::kAuto);

  /// process() testing every input on the way, as the monitor's input check does: true when
  /// |in[a][i]| ≤ limit[a] for every channel and sample (a NaN is not), the samples then
  /// filtered as process() filters them, bit for bit; false otherwise, the filter then as it was
  /// before the call (out written with anything). The check of a block the filter reads first
  /// costs no pass of its own over the block (monitor::Conditioner::filter_checked).
  [[nodiscard]] bool process_checked(const std::array<const double*, 3>& in,
                                     const std::array<double*, 3>& out, std::size_t count,
                                     const std::array<double, 3>& limit,
                                     Kernel kernel = Kernel::kAuto);

  /// Look-ahead coefficients (row-major A^k; column j of the input gain A^(k−1−j)·B; C; D),
  /// in the modal basis, and that basis's K (State).
  struct LookAhead {
    std::array<std::array<double, 4>, 4> power{};
    std::array<State, kMaxGridStride> input{};
    State output{};
    double direct = 0.0;
    std::array<std::array<double, 2>, 2> coupling{};
  };

 private:
  /// process(), and with `limit` its check: whether every input was within.
  bool run(const std::array<const double*, 3>& in, const std::array<double*, 3>& out,
           std::size_t count, Kernel kernel, const std::array<double, 3>* limit);
  void advance_pending();

  ButterworthDesign design_;
  LookAhead look_{};
  int stride_ = 1;
  std::array<double, 3> sign_{1.0, 1.0, 1.0};
  bool fused_ = false;
  std::array<State, 3> z_{};  // per channel, at the grid sample of pending_'s first input
  std::array<std::array<double, kMaxGridStride>, 3> pending_{};  // raw inputs of a part-stride
  int pending_count_ = 0;
};

}  // namespace millwatch::signal
