#include "core/signal/grid_lowpass.hpp"

#include <Eigen/Core>
#include <Eigen/LU>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

#include "core/signal/cpu_features.hpp"
#include "core/signal/sample_limit.hpp"

namespace millwatch::signal {
namespace {

using LookAhead = GridLowPass::LookAhead;
using State = GridLowPass::State;
using Wide = long double;  // the look-ahead's powers are formed in extended precision
using WideMatrix = Eigen::Matrix<Wide, 4, 4>;
using WideVector = Eigen::Matrix<Wide, 4, 1>;

/// One step of the cascade (transposed direct form II, the state LowPassFilter::step keeps), in
/// extended precision; a design with one section gets a pass-through second section, whose delay
/// elements stay zero.
Wide cascade_step(const ButterworthDesign& d, WideVector& z, Wide x) {
  for (int s = 0; s < 2; ++s) {
    const Biquad c = s < d.sections ? d.sos[static_cast<std::size_t>(s)] : Biquad{};
    Wide& z0 = z(2 * s);
    Wide& z1 = z(2 * s + 1);
    const Wide y = c.b0 * x + z0;
    z0 = (c.b1 * x + z1) - c.a1 * y;
    z1 = c.b2 * x - c.a2 * y;
    x = y;
  }
  return x;
}

/// The K of the sections' modal basis (GridLowPass::State): A = [A₁ 0; M A₂] (section 2 driven
/// by section 1), and w = z₂ + K·z₁ evolves by A₂ alone when A₂·K − K·A₁ = M, a Sylvester
/// equation, solved as the 4×4 system (I ⊗ A₂ − A₁ᵀ ⊗ I)·vec(K) = vec(M). It has one solution
/// when the sections share no pole (a Butterworth design's sections never do); K = 0 when
/// section 2 does not follow section 1 (M = 0: a design of one section).
Eigen::Matrix<Wide, 2, 2> modal_coupling(const WideMatrix& a) {
  const Eigen::Matrix<Wide, 2, 2> a1 = a.topLeftCorner<2, 2>();
  const Eigen::Matrix<Wide, 2, 2> a2 = a.bottomRightCorner<2, 2>();
  const Eigen::Matrix<Wide, 2, 2> m = a.bottomLeftCorner<2, 2>();
  if (m.isZero(0.0L)) {
    return Eigen::Matrix<Wide, 2, 2>::Zero();
  }
  WideMatrix system = WideMatrix::Zero();
  const auto at = [](int i, int j) { return i + 2 * j; };  // vec(): column after column
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 2; ++j) {
      for (int l = 0; l < 2; ++l) {
        system(at(i, j), at(l, j)) += a2(i, l);  // (A₂·K)(i, j)
        system(at(i, j), at(i, l)) -= a1(l, j);  // (K·A₁)(i, j)
      }
    }
  }
  const WideVector vec_m(m(0, 0), m(1, 0), m(0, 1), m(1, 1));
  const Eigen::FullPivLU<WideMatrix> lu(system);
  if (!lu.isInvertible()) {
    throw std::invalid_argument("GridLowPass: the design's two sections share a pole");
  }
  const WideVector k = lu.solve(vec_m);
  Eigen::Matrix<Wide, 2, 2> out;
  out << k(0), k(2), k(1), k(3);
  return out;
}

