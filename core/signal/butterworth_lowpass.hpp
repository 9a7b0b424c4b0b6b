#pragma once
// Digital Butterworth low-pass filter of the force channels ([000] Sect. 5 low-pass filters the
// dynamometer forces at 3.3 kHz before reading tooth periods and peak forces).
//
// Design (ButterworthDesign::lowpass): the analog prototype of order n has its poles at
//   p_k = Ω_c·exp(jπ(2k + n + 1)/(2n)),  k = 0..n−1,
// with the cut-off pre-warped, Ω_c = 2·f_s·tan(π·f_c/f_s), so that the bilinear transform
// s = 2·f_s·(1 − z⁻¹)/(1 + z⁻¹) puts the −3.01 dB point exactly at f_c. Each conjugate pair
// becomes one second-order section (odd n adds one first-order section for the real pole). With
// w = tan(π·f_c/f_s) and q = −2·Re(p_k)/Ω_c = 2·sin(π(2k + 1)/(2n)) a section is
//   H_k(z) = w²·(1 + z⁻¹)² / ((1 + q·w + w²) + 2·(w² − 1)·z⁻¹ + (1 − q·w + w²)·z⁻²),
// and the first-order one H(z) = w·(1 + z⁻¹)/((1 + w) + (w − 1)·z⁻¹). Every section has unit
// gain at DC, and the cascade has exactly
//   |H(e^{jω})|² = 1 / (1 + (tan(ω/2)/tan(ω_c/2))^{2n}),   ω = 2π·f/f_s.
//
// Coefficients live apart from state (as iir1 and Drake do): a ButterworthDesign is a plain
// value set once, a ButterworthState the history of one channel.
//
// Causal streaming: one LowPassFilter per channel (the monitor keeps three, for Fx, Fy, Fz; each
// holds its own copy of the design (under 200 bytes), so channels are independent objects that can
// be stepped sample by sample or block by block). setup() once, then process() blocks of any size
// or step() single samples: the output does not depend on how the stream is cut into blocks,
// and nothing allocates. reset() returns to rest; settle(x) starts from the steady state of a
// constant x (a stream that starts mid-cut has no start-up transient).
//
// Timing: the filter delays a component of frequency f by the group delay
// τ_g(f) = −dφ/dω (an envelope, an event) and a pure tone by the phase delay τ_φ(f) = −φ(ω)/ω,
// both exact from the coefficients. The monitor subtracts τ_g at the tooth-passing frequency from
// event times. A valley that is not sinusoidal (a cusp like |sin|) is a sum of harmonics, each
// delayed by its own τ_φ, so its filtered minimum moves by a |H|-weighted mean of those: with
// the default filter (order 4, 3.3 kHz) and 840 Hz tooth passing, τ_g(840 Hz) + 7.6 µs at
// 50 kHz and + 6.8 µs at 333.3 kHz (about 1° of spindle angle at 25,000 rpm). Valley periods are
// not changed at all. (tests/signal/butterworth_lowpass_test.cpp,
// CausalValleyTimesAfterGroupDelayCorrection.)
//
// Offline: filtfilt() runs the filter forwards and then backwards over a whole record (zero
// phase, magnitude |H|²), with odd reflection padding and steady-state initial conditions like
// scipy.signal.sosfiltfilt.

#include <array>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <complex>
#include <cstddef>
#include <span>

#include "core/signal/cpu_features.hpp"

namespace millwatch::signal {

/// Highest supported order; the design keeps its sections in fixed arrays of this size.
inline constexpr int kMaxButterworthOrder = 8;
inline constexpr int kMaxButterworthSections = (kMaxButterworthOrder + 1) / 2;

/// One section, a0 normalised to 1:  y[i] = b0·x[i] + b1·x[i−1] + b2·x[i−2] − a1·y[i−1] −
/// a2·y[i−2]. A first-order section has b2 = a2 = 0.
struct Biquad {
  double b0 = 1.0, b1 = 0.0, b2 = 0.0, a1 = 0.0, a2 = 0.0;
};

/// Coefficients of a digital Butterworth low-pass as cascaded sections (see the file comment).
/// Only sos[0..sections) are used. A default-constructed design has no sections: it passes the
/// input through unchanged.
struct ButterworthDesign {
  double sample_rate_hz = 0.0;
  double cutoff_hz = 0.0;
  int order = 0;
  int sections = 0;  ///< ⌈order/2⌉; the first-order section of an odd order comes last
  std::array<Biquad, kMaxButterworthSections> sos{};

