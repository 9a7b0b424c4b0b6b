#include "core/signal/butterworth_lowpass.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/signal/sample_limit.hpp"

#if defined(__SSE2__)
#include <immintrin.h>
#endif

namespace millwatch::signal {
namespace {

constexpr double kPi = std::numbers::pi;

std::string number(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

[[noreturn]] void reject(const std::string& what) {
  throw std::invalid_argument("Butterworth low-pass: " + what);
}

/// P(e^{jω}) = c0 + c1·e^{−jω} + c2·e^{−2jω} and Σ k·c_k·e^{−jωk}.
struct PolyAt {
  std::complex<double> value;
  std::complex<double> weighted;
};

PolyAt eval(double c0, double c1, double c2, double omega) {
  const std::complex<double> e1 = std::polar(1.0, -omega);
  const std::complex<double> e2 = e1 * e1;
  return {c0 + c1 * e1 + c2 * e2, c1 * e1 + 2.0 * c2 * e2};
}

/// Largest pole radius of 1 + a1·z⁻¹ + a2·z⁻², i.e. of z² + a1·z + a2.
double pole_radius(const Biquad& c) {
  const double disc = c.a1 * c.a1 - 4.0 * c.a2;
  if (disc < 0.0) {
    return std::sqrt(c.a2);  // complex pair: |p|² = a2
  }
  const double root = std::sqrt(disc);
  return std::max(std::fabs(-c.a1 + root), std::fabs(-c.a1 - root)) / 2.0;
}

}  // namespace

ButterworthDesign ButterworthDesign::lowpass(double sample_rate_hz, double cutoff_hz, int order) {
  if (!std::isfinite(sample_rate_hz) || !(sample_rate_hz > 0.0)) {
    reject("sample_rate_hz = " + number(sample_rate_hz) + " must be finite and > 0 Hz");
  }
  const double max_cutoff_hz = 0.45 * sample_rate_hz;
  if (!std::isfinite(cutoff_hz) || !(cutoff_hz > 0.0) || !(cutoff_hz < max_cutoff_hz)) {
    reject("cutoff_hz = " + number(cutoff_hz) + " is out of range (0, " + number(max_cutoff_hz) +
           ") Hz (0.45·sample_rate_hz at sample_rate_hz = " + number(sample_rate_hz) + " Hz)");
  }
  if (order < 1 || order > kMaxButterworthOrder) {
    reject("order = " + std::to_string(order) + " is out of range [1, " +
           std::to_string(kMaxButterworthOrder) + "]");
  }
  ButterworthDesign d;
  d.sample_rate_hz = sample_rate_hz;
  d.cutoff_hz = cutoff_hz;
  d.order = order;
  d.sections = (order + 1) / 2;
  const double w = std::tan(kPi * cutoff_hz / sample_rate_hz);
  const double w2 = w * w;
  for (int k = 0; k < order / 2; ++k) {
    const double q = 2.0 * std::sin(kPi * (2 * k + 1) / (2.0 * order));
    const double a0 = 1.0 + q * w + w2;
    d.sos[static_cast<std::size_t>(k)] = {w2 / a0, 2.0 * w2 / a0, w2 / a0, 2.0 * (w2 - 1.0) / a0,
                                          (1.0 - q * w + w2) / a0};
  }
  if (order % 2 == 1) {
    d.sos[static_cast<std::size_t>(order / 2)] = {w / (1.0 + w), w / (1.0 + w), 0.0,
                                                  (w - 1.0) / (w + 1.0), 0.0};
  }
  return d;
}

std::complex<double> ButterworthDesign::response(double frequency_hz) const {
  const double omega = 2.0 * kPi * frequency_hz / sample_rate_hz;
  std::complex<double> h = 1.0;
  for (int s = 0; s < sections; ++s) {
    const Biquad& c = sos[static_cast<std::size_t>(s)];
    h *= eval(c.b0, c.b1, c.b2, omega).value / eval(1.0, c.a1, c.a2, omega).value;
  }
  return h;
}

namespace {

void check_frequency(const ButterworthDesign& d, double frequency_hz) {
  if (!(frequency_hz >= 0.0) || !(frequency_hz < 0.5 * d.sample_rate_hz)) {
    reject("frequency_hz = " + number(frequency_hz) + " is out of range [0, " +
           number(0.5 * d.sample_rate_hz) + ") Hz (below the Nyquist frequency)");
  }
}

}  // namespace

double ButterworthDesign::phase_rad(double frequency_hz) const {
  check_frequency(*this, frequency_hz);
  const double omega = 2.0 * kPi * frequency_hz / sample_rate_hz;
  double phase = 0.0;
  for (int s = 0; s < sections; ++s) {
    const Biquad& c = sos[static_cast<std::size_t>(s)];
    phase += std::arg(eval(c.b0, c.b1, c.b2, omega).value) -
             std::arg(eval(1.0, c.a1, c.a2, omega).value);
  }
  return phase;
}

double ButterworthDesign::group_delay_samples(double frequency_hz) const {
  check_frequency(*this, frequency_hz);
  const double omega = 2.0 * kPi * frequency_hz / sample_rate_hz;
  double delay = 0.0;
  for (int s = 0; s < sections; ++s) {
    const Biquad& c = sos[static_cast<std::size_t>(s)];
    const PolyAt b = eval(c.b0, c.b1, c.b2, omega);
    const PolyAt a = eval(1.0, c.a1, c.a2, omega);
    delay += std::real(b.weighted / b.value) - std::real(a.weighted / a.value);
  }
  return delay;
}

double ButterworthDesign::phase_delay_s(double frequency_hz) const {
  if (frequency_hz == 0.0) {
    return group_delay_s(0.0);
  }
  return -phase_rad(frequency_hz) / (2.0 * kPi * frequency_hz);
}

void LowPassFilter::process(std::span<const double> in, std::span<double> out) {
  if (in.size() != out.size()) {
    reject("process: out has " + std::to_string(out.size()) + " samples, in has " +
           std::to_string(in.size()));
  }
  for (std::size_t i = 0; i < in.size(); ++i) {
    out[i] = step(in[i]);
  }
}

void LowPassFilter::settle(double x) {
  // Per section, the steady state of a constant input x: output y = g·x with the section's DC
  // gain g, and the delay elements that reproduce it.
  for (int s = 0; s < design_.sections; ++s) {
    const Biquad& c = design_.sos[static_cast<std::size_t>(s)];
    auto& z = state_.z[static_cast<std::size_t>(s)];
    const double gain = (c.b0 + c.b1 + c.b2) / (1.0 + c.a1 + c.a2);
    const double y = gain * x;
    z[1] = c.b2 * x - c.a2 * y;
    z[0] = (c.b1 * x + z[1]) - c.a1 * y;
    x = y;
  }
}

std::size_t decay_samples(const ButterworthDesign& design, double fraction) {
  double radius = 0.0;
  for (int s = 0; s < design.sections; ++s) {
    radius = std::max(radius, pole_radius(design.sos[static_cast<std::size_t>(s)]));
  }
  if (!(radius > 0.0 && radius < 1.0)) {
    return 0;
  }
  return static_cast<std::size_t>(std::ceil(std::log(fraction) / std::log(radius)));
}

std::size_t filtfilt_pad_samples(const ButterworthDesign& design, std::size_t record_samples) {
  if (record_samples == 0) {
    return 0;
  }
  const auto scipy_default = static_cast<std::size_t>(3 * (2 * design.sections + 1));
  return std::min(record_samples - 1, std::max(scipy_default, decay_samples(design, 1e-6)));
}

void filtfilt(const ButterworthDesign& design, std::span<const double> in, std::span<double> out) {
  if (in.size() != out.size()) {
    reject("filtfilt: out has " + std::to_string(out.size()) + " samples, in has " +
           std::to_string(in.size()));
  }
  const std::size_t n = in.size();
  if (n == 0) {
    return;
  }
  const std::size_t pad = filtfilt_pad_samples(design, n);
  std::vector<double> work(n + 2 * pad);
  for (std::size_t i = 0; i < pad; ++i) {
    work[i] = 2.0 * in[0] - in[pad - i];
    work[pad + n + i] = 2.0 * in[n - 1] - in[n - 2 - i];
  }
  std::copy(in.begin(), in.end(), work.begin() + static_cast<std::ptrdiff_t>(pad));
  LowPassFilter f(design);
  f.settle(work.front());
  f.process(work, work);
  std::reverse(work.begin(), work.end());
  f.reset();
  f.settle(work.front());
  f.process(work, work);
  std::reverse(work.begin(), work.end());
  std::copy(work.begin() + static_cast<std::ptrdiff_t>(pad),
            work.begin() + static_cast<std::ptrdiff_t>(pad + n), out.begin());
}

#if defined(__SSE2__)
namespace {

using SectionStates = std::array<std::array<double, 2>, kMaxButterworthSections>;

/// A section's b0, k1, k2, a1, a2 (SectionRecursion) on four lanes.
struct SectionLanes {
  __m256d b0, k1, k2, a1, a2;
};

__attribute__((target("avx"))) SectionLanes section_lanes(const SectionRecursion& c) {
  return {_mm256_set1_pd(c.b0), _mm256_set1_pd(c.k1), _mm256_set1_pd(c.k2), _mm256_set1_pd(c.a1),
          _mm256_set1_pd(c.a2)};
}

/// One section on four lanes (SectionRecursion::step, operation for operation).
__attribute__((target("avx"), always_inline)) inline __m256d lowpass_section_avx(
    __m256d x, const SectionLanes& c, __m256d& z0, __m256d& z1) {
  const __m256d y = _mm256_add_pd(_mm256_mul_pd(c.b0, x), z0);
  const __m256d z0_next =
      _mm256_sub_pd(_mm256_add_pd(_mm256_mul_pd(c.k1, x), z1), _mm256_mul_pd(c.a1, z0));
  z1 = _mm256_sub_pd(_mm256_mul_pd(c.k2, x), _mm256_mul_pd(c.a2, z0));
  z0 = z0_next;
  return y;
}

/// One delay element of one section of the three channels as lanes (fx, fy, fz, fz).
__attribute__((target("avx"), always_inline)) inline __m256d state_lanes(const SectionStates& a,
                                                                         const SectionStates& b,
                                                                         const SectionStates& c,
                                                                         std::size_t section,
                                                                         std::size_t k) {
  return _mm256_set_pd(c[section][k], c[section][k], b[section][k], a[section][k]);
}

/// Lanes (fx, fy, fz, fz); states sa, sb, sc of fx, fy, fz. No FMA: target "avx" alone, so GCC
/// contracts nothing and every lane rounds as step() does. kCheck: each sample also tested,
/// |x| ≤ its channel's limit (`limit`; a NaN is not), beside the recursions; returns whether
/// every one was (true without kCheck). The states are written either way.
template <bool kCheck>
__attribute__((target("avx"))) bool lowpass_two_sections_avx(
    const SectionRecursion& first, const SectionRecursion& second, SectionStates& sa,
    SectionStates& sb, SectionStates& sc, const std::array<const double*, 3>& in,
    const std::array<double, 3>& sign, const std::array<double*, 3>& out, std::size_t count,
    const std::array<double, 3>& limit = {}) {
  // The signs as the lanes hold the channels. The input is sign·x, as the axis map writes it;
  // the first section multiplies it by b0, k1 and k2 alone, and (c·s)·x is c·(s·x) exactly for
  // s = ±1, so the signs go into those three (a multiply a sample fewer, the same results).
  const __m256d m = _mm256_set_pd(sign[2], sign[2], sign[1], sign[0]);
  SectionLanes p = section_lanes(first);
  p.b0 = _mm256_mul_pd(p.b0, m);
  p.k1 = _mm256_mul_pd(p.k1, m);
  p.k2 = _mm256_mul_pd(p.k2, m);
  const SectionLanes q = section_lanes(second);
  __m256d u0 = state_lanes(sa, sb, sc, 0, 0), u1 = state_lanes(sa, sb, sc, 0, 1);
  __m256d u2 = state_lanes(sa, sb, sc, 1, 0), u3 = state_lanes(sa, sb, sc, 1, 1);
  const double* ra = in[0];
  const double* rb = in[1];
  const double* rc = in[2];
  double* xa = out[0];
  double* xb = out[1];
  double* xc = out[2];
  const __m256d magnitude = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7fffffffffffffff));
  const __m256d bound = _mm256_set_pd(limit[2], limit[2], limit[1], limit[0]);
  __m256d within = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
  for (std::size_t i = 0; i < count; ++i) {
    const __m128d x_ab = _mm_loadh_pd(_mm_load_sd(ra + i), rb + i);
    const __m256d x = _mm256_insertf128_pd(_mm256_castpd128_pd256(x_ab), _mm_load1_pd(rc + i), 1);
    if constexpr (kCheck) {  // |x| ≤ limit, ordered: false for a NaN
      within = _mm256_and_pd(within, _mm256_cmp_pd(_mm256_and_pd(x, magnitude), bound, _CMP_LE_OQ));
    }
    const __m256d y = lowpass_section_avx(lowpass_section_avx(x, p, u0, u1), q, u2, u3);
    const __m128d y_ab = _mm256_castpd256_pd128(y);
    _mm_storel_pd(xa + i, y_ab);
    _mm_storeh_pd(xb + i, y_ab);
    _mm_storel_pd(xc + i, _mm256_extractf128_pd(y, 1));
  }
  alignas(32) std::array<double, 4> v0{}, v1{}, v2{}, v3{};
  _mm256_store_pd(v0.data(), u0);
  _mm256_store_pd(v1.data(), u1);
  _mm256_store_pd(v2.data(), u2);
  _mm256_store_pd(v3.data(), u3);
  sa[0] = {v0[0], v1[0]};
  sa[1] = {v2[0], v3[0]};
  sb[0] = {v0[1], v1[1]};
  sb[1] = {v2[1], v3[1]};
  sc[0] = {v0[2], v1[2]};
  sc[1] = {v2[2], v3[2]};
  return _mm256_movemask_pd(within) == 0xF;
}

}  // namespace