/// A, B, C, D read off the cascade's step (it is linear: a unit state or a unit input at a
/// time), taken to the modal basis w = T·z (T = [I 0; K I]), then A^k and A^(k−1−j)·B there.
LookAhead look_ahead(const ButterworthDesign& d, int stride) {
  WideMatrix a;
  WideVector c;
  for (int m = 0; m < 4; ++m) {
    WideVector z = WideVector::Unit(m);
    c(m) = cascade_step(d, z, 0.0L);
    a.col(m) = z;
  }
  WideVector b = WideVector::Zero();
  const Wide direct = cascade_step(d, b, 1.0L);
  const Eigen::Matrix<Wide, 2, 2> coupling = modal_coupling(a);
  WideMatrix t = WideMatrix::Identity();
  WideMatrix t_inverse = WideMatrix::Identity();
  t.bottomLeftCorner<2, 2>() = coupling;
  t_inverse.bottomLeftCorner<2, 2>() = -coupling;
  a = t * a * t_inverse;
  b = t * b;
  const Eigen::Matrix<Wide, 1, 4> c_modal = c.transpose() * t_inverse;
  c = c_modal.transpose();
  // The sections apart: A's coupling block is zero up to the extended precision's rounding.
  a.bottomLeftCorner<2, 2>().setZero();
  // y = b0₂·y₁ + z₂[0]: C reads section 2's first delay element with weight 1 and not its second,
  // exactly (the kernels add it without a multiply).
  if (c(2) != 1.0L || c(3) != 0.0L) {
    throw std::logic_error("GridLowPass: the cascade's output is not its last section's z0");
  }
  LookAhead l;
  WideMatrix power = WideMatrix::Identity();
  // Column j of the input gain is A^(k−1−j)·B: the last input's is B, each earlier one A times
  // the next.
  for (int j = stride - 1; j >= 0; --j) {
    const WideVector g = power * b;
    for (int i = 0; i < 4; ++i) {
      l.input[static_cast<std::size_t>(j)][static_cast<std::size_t>(i)] = static_cast<double>(g(i));
    }
    power = a * power;
  }
  for (int i = 0; i < 4; ++i) {
    const auto ui = static_cast<std::size_t>(i);
    for (int m = 0; m < 4; ++m) {
      l.power[ui][static_cast<std::size_t>(m)] = static_cast<double>(power(i, m));
    }
    l.output[ui] = static_cast<double>(c(i));
  }
  l.direct = static_cast<double>(direct);
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 2; ++j) {
      l.coupling[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)] =
          static_cast<double>(coupling(i, j));
    }
  }
  return l;
}

/// y(g) = C·z(g) + D·x(g), with ds = D·sign; C = (c0, c1, 1, 0) (look_ahead() checks the 1 and
/// the 0). kFused: in multiply-adds (GridLowPass::fused()), in the order the vector kernel does
/// them.
template <bool kFused>
inline double grid_output(const LookAhead& l, const State& z, double ds, double x) {
  if constexpr (kFused) {
    return std::fma(l.output[0], z[0], std::fma(l.output[1], z[1], z[2] + ds * x));
  }
  return (l.output[0] * z[0] + l.output[1] * z[1]) + (z[2] + ds * x);
}

/// z ← A^k·z + Σ_j A^(k−1−j)·B·sign·x_j, A^k block diagonal (the modal basis: each section's
/// delay elements advance on their own). `x(j)` is the j-th input of the stride.
template <bool kFused, typename Input>
inline void grid_advance(const LookAhead& l, int stride, double sign, State& z, Input&& x) {
  State u{};
  for (std::size_t i = 0; i < 4; ++i) {
    u[i] = (l.input[0][i] * sign) * x(0);
  }
  for (int j = 1; j < stride; ++j) {
    const auto uj = static_cast<std::size_t>(j);
    for (std::size_t i = 0; i < 4; ++i) {
      u[i] = kFused ? std::fma(l.input[uj][i] * sign, x(j), u[i])
                    : u[i] + (l.input[uj][i] * sign) * x(j);
    }
  }
  const auto& p = l.power;
  const double z0 = z[0], z1 = z[1], z2 = z[2], z3 = z[3];
  if constexpr (kFused) {
    // The state's chain two multiply-adds deep (the plain one: a multiply and two adds).
    z[0] = std::fma(p[0][0], z0, std::fma(p[0][1], z1, u[0]));
    z[1] = std::fma(p[1][0], z0, std::fma(p[1][1], z1, u[1]));
    z[2] = std::fma(p[2][2], z2, std::fma(p[2][3], z3, u[2]));
    z[3] = std::fma(p[3][2], z2, std::fma(p[3][3], z3, u[3]));
    return;
  }
  z[0] = (p[0][0] * z0 + p[0][1] * z1) + u[0];
  z[1] = (p[1][0] * z0 + p[1][1] * z1) + u[1];
  z[2] = (p[2][2] * z2 + p[2][3] * z3) + u[2];
  z[3] = (p[3][2] * z2 + p[3][3] * z3) + u[3];
}