  /// Designs the filter by the bilinear transform with the cut-off pre-warped.
  /// @param sample_rate_hz finite, > 0 (the monitor runs at 20–333.3 kHz).
  /// @param cutoff_hz the −3.01 dB frequency, in (0, 0.45·sample_rate_hz).
  /// @param order 1..8 (attenuation 6·order dB per octave above the cut-off).
  /// @throws std::invalid_argument naming the parameter, its value and the allowed range.
  static ButterworthDesign lowpass(double sample_rate_hz, double cutoff_hz, int order = 4);

  /// Frequency response H(e^{jω}), ω = 2π·frequency_hz/sample_rate_hz (any finite frequency).
  [[nodiscard]] std::complex<double> response(double frequency_hz) const;

  /// Unwrapped phase φ(ω) = arg H(e^{jω}) in rad, continuous from φ(0) = 0 (it falls to
  /// −order·π/2 towards the Nyquist frequency). Exact: every section's poles lie inside and its
  /// zeros on the unit circle, so each factor's principal argument is its continuous phase.
  /// @param frequency_hz in [0, sample_rate_hz/2). @throws std::invalid_argument otherwise.
  [[nodiscard]] double phase_rad(double frequency_hz) const;

  /// Group delay τ_g = −dφ/dω in samples, exact from the coefficients: for a section polynomial
  /// P(e^{jω}) = Σ c_k·e^{−jωk}, −d arg P/dω = Re(Σ k·c_k·e^{−jωk} / P), numerators minus
  /// denominators. Default: at DC, where the analytic value is 1/(2·tan(π·f_c/f_s)·sin(π/(2n))).
  /// @param frequency_hz in [0, sample_rate_hz/2). @throws std::invalid_argument otherwise.
  [[nodiscard]] double group_delay_samples(double frequency_hz = 0.0) const;

  /// Group delay in seconds: group_delay_samples(frequency_hz)/sample_rate_hz.
  [[nodiscard]] double group_delay_s(double frequency_hz = 0.0) const {
    return group_delay_samples(frequency_hz) / sample_rate_hz;
  }

  /// Phase delay τ_φ = −φ(ω)/(2π·frequency_hz) in seconds: how late a steady pure tone of that
  /// frequency comes out (its zero crossings move by exactly this). At DC, the limit τ_g(0).
  /// @param frequency_hz in [0, sample_rate_hz/2). @throws std::invalid_argument otherwise.
  [[nodiscard]] double phase_delay_s(double frequency_hz) const;
};

/// History of one channel: two delay elements per section (direct form II transposed).
struct ButterworthState {
  std::array<std::array<double, 2>, kMaxButterworthSections> z{};
};

/// A section's transposed direct form II with y's terms folded into the delay elements' updates:
///   y = b0·x + z0,   z0 ← (k1·x + z1) − a1·z0,   z1 ← k2·x − a2·z0,
/// k1 = b1 − a1·b0 and k2 = b2 − a2·b0 (substituting y). The same state and, up to rounding, the
/// same values as z0 ← (b1·x + z1) − a1·y, z1 ← b2·x − a2·y; but the recursion from one z0 to the
/// next is a multiply and a subtraction, where through y it was an addition more — and that
/// recursion's latency is what bounds the monitor's three channels filtered side by side
/// (BM_LowPassThree's AVX kernel: 0.93 → 0.78 ms for a second at 333.3 kHz).
struct SectionRecursion {
  double b0 = 1.0, k1 = 0.0, k2 = 0.0, a1 = 0.0, a2 = 0.0;

