#include "core/signal/butterworth_lowpass.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

namespace millwatch::signal {
namespace {

constexpr double kPi = std::numbers::pi;

/// Σ c_k·e^{−jωk} and Σ k·c_k·e^{−jωk} for a polynomial in z⁻¹ of degree 2.
struct PolyAt {
  std::complex<double> value;
  std::complex<double> weighted;
};

PolyAt eval(double c0, double c1, double c2, double omega) {
  const std::complex<double> e1 = std::polar(1.0, -omega);
  const std::complex<double> e2 = e1 * e1;
  return {c0 + c1 * e1 + c2 * e2, c1 * e1 + 2.0 * c2 * e2};
}

}  // namespace

ButterworthDesign ButterworthDesign::lowpass(double sample_rate_hz, double cutoff_hz, int order) {
  if (!(sample_rate_hz > 0.0) || !std::isfinite(sample_rate_hz)) {
    throw std::invalid_argument("low-pass: sample_rate_hz " + std::to_string(sample_rate_hz) +
                                " must be a finite number > 0");
  }
  if (!(cutoff_hz > 0.0) || !(cutoff_hz < 0.45 * sample_rate_hz)) {
    throw std::invalid_argument("low-pass: cutoff_hz " + std::to_string(cutoff_hz) +
                                " must be in (0, " + std::to_string(0.45 * sample_rate_hz) +
                                ") Hz at sample rate " + std::to_string(sample_rate_hz) + " Hz");
  }
  if (order < 1 || order > kMaxButterworthOrder) {
    throw std::invalid_argument("low-pass: order " + std::to_string(order) + " must be in [1, " +
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
    // Conjugate pair p_k, p_k*: q = −2·Re(p_k) = 2·sin(π(2k + 1)/(2n)).
    const double q = 2.0 * std::sin(kPi * (2 * k + 1) / (2.0 * order));
    const double a0 = 1.0 + q * w + w2;
    d.sos[static_cast<std::size_t>(k)] = {w2 / a0, 2.0 * w2 / a0, w2 / a0, 2.0 * (w2 - 1.0) / a0,
                                          (1.0 - q * w + w2) / a0};
  }
  if (order % 2 == 1) {  // the real pole p = −1: H = w(1 + z⁻¹)/((1 + w) + (w − 1)z⁻¹)
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

double ButterworthDesign::group_delay_samples(double frequency_hz) const {
  // For P(e^{jω}) = Σ c_k e^{−jωk}: −d arg P/dω = Re(Σ k c_k e^{−jωk} / P).
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
  // Unwrap the phase from DC along a fine grid so that −φ/ω is the true lag of the tone.
  const int steps = 256;
  double phase = 0.0;
  std::complex<double> previous = response(0.0);
  for (int i = 1; i <= steps; ++i) {
    const std::complex<double> h = response(frequency_hz * i / steps);
    phase += std::arg(h / previous);
    previous = h;
  }
  return -phase / (2.0 * kPi * frequency_hz);
}

void LowPassFilter::process(std::span<const double> in, std::span<double> out) {
  const std::size_t n = std::min(in.size(), out.size());
  for (std::size_t i = 0; i < n; ++i) {
    out[i] = step(in[i]);
  }
}

void LowPassFilter::settle(double x) {
  for (int s = 0; s < design_.sections; ++s) {
    const Biquad& c = design_.sos[static_cast<std::size_t>(s)];
    auto& z = state_.z[static_cast<std::size_t>(s)];
    const double gain = (c.b0 + c.b1 + c.b2) / (1.0 + c.a1 + c.a2);
    const double y = gain * x;
    z[1] = c.b2 * x - c.a2 * y;
    z[0] = c.b1 * x - c.a1 * y + z[1];
    x = y;
  }
}

void filtfilt(const ButterworthDesign& design, std::span<const double> in, std::span<double> out) {
  const std::size_t n = std::min(in.size(), out.size());
  if (n == 0) {
    return;
  }
  // Padding: several time constants of the filter, at most the record itself.
  const auto settle_samples =
      static_cast<std::size_t>(std::ceil(3.0 * design.sample_rate_hz / design.cutoff_hz));
  const std::size_t pad =
      std::min(n - 1, std::max<std::size_t>(3 * (2 * design.sections + 1), settle_samples));
  std::vector<double> work(n + 2 * pad);
  // Odd reflection about the end values: 2·x[0] − x[pad..1], then x, then 2·x[n−1] − ...
  for (std::size_t i = 0; i < pad; ++i) {
    work[i] = 2.0 * in[0] - in[pad - i];
    work[pad + n + i] = 2.0 * in[n - 1] - in[n - 2 - i];
  }
  std::copy(in.begin(), in.begin() + static_cast<std::ptrdiff_t>(n),
            work.begin() + static_cast<std::ptrdiff_t>(pad));
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

}  // namespace millwatch::signal