/// A kernel: `strides` whole strides from a grid sample (strides_scalar; strides_avx, strides_fma,
/// strides_avx512). A checking one (kCheck) also tests every input it reads against `limit` (its
/// channel's) and returns whether all were within (|x| ≤ limit; a NaN is not); an unchecking one
/// returns true.
using Strides = bool (*)(const LookAhead&, int, const std::array<double, 3>&, std::array<State, 3>&,
                         const std::array<const double*, 3>&, const std::array<double*, 3>&,
                         std::size_t, const std::array<double, 3>&);

/// Whole strides from a grid sample: the output at each stride's first sample, the state
/// advanced past it; the three channels in step (three independent chains). kStride as
/// strides_avx's; kFused: in multiply-adds (GridLowPass::fused()).
template <bool kCheck, int kStride, bool kFused>
bool strides_scalar(const LookAhead& l, int stride, const std::array<double, 3>& sign,
                    std::array<State, 3>& z, const std::array<const double*, 3>& in,
                    const std::array<double*, 3>& out, std::size_t strides,
                    const std::array<double, 3>& limit) {
  const LookAhead c = l;  // a local copy: the stores to out cannot touch it
  const int k = kStride > 0 ? kStride : stride;
  std::array<State, 3> zs = z;
  const auto step = static_cast<std::size_t>(k);
  bool ok = true;
  for (std::size_t s = 0; s < strides; ++s) {
    const std::size_t at = s * step;
    for (std::size_t a = 0; a < 3; ++a) {
      const double* xs = in[a] + at;
      out[a][at] = grid_output<kFused>(c, zs[a], c.direct * sign[a], xs[0]);
      grid_advance<kFused>(c, k, sign[a], zs[a], [xs](int j) { return xs[j]; });
      if constexpr (kCheck) {
        for (int j = 0; j < k; ++j) {
          ok = ok && within_limit(xs[j], limit[a]);
        }
      }
    }
  }
  z = zs;
  return ok;
}

#if defined(__SSE2__)
/// Sample i of the three channels as lanes (fx, fy, fz, fz).
__attribute__((target("avx"), always_inline)) inline __m256d sample_lanes(
    const std::array<const double*, 3>& in, std::size_t i) {
  const __m128d ab = _mm_loadh_pd(_mm_load_sd(in[0] + i), in[1] + i);
  return _mm256_insertf128_pd(_mm256_castpd128_pd256(ab), _mm_load1_pd(in[2] + i), 1);
}

/// Delay element i of the three channels as lanes.
__attribute__((target("avx"), always_inline)) inline __m256d state_lanes(
    const std::array<State, 3>& z, std::size_t i) {
  return _mm256_set_pd(z[2][i], z[2][i], z[1][i], z[0][i]);
}

/// `beyond` with the lanes of x that are not within their limit set: |x| > limit, or a NaN
/// (unordered).
__attribute__((target("avx"), always_inline)) inline __m256d lanes_beyond(__m256d beyond, __m256d x,
                                                                          __m256d limit) {
  const __m256d magnitude = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7fffffffffffffff));
  return _mm256_or_pd(beyond, _mm256_cmp_pd(_mm256_and_pd(x, magnitude), limit, _CMP_NLE_UQ));
}

/// The vector kernels' constants, as lanes: the input gains times the signs, A^k's two blocks,
/// C's first two (its others are 1 and 0), D times the signs, the limits.
struct LaneConstants {
  __m256d g[kMaxGridStride][4];
  __m256d p00, p01, p10, p11, p22, p23, p32, p33;
  __m256d c0, c1, ds, lim;
};