void LowPassFilter::process_three_lowpass_avx(std::array<LowPassFilter, 3>& filters,
                                              const std::array<const double*, 3>& in,
                                              const std::array<double, 3>& sign,
                                              const std::array<double*, 3>& out,
                                              std::size_t count) {
  lowpass_two_sections_avx<false>(filters[0].recursion_[0], filters[0].recursion_[1],
                                  filters[0].state_.z, filters[1].state_.z, filters[2].state_.z, in,
                                  sign, out, count);
}
#endif

bool LowPassFilter::process_three_checked(std::array<LowPassFilter, 3>& filters,
                                          const std::array<const double*, 3>& in,
                                          const std::array<double, 3>& sign,
                                          const std::array<double*, 3>& out, std::size_t count,
                                          const std::array<double, 3>& limit, Kernel kernel) {
#if defined(__SSE2__)
  if (filters[0].design_.sections == 2 && kernel != Kernel::kScalar && kernel != Kernel::kSse2 &&
      cpu_has_avx()) {
    const std::array<ButterworthState, 3> before = {filters[0].state_, filters[1].state_,
                                                    filters[2].state_};
    if (lowpass_two_sections_avx<true>(filters[0].recursion_[0], filters[0].recursion_[1],
                                       filters[0].state_.z, filters[1].state_.z,
                                       filters[2].state_.z, in, sign, out, count, limit)) {
      return true;
    }
    for (std::size_t a = 0; a < 3; ++a) {
      filters[a].state_ = before[a];
    }
    return false;
  }
#endif
  for (std::size_t a = 0; a < 3; ++a) {
    for (std::size_t i = 0; i < count; ++i) {
      if (!within_limit(in[a][i], limit[a])) {
        return false;
      }
    }
  }
  process_three(filters, in, sign, out, count, kernel);
  return true;
}

}  // namespace millwatch::signal