  [[nodiscard]] static SectionRecursion of(const Biquad& c) {
    return {c.b0, c.b1 - c.a1 * c.b0, c.b2 - c.a2 * c.b0, c.a1, c.a2};
  }
  /// One sample through the section; z = {z0, z1}.
  double step(double x, double& z0, double& z1) const {
    const double y = b0 * x + z0;
    const double z0_next = (k1 * x + z1) - a1 * z0;
    z1 = k2 * x - a2 * z0;
    z0 = z0_next;
    return y;
  }
};

/// One channel of causal low-pass filtering: a design and that channel's state.
/// Set up once (setup or the constructor; nothing is allocated, ever), then step() or process().
class LowPassFilter {
 public:
  /// A pass-through filter until setup().
  LowPassFilter() = default;
  explicit LowPassFilter(const ButterworthDesign& design) : design_(design) { derive_recursions(); }

  /// Takes `design` and returns to rest.
  void setup(const ButterworthDesign& design) {
    design_ = design;
    derive_recursions();
    reset();
  }
  /// Designs (ButterworthDesign::lowpass, which validates the arguments) and returns to rest.
  void setup(double sample_rate_hz, double cutoff_hz, int order = 4) {
    setup(ButterworthDesign::lowpass(sample_rate_hz, cutoff_hz, order));
  }

  /// Filters one sample (same units out as in). Transposed direct form II, section by section
  /// as SectionRecursion::step (every kernel below does the same operations, to keep their
  /// results step()'s).
  double step(double x) {
    for (int s = 0; s < design_.sections; ++s) {
      const auto us = static_cast<std::size_t>(s);
      auto& z = state_.z[us];
      x = recursion_[us].step(x, z[0], z[1]);
    }
    return x;
  }

  /// Filters `in` into `out`, sample by sample as step() does, so the result does not depend on
  /// the block sizes. `out` may be the same memory as `in`.
  /// @throws std::invalid_argument if the sizes differ (a programming error).
  void process(std::span<const double> in, std::span<double> out);

  /// Which code filters three channels of the monitor's low-pass (order 4: two sections) at once:
  /// the fastest this CPU runs (kAuto: AVX where the CPU has it, else SSE2), or one named (the
  /// tests compare them bit for bit). Every kernel gives what step() gives; another design goes
  /// section by section whatever is asked.
  enum class Kernel { kAuto, kScalar, kSse2, kAvx };

  /// Filters three channels of `count` samples in place, each with its own filter (all three
  /// of the same design), exactly as step() would sample by sample: section by section over the
  /// block with the states in registers, the three channels in step (three independent
  /// recursions in flight instead of one). `kernel`: see Kernel (kAvx on a CPU without AVX: SSE2).
  static void process_three(std::array<LowPassFilter, 3>& filters,
                            const std::array<double*, 3>& data, std::size_t count,
                            Kernel kernel = Kernel::kAuto) {
    process_three(filters, {data[0], data[1], data[2]}, {1.0, 1.0, 1.0}, data, count, kernel);
  }