__attribute__((target("avx"), always_inline)) inline void lane_constants(
    const LookAhead& l, int stride, const std::array<double, 3>& sign,
    const std::array<double, 3>& limit, LaneConstants& k) {
  const __m256d m = _mm256_set_pd(sign[2], sign[2], sign[1], sign[0]);
  for (int j = 0; j < stride; ++j) {
    const auto uj = static_cast<std::size_t>(j);
    for (std::size_t i = 0; i < 4; ++i) {
      k.g[uj][i] = _mm256_mul_pd(_mm256_set1_pd(l.input[uj][i]), m);
    }
  }
  const auto& p = l.power;
  k.p00 = _mm256_set1_pd(p[0][0]), k.p01 = _mm256_set1_pd(p[0][1]);
  k.p10 = _mm256_set1_pd(p[1][0]), k.p11 = _mm256_set1_pd(p[1][1]);
  k.p22 = _mm256_set1_pd(p[2][2]), k.p23 = _mm256_set1_pd(p[2][3]);
  k.p32 = _mm256_set1_pd(p[3][2]), k.p33 = _mm256_set1_pd(p[3][3]);
  k.c0 = _mm256_set1_pd(l.output[0]), k.c1 = _mm256_set1_pd(l.output[1]);
  k.ds = _mm256_mul_pd(_mm256_set1_pd(l.direct), m);
  k.lim = _mm256_set_pd(limit[2], limit[2], limit[1], limit[0]);
}

/// Sample i of the three channels as lanes, with kCheck the lanes not within their limits set
/// in `beyond`.
template <bool kCheck>
__attribute__((target("avx"), always_inline)) inline __m256d read_lanes(
    const std::array<const double*, 3>& in, std::size_t i, const LaneConstants& c,
    __m256d& beyond) {
  const __m256d x = sample_lanes(in, i);
  if constexpr (kCheck) {
    beyond = lanes_beyond(beyond, x, c.lim);
  }
  return x;
}

/// Asks for the three channels' samples 128 on from i (1 KiB, 16 cache lines; past the block's
/// end too: a prefetch never faults). The kernel reads each block first, from memory the source
/// has just written (on another core) or the hardware's prefetcher lost track of while the
/// pipeline's other stages ran: the 333.3 kHz pipeline about +10 % (bench/HISTORY.md, the
/// seventy-ninth stop); the kernel alone (BM_LowPassOnGrid, its input read again and again)
/// no faster.
__attribute__((target("avx"), always_inline)) inline void prefetch_lanes(
    const std::array<const double*, 3>& in, std::size_t i) {
  constexpr std::size_t kAhead = 128;
  for (const double* channel : in) {
    // The address as an integer: a pointer past the array's end may not even be formed.
    const std::uintptr_t at =
        reinterpret_cast<std::uintptr_t>(channel) + (i + kAhead) * sizeof(double);
    _mm_prefetch(reinterpret_cast<const char*>(at), _MM_HINT_T0);
  }
}

/// The three channels' outputs (lanes 0–2 of y) to their arrays at `at`.
__attribute__((target("avx"), always_inline)) inline void store_outputs(
    const std::array<double*, 3>& out, std::size_t at, __m256d y) {
  const __m128d y_ab = _mm256_castpd256_pd128(y);
  _mm_storel_pd(out[0] + at, y_ab);
  _mm_storeh_pd(out[1] + at, y_ab);
  _mm_storel_pd(out[2] + at, _mm256_extractf128_pd(y, 1));
}

/// The delay elements' lanes back to the channels' states.
__attribute__((target("avx"), always_inline)) inline void store_states(__m256d z0, __m256d z1,
                                                                       __m256d z2, __m256d z3,
                                                                       std::array<State, 3>& z) {
  alignas(32) std::array<std::array<double, 4>, 4> v{};
  _mm256_store_pd(v[0].data(), z0);
  _mm256_store_pd(v[1].data(), z1);
  _mm256_store_pd(v[2].data(), z2);
  _mm256_store_pd(v[3].data(), z3);
  for (std::size_t a = 0; a < 3; ++a) {
    z[a] = {v[0][a], v[1][a], v[2][a], v[3][a]};
  }
}

