#include "core/model/dynamometer.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace millwatch::model {

Resonance::Resonance(double natural_hz, double damping_ratio, double sample_rate_hz)
    : sample_rate_hz_(sample_rate_hz) {
  if (!(sample_rate_hz > 0.0) || !std::isfinite(sample_rate_hz)) {
    throw std::invalid_argument("dynamometer: sample_rate_hz must be > 0, got " +
                                std::to_string(sample_rate_hz));
  }
  if (!(natural_hz > 0.0) || natural_hz >= 0.45 * sample_rate_hz) {
    throw std::invalid_argument("dynamometer: natural_hz " + std::to_string(natural_hz) +
                                " must be in (0, " + std::to_string(0.45 * sample_rate_hz) +
                                ") Hz at sample rate " + std::to_string(sample_rate_hz) + " Hz");
  }
  if (!(damping_ratio > 0.0) || damping_ratio > 5.0) {
    throw std::invalid_argument("dynamometer: damping_ratio " + std::to_string(damping_ratio) +
                                " must be in (0, 5]");
  }
  const double wn = 2.0 * std::numbers::pi * natural_hz;
  const double k = wn / std::tan(wn / (2.0 * sample_rate_hz));  // pre-warped bilinear
  const double k2 = k * k;
  const double w2 = wn * wn;
  const double a0 = k2 + 2.0 * damping_ratio * wn * k + w2;
  b0_ = w2 / a0;
  b1_ = 2.0 * w2 / a0;
  b2_ = w2 / a0;
  a1_ = 2.0 * (w2 - k2) / a0;
  a2_ = (k2 - 2.0 * damping_ratio * wn * k + w2) / a0;
  decay_time_s_ = 1.0 / (damping_ratio * wn);
}

void Resonance::settle(double x) {
  // Steady state of DF-II-T with y = x (unit DC gain).
  const double y = x;
  s2_ = b2_ * x - a2_ * y;
  s1_ = b1_ * x - a1_ * y + s2_;
}

std::complex<double> Resonance::response(double frequency_hz) const {
  const std::complex<double> z1 =
      std::polar(1.0, -2.0 * std::numbers::pi * frequency_hz / sample_rate_hz_);
  return (b0_ + b1_ * z1 + b2_ * z1 * z1) / (1.0 + a1_ * z1 + a2_ * z1 * z1);
}

std::complex<double> resonance_response(double natural_hz, double damping_ratio,
                                        double frequency_hz) {
  const double u = frequency_hz / natural_hz;
  const double re = 1.0 - u * u;
  const double im = 2.0 * damping_ratio * u;
  const double d = re * re + im * im;
  return {re / d, -im / d};
}

}  // namespace millwatch::model