  /// process_three() from `in` into `out` (the same memory, or apart), channel a's input taken
  /// as sign[a]·in[a][i] — the axis map's ±1 (an exact product), applied as the kernel reads
  /// the sample instead of in a pass of its own: the filter of sign[a]·x, bit for bit.
  static void process_three(std::array<LowPassFilter, 3>& filters,
                            const std::array<const double*, 3>& in,
                            const std::array<double, 3>& sign, const std::array<double*, 3>& out,
                            std::size_t count, Kernel kernel = Kernel::kAuto) {
    const ButterworthDesign& d = filters[0].design_;
    if (d.sections == 0) {  // no design yet: a pass-through, as step() is
      for (std::size_t a = 0; a < 3; ++a) {
        for (std::size_t i = 0; i < count; ++i) {
          out[a][i] = sign[a] * in[a][i];
        }
      }
      return;
    }
    if (d.sections == 2) {  // the monitor's order 4: both sections in one pass (six chains)
      process_three_two_sections(filters, in, sign, out, count, kernel);
      return;
    }
    for (int s = 0; s < d.sections; ++s) {
      const auto us = static_cast<std::size_t>(s);
      const SectionRecursion c = filters[0].recursion_[us];
      auto& za = filters[0].state_.z[us];
      auto& zb = filters[1].state_.z[us];
      auto& zc = filters[2].state_.z[us];
      double a0 = za[0], a1 = za[1], b0 = zb[0], b1 = zb[1], c0 = zc[0], c1 = zc[1];
      // The first section reads the input, with its signs; the others, the last one's output.
      const double* ra = s == 0 ? in[0] : out[0];
      const double* rb = s == 0 ? in[1] : out[1];
      const double* rc = s == 0 ? in[2] : out[2];
      const double ma = s == 0 ? sign[0] : 1.0;
      const double mb = s == 0 ? sign[1] : 1.0;
      const double mc = s == 0 ? sign[2] : 1.0;
      double* xa = out[0];
      double* xb = out[1];
      double* xc = out[2];
      for (std::size_t i = 0; i < count; ++i) {
        const double ya = c.step(ma * ra[i], a0, a1);
        const double yb = c.step(mb * rb[i], b0, b1);
        const double yc = c.step(mc * rc[i], c0, c1);
        xa[i] = ya;
        xb[i] = yb;
        xc[i] = yc;
      }
      za = {a0, a1};
      zb = {b0, b1};
      zc = {c0, c1};
    }
  }

  /// process_three() testing every sample as it reads it: |in[a][i]| ≤ limit[a] (a NaN is not:
  /// the monitor's input check). True: every sample within, the block filtered as
  /// process_three() filters it, bit for bit. False: a sample was not; the filters' states are
  /// as they were (`out` holds anything: filtering in place, the input is lost). Where the CPU has
  /// AVX, for two sections (the monitor's order 4), the test is in the AVX kernel's own pass, off
  /// its recursions' chain (the block's first read from memory, which a pass of its own would wait
  /// on); elsewhere it is a pass before the filter.
  static bool process_three_checked(std::array<LowPassFilter, 3>& filters,
                                    const std::array<const double*, 3>& in,
                                    const std::array<double, 3>& sign,
                                    const std::array<double*, 3>& out, std::size_t count,
                                    const std::array<double, 3>& limit,
                                    Kernel kernel = Kernel::kAuto);

  /// Zero state: the filter starts from rest.
  void reset() { state_ = {}; }