/// strides_scalar<…, false>() with the three channels as lanes (fx, fy, fz, fz) of one AVX
/// register: the same operations in the same order on each lane (no FMA: target "avx" alone),
/// so the same results bit for bit.
/// kStride: the stride, known when compiled (its inputs' loop unrolled), or 0: `stride`.
/// kCheck: every input's |x| is compared with its channel's limit as it is read (two more
/// operations an input beside the recursion, whose latency bounds the kernel): the check of a
/// block read from memory costs no pass of its own.
template <bool kCheck, int kStride>
__attribute__((target("avx"))) bool strides_avx(
    const LookAhead& l, int stride, const std::array<double, 3>& sign, std::array<State, 3>& z,
    const std::array<const double*, 3>& in, const std::array<double*, 3>& out, std::size_t strides,
    const std::array<double, 3>& limit) {
  if constexpr (kStride > 0) {
    stride = kStride;
  }
  LaneConstants c;
  lane_constants(l, stride, sign, limit, c);
  __m256d z0 = state_lanes(z, 0), z1 = state_lanes(z, 1), z2 = state_lanes(z, 2),
          z3 = state_lanes(z, 3);
  __m256d beyond = _mm256_setzero_pd();  // lanes that read a sample not within its limit
  const auto k = static_cast<std::size_t>(stride);
  for (std::size_t s = 0; s < strides; ++s) {
    const std::size_t at = s * k;
    prefetch_lanes(in, at);
    const __m256d x0 = read_lanes<kCheck>(in, at, c, beyond);
    const __m256d y = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(c.c0, z0), _mm256_mul_pd(c.c1, z1)),
                                    _mm256_add_pd(z2, _mm256_mul_pd(c.ds, x0)));
    __m256d u0 = _mm256_mul_pd(c.g[0][0], x0), u1 = _mm256_mul_pd(c.g[0][1], x0);
    __m256d u2 = _mm256_mul_pd(c.g[0][2], x0), u3 = _mm256_mul_pd(c.g[0][3], x0);
    for (std::size_t j = 1; j < k; ++j) {
      const __m256d xj = read_lanes<kCheck>(in, at + j, c, beyond);
      u0 = _mm256_add_pd(u0, _mm256_mul_pd(c.g[j][0], xj));
      u1 = _mm256_add_pd(u1, _mm256_mul_pd(c.g[j][1], xj));
      u2 = _mm256_add_pd(u2, _mm256_mul_pd(c.g[j][2], xj));
      u3 = _mm256_add_pd(u3, _mm256_mul_pd(c.g[j][3], xj));
    }
    const __m256d n0 =
        _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(c.p00, z0), _mm256_mul_pd(c.p01, z1)), u0);
    const __m256d n1 =
        _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(c.p10, z0), _mm256_mul_pd(c.p11, z1)), u1);
    const __m256d n2 =
        _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(c.p22, z2), _mm256_mul_pd(c.p23, z3)), u2);
    const __m256d n3 =
        _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(c.p32, z2), _mm256_mul_pd(c.p33, z3)), u3);
    z0 = n0;
    z1 = n1;
    z2 = n2;
    z3 = n3;
    store_outputs(out, at, y);
  }
  store_states(z0, z1, z2, z3, z);
  return _mm256_movemask_pd(beyond) == 0;
}