 private:
#if defined(__SSE2__)
  /// process_three_two_sections() with fx and fy side by side in one SSE2 register, fz in
  /// another (its upper lane a copy), every state in a register (the scalar version keeps
  /// states in memory, in the recursions' way; here some of the ten coefficients are read from
  /// memory instead, which waits on nothing). The same operations in the same order on each
  /// lane as step(): the same results, bit for bit.
  static void process_three_lowpass_sse2(std::array<LowPassFilter, 3>& filters,
                                         const std::array<const double*, 3>& in,
                                         const std::array<double, 3>& sign,
                                         const std::array<double*, 3>& out, std::size_t count) {
    // Per section: b0, k1, k2, a1, a2 (SectionRecursion) on both lanes.
    struct Lanes {
      __m128d b0, k1, k2, a1, a2;
    };
    const auto lanes = [](const SectionRecursion& c) {
      return Lanes{_mm_set1_pd(c.b0), _mm_set1_pd(c.k1), _mm_set1_pd(c.k2), _mm_set1_pd(c.a1),
                   _mm_set1_pd(c.a2)};
    };
    const Lanes p = lanes(filters[0].recursion_[0]);
    const Lanes q = lanes(filters[0].recursion_[1]);
    const auto& sa = filters[0].state_.z;
    const auto& sb = filters[1].state_.z;
    const auto& sc = filters[2].state_.z;
    // Lanes (fx, fy) and (fz, fz): section 1's z0, z1 and section 2's z0, z1.
    __m128d u0 = _mm_set_pd(sb[0][0], sa[0][0]), u1 = _mm_set_pd(sb[0][1], sa[0][1]);
    __m128d u2 = _mm_set_pd(sb[1][0], sa[1][0]), u3 = _mm_set_pd(sb[1][1], sa[1][1]);
    __m128d v0 = _mm_set1_pd(sc[0][0]), v1 = _mm_set1_pd(sc[0][1]);
    __m128d v2 = _mm_set1_pd(sc[1][0]), v3 = _mm_set1_pd(sc[1][1]);
    const double* ra = in[0];
    const double* rb = in[1];
    const double* rc = in[2];
    const __m128d m_ab = _mm_set_pd(sign[1], sign[0]), m_c = _mm_set1_pd(sign[2]);
    double* xa = out[0];
    double* xb = out[1];
    double* xc = out[2];
    // One section on a pair of lanes, as SectionRecursion::step.
    const auto section = [](__m128d x, const Lanes& c, __m128d& z0, __m128d& z1) {
      const __m128d y = _mm_add_pd(_mm_mul_pd(c.b0, x), z0);
      const __m128d z0_next = _mm_sub_pd(_mm_add_pd(_mm_mul_pd(c.k1, x), z1), _mm_mul_pd(c.a1, z0));
      z1 = _mm_sub_pd(_mm_mul_pd(c.k2, x), _mm_mul_pd(c.a2, z0));
      z0 = z0_next;
      return y;
    };
    for (std::size_t i = 0; i < count; ++i) {
      const __m128d in_ab = _mm_mul_pd(m_ab, _mm_loadh_pd(_mm_load_sd(ra + i), rb + i));
      const __m128d in_c = _mm_mul_pd(m_c, _mm_load1_pd(rc + i));
      const __m128d out_ab = section(section(in_ab, p, u0, u1), q, u2, u3);
      const __m128d out_c = section(section(in_c, p, v0, v1), q, v2, v3);
      _mm_storel_pd(xa + i, out_ab);
      _mm_storeh_pd(xb + i, out_ab);
      _mm_storel_pd(xc + i, out_c);
    }
    auto& za = filters[0].state_.z;
    auto& zb = filters[1].state_.z;
    auto& zc = filters[2].state_.z;
    za[0] = {_mm_cvtsd_f64(u0), _mm_cvtsd_f64(u1)};
    za[1] = {_mm_cvtsd_f64(u2), _mm_cvtsd_f64(u3)};
    zb[0] = {_mm_cvtsd_f64(_mm_unpackhi_pd(u0, u0)), _mm_cvtsd_f64(_mm_unpackhi_pd(u1, u1))};
    zb[1] = {_mm_cvtsd_f64(_mm_unpackhi_pd(u2, u2)), _mm_cvtsd_f64(_mm_unpackhi_pd(u3, u3))};
    zc[0] = {_mm_cvtsd_f64(v0), _mm_cvtsd_f64(v1)};
    zc[1] = {_mm_cvtsd_f64(v2), _mm_cvtsd_f64(v3)};
  }
#endif

#if defined(__SSE2__)
  /// process_three_lowpass_sse2() with AVX: fx, fy and fz side by side in one 256-bit register
  /// (its fourth lane a copy of fz), the same operations in the same order on each lane (the
  /// signs folded into the first section's coefficients: exact), so the same results bit for
  /// bit, in half the instructions of the two SSE2 registers. The kernel is
  /// compiled for AVX alone (butterworth_lowpass.cpp): call this only where signal::cpu_has_avx().
  static void process_three_lowpass_avx(std::array<LowPassFilter, 3>& filters,
                                        const std::array<const double*, 3>& in,
                                        const std::array<double, 3>& sign,
                                        const std::array<double*, 3>& out, std::size_t count);
#endif