/// strides_avx() in multiply-adds, the operations and their order strides_scalar<…, true>'s (so
/// the same results bit for bit): 24 operations a stride of 3 instead of 42. Compiled into
/// strides_fma() and strides_avx512() for the CPUs that have FMA, and AVX-512VL's 32 registers.
template <bool kCheck, int kStride>
__attribute__((target("avx,avx2,fma"), always_inline)) inline bool strides_fused(
    const LookAhead& l, int stride, const std::array<double, 3>& sign, std::array<State, 3>& z,
    const std::array<const double*, 3>& in, const std::array<double*, 3>& out, std::size_t strides,
    const std::array<double, 3>& limit) {
  if constexpr (kStride > 0) {
    stride = kStride;
  }
  LaneConstants c;
  lane_constants(l, stride, sign, limit, c);
  __m256d z0 = state_lanes(z, 0), z1 = state_lanes(z, 1), z2 = state_lanes(z, 2),
          z3 = state_lanes(z, 3);
  __m256d beyond = _mm256_setzero_pd();
  const auto k = static_cast<std::size_t>(stride);
  for (std::size_t s = 0; s < strides; ++s) {
    const std::size_t at = s * k;
    prefetch_lanes(in, at);
    const __m256d x0 = read_lanes<kCheck>(in, at, c, beyond);
    const __m256d y = _mm256_fmadd_pd(
        c.c0, z0, _mm256_fmadd_pd(c.c1, z1, _mm256_add_pd(z2, _mm256_mul_pd(c.ds, x0))));
    __m256d u0 = _mm256_mul_pd(c.g[0][0], x0), u1 = _mm256_mul_pd(c.g[0][1], x0);
    __m256d u2 = _mm256_mul_pd(c.g[0][2], x0), u3 = _mm256_mul_pd(c.g[0][3], x0);
    for (std::size_t j = 1; j < k; ++j) {
      const __m256d xj = read_lanes<kCheck>(in, at + j, c, beyond);
      u0 = _mm256_fmadd_pd(c.g[j][0], xj, u0);
      u1 = _mm256_fmadd_pd(c.g[j][1], xj, u1);
      u2 = _mm256_fmadd_pd(c.g[j][2], xj, u2);
      u3 = _mm256_fmadd_pd(c.g[j][3], xj, u3);
    }
    const __m256d n0 = _mm256_fmadd_pd(c.p00, z0, _mm256_fmadd_pd(c.p01, z1, u0));
    const __m256d n1 = _mm256_fmadd_pd(c.p10, z0, _mm256_fmadd_pd(c.p11, z1, u1));
    const __m256d n2 = _mm256_fmadd_pd(c.p22, z2, _mm256_fmadd_pd(c.p23, z3, u2));
    const __m256d n3 = _mm256_fmadd_pd(c.p32, z2, _mm256_fmadd_pd(c.p33, z3, u3));
    z0 = n0;
    z1 = n1;
    z2 = n2;
    z3 = n3;
    store_outputs(out, at, y);
  }
  store_states(z0, z1, z2, z3, z);
  return _mm256_movemask_pd(beyond) == 0;
}

template <bool kCheck, int kStride>
__attribute__((target("avx,avx2,fma"))) bool strides_fma(
    const LookAhead& l, int stride, const std::array<double, 3>& sign, std::array<State, 3>& z,
    const std::array<const double*, 3>& in, const std::array<double*, 3>& out, std::size_t strides,
    const std::array<double, 3>& limit) {
  return strides_fused<kCheck, kStride>(l, stride, sign, z, in, out, strides, limit);
}

/// The same code with AVX-512VL's 32 vector registers: fewer of its ~30 constants are read from
/// the stack every stride (11 still are). GCC emits AVX-512DQ forms too (vextractf64x2), so
/// cpu_has_avx512vl() asks for DQ as well.
template <bool kCheck, int kStride>
__attribute__((target("avx,avx2,fma,avx512f,avx512vl,avx512dq"))) bool strides_avx512(
    const LookAhead& l, int stride, const std::array<double, 3>& sign, std::array<State, 3>& z,
    const std::array<const double*, 3>& in, const std::array<double*, 3>& out, std::size_t strides,
    const std::array<double, 3>& limit) {
  return strides_fused<kCheck, kStride>(l, stride, sign, z, in, out, strides, limit);
}

#endif

/// The kernels by name, for pick_strides().
template <bool kCheck, bool kFused>
struct Scalar {
  template <int kStride>
  static constexpr Strides kernel = strides_scalar<kCheck, kStride, kFused>;
};
#if defined(__SSE2__)
template <bool kCheck>
struct Avx {
  template <int kStride>
  static constexpr Strides kernel = strides_avx<kCheck, kStride>;
};
template <bool kCheck>
struct Fma {
  template <int kStride>
  static constexpr Strides kernel = strides_fma<kCheck, kStride>;
};
template <bool kCheck>
struct Avx512 {
  template <int kStride>
  static constexpr Strides kernel = strides_avx512<kCheck, kStride>;
};
#endif

/// Strides up to kUnrolledStrides have their inputs' loop unrolled (333.3 kHz measures on a
/// stride of 3 at 25,000 rpm, of 6 at 12,000 rpm; unrolled, a stride of 5 takes 4 % less time
/// with AVX, 28 % less without); a loop over them beyond.
constexpr int kUnrolledStrides = 8;

template <typename Kernels, int... kStride>
Strides pick_strides(int stride, std::integer_sequence<int, kStride...>) {
  constexpr std::array<Strides, sizeof...(kStride)> unrolled = {
      Kernels::template kernel<kStride>...};
  // Entry 0 is the loop too (a stride is at least 1).
  return stride <= kUnrolledStrides ? unrolled[static_cast<std::size_t>(stride)]
                                    : Kernels::template kernel<0>;
}

template <typename Kernels>
Strides pick_strides(int stride) {
  return pick_strides<Kernels>(stride, std::make_integer_sequence<int, kUnrolledStrides + 1>{});
}

/// The fastest kernel this CPU runs in the arithmetic chosen (`fused`: multiply-adds, where
/// the CPU has FMA), or with kScalar the scalar one: the same results.
template <bool kCheck>
Strides pick_kernel(GridLowPass::Kernel kernel, bool fused, int stride) {
#if defined(__SSE2__)
  if (kernel != GridLowPass::Kernel::kScalar && fused) {  // (FMA: AVX too)
    return cpu_has_avx512vl() && kernel != GridLowPass::Kernel::kNoAvx512
               ? pick_strides<Avx512<kCheck>>(stride)
               : pick_strides<Fma<kCheck>>(stride);
  }
  if (kernel != GridLowPass::Kernel::kScalar && cpu_has_avx()) {
    return pick_strides<Avx<kCheck>>(stride);
  }
#else
  static_cast<void>(kernel);
#endif
  return fused ? pick_strides<Scalar<kCheck, true>>(stride)
               : pick_strides<Scalar<kCheck, false>>(stride);
}

}  // namespace

bool GridLowPass::supports(const ButterworthDesign& design, int stride) {
  return design.sections >= 1 && design.sections <= 2 && stride >= 1 && stride <= kMaxGridStride;
}

GridLowPass::GridLowPass(const ButterworthDesign& design, int stride,
                         const std::array<double, 3>& sign, Arithmetic arithmetic)
    : design_(design),
      stride_(stride),
      sign_(sign),
      fused_(arithmetic == Arithmetic::kAuto && cpu_has_fma()) {
  if (!supports(design, stride)) {
    throw std::invalid_argument("GridLowPass: a design of " + std::to_string(design.sections) +
                                " sections on a stride of " + std::to_string(stride) +
                                " is not supported (1–2 sections, stride 1–" +
                                std::to_string(kMaxGridStride) + ")");
  }
  look_ = look_ahead(design, stride);
}