  /// process_three() for two sections, sample by sample with every state in a local: the two
  /// sections' recursions of the three channels overlap (each waits only on its own last step).
  static void process_three_two_sections(std::array<LowPassFilter, 3>& filters,
                                         const std::array<const double*, 3>& in,
                                         const std::array<double, 3>& sign,
                                         const std::array<double*, 3>& out, std::size_t count,
                                         Kernel kernel) {
    const SectionRecursion p = filters[0].recursion_[0];
    const SectionRecursion q = filters[0].recursion_[1];
#if defined(__SSE2__)
    if (kernel != Kernel::kScalar) {
      if (kernel != Kernel::kSse2 && signal::cpu_has_avx()) {
        process_three_lowpass_avx(filters, in, sign, out, count);
      } else {
        process_three_lowpass_sse2(filters, in, sign, out, count);
      }
      return;
    }
#else
    static_cast<void>(kernel);
#endif
    std::array<std::array<double, 4>, 3> z{};  // per channel: section 1's z0, z1, section 2's
    for (std::size_t a = 0; a < 3; ++a) {
      const auto& s = filters[a].state_.z;
      z[a] = {s[0][0], s[0][1], s[1][0], s[1][1]};
    }
    const double* ra = in[0];
    const double* rb = in[1];
    const double* rc = in[2];
    double* xa = out[0];
    double* xb = out[1];
    double* xc = out[2];
    const auto step = [&p, &q](double x, std::array<double, 4>& s) {
      return q.step(p.step(x, s[0], s[1]), s[2], s[3]);
    };
    for (std::size_t i = 0; i < count; ++i) {
      xa[i] = step(sign[0] * ra[i], z[0]);
      xb[i] = step(sign[1] * rb[i], z[1]);
      xc[i] = step(sign[2] * rc[i], z[2]);
    }
    for (std::size_t a = 0; a < 3; ++a) {
      auto& s = filters[a].state_.z;
      s[0] = {z[a][0], z[a][1]};
      s[1] = {z[a][2], z[a][3]};
    }
  }

 public:
  /// The state after a constant input `x` for ever: step(x) then returns x (DC gain 1), so a
  /// stream that starts at a level other than zero (mid-cut) has no start-up transient.
  /// Per section, like scipy.signal.sosfilt_zi(sos)·x.
  void settle(double x);

  [[nodiscard]] const ButterworthDesign& design() const {
    return design_;
  }
  [[nodiscard]] const ButterworthState& state() const {
    return state_;
  }

 private:
  void derive_recursions() {
    for (std::size_t s = 0; s < recursion_.size(); ++s) {
      recursion_[s] = SectionRecursion::of(design_.sos[s]);
    }
  }

  ButterworthDesign design_;
  std::array<SectionRecursion, kMaxButterworthSections> recursion_{};  // design_'s sections
  ButterworthState state_;
};

/// Samples for the slowest pole (radius r) to decay to `fraction` (in (0, 1)) of its start:
/// ⌈ln fraction / ln r⌉; 0 for a design without poles.
[[nodiscard]] std::size_t decay_samples(const ButterworthDesign& design, double fraction);

/// Samples of padding filtfilt() adds at each end of a record of `record_samples` samples: long
/// enough for the slowest pole (radius r) to decay to 10⁻⁶ (⌈ln 10⁻⁶ / ln r⌉, at least scipy's
/// 3·(2·sections + 1)), at most record_samples − 1 (the odd reflection needs that many samples).
[[nodiscard]] std::size_t filtfilt_pad_samples(const ButterworthDesign& design,
                                               std::size_t record_samples);

/// Zero-phase filtering of a whole record (offline work only): the record is extended at each end
/// by filtfilt_pad_samples() samples of odd reflection (2·x[0] − x[p..1] before,
/// 2·x[n−1] − x[n−2..n−1−p] after), filtered forwards from the steady state of its first value,
/// reversed, filtered again from the steady state of its (new) first value and reversed back —
/// scipy.signal.sosfiltfilt(sos, x, padtype="odd", padlen=filtfilt_pad_samples(...)).
/// The result has zero phase and magnitude |H(e^{jω})|²: a symmetric pulse stays symmetric about
/// the same centre, a constant stays exactly constant up to the ends.
/// Allocates a work buffer of n + 2·pad samples. `out` may be the same memory as `in`.
/// @throws std::invalid_argument if the sizes differ.
void filtfilt(const ButterworthDesign& design, std::span<const double> in, std::span<double> out);

}  // namespace millwatch::signal