void GridLowPass::settle(std::int64_t n, const std::array<double, 3>& raw) {
  // A constant input leaves the state where it is, so the grid sample at or before n had it
  // too: the stretch starts there, with the inputs from it to n − 1 (that constant) pending.
  const auto behind = static_cast<int>(((n % stride_) + stride_) % stride_);
  pending_count_ = behind;
  for (std::size_t a = 0; a < 3; ++a) {
    pending_[a].fill(raw[a]);
    LowPassFilter f(design_);
    f.settle(sign_[a] * raw[a]);
    const auto& s = f.state().z;
    const double z20 = design_.sections > 1 ? s[1][0] : 0.0;
    const double z21 = design_.sections > 1 ? s[1][1] : 0.0;
    // In the modal basis: section 2's w = z₂ + K·z₁.
    const auto& k = look_.coupling;
    z_[a] = {s[0][0], s[0][1], z20 + (k[0][0] * s[0][0] + k[0][1] * s[0][1]),
             z21 + (k[1][0] * s[0][0] + k[1][1] * s[0][1])};
  }
}

void GridLowPass::advance_pending() {
  for (std::size_t a = 0; a < 3; ++a) {
    const auto& x = pending_[a];
    const auto input = [&x](int j) { return x[static_cast<std::size_t>(j)]; };
    if (fused_) {
      grid_advance<true>(look_, stride_, sign_[a], z_[a], input);
    } else {
      grid_advance<false>(look_, stride_, sign_[a], z_[a], input);
    }
  }
  pending_count_ = 0;
}

void GridLowPass::process(const std::array<const double*, 3>& in, const std::array<double*, 3>& out,
                          std::size_t count, Kernel kernel) {
  run(in, out, count, kernel, nullptr);
}

bool GridLowPass::process_checked(const std::array<const double*, 3>& in,
                                  const std::array<double*, 3>& out, std::size_t count,
                                  const std::array<double, 3>& limit, Kernel kernel) {
  const std::array<State, 3> z = z_;
  const auto pending = pending_;
  const int pending_count = pending_count_;
  if (run(in, out, count, kernel, &limit)) {
    return true;
  }
  z_ = z;
  pending_ = pending;
  pending_count_ = pending_count;
  return false;
}

bool GridLowPass::run(const std::array<const double*, 3>& in, const std::array<double*, 3>& out,
                      std::size_t count, Kernel kernel, const std::array<double, 3>* limit) {
  static constexpr std::array<double, 3> kNoLimit{};
  bool ok = true;
  // Holds sample i of every channel for a later stride (checked first, if asked).
  const auto hold = [&](std::size_t i) {
    const auto p = static_cast<std::size_t>(pending_count_++);
    for (std::size_t a = 0; a < 3; ++a) {
      pending_[a][p] = in[a][i];
      ok = ok && (limit == nullptr || within_limit(in[a][i], (*limit)[a]));
    }
  };
  std::size_t i = 0;
  // A stride a block left unfinished: its output went out with its first sample.
  if (pending_count_ > 0) {
    for (; pending_count_ < stride_ && i < count; ++i) {
      hold(i);
    }
    if (pending_count_ < stride_) {
      return ok;
    }
    advance_pending();
  }
  const auto k = static_cast<std::size_t>(stride_);
  const std::size_t strides = (count - i) / k;
  const std::array<const double*, 3> from = {in[0] + i, in[1] + i, in[2] + i};
  const std::array<double*, 3> to = {out[0] + i, out[1] + i, out[2] + i};
  const bool check = limit != nullptr;
  const Strides kernel_run = check ? pick_kernel<true>(kernel, fused_, stride_)
                                   : pick_kernel<false>(kernel, fused_, stride_);
  ok = kernel_run(look_, stride_, sign_, z_, from, to, strides, check ? *limit : kNoLimit) && ok;
  i += strides * k;
  if (i == count) {
    return ok;
  }
  // The rest starts a stride: its first sample is on the grid.
  for (std::size_t a = 0; a < 3; ++a) {
    out[a][i] = fused_ ? grid_output<true>(look_, z_[a], look_.direct * sign_[a], in[a][i])
                       : grid_output<false>(look_, z_[a], look_.direct * sign_[a], in[a][i]);
  }
  for (; i < count; ++i) {
    hold(i);
  }
  return ok;
}

}  // namespace millwatch::signal
