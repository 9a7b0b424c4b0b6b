#pragma once
// The spindle angle as a function of sample index, as the tracker locks it (unwrapped):
//   angle(n) = φ_ref + 2π·(f·τ + ½·ḟ·τ²),  τ = (n − n_ref)/f_s
// with f = spindle_hz at n_ref and ḟ = spindle_hz_per_s (slow ramps). The angle's zero is the
// tracker's own (no encoder): arbitrary, but steady while locked.

#include <cmath>
#include <numbers>

namespace millwatch::signal {

struct PhaseModel {
  double reference_sample = 0.0;
  double reference_angle_rad = 0.0;
  double spindle_hz = 0.0;
  double sample_rate_hz = 1.0;
  bool valid = false;
  double spindle_hz_per_s = 0.0;

  [[nodiscard]] double angle_at(double sample) const {
    const double tau = (sample - reference_sample) / sample_rate_hz;
    return reference_angle_rad +
           2.0 * std::numbers::pi * tau * (spindle_hz + 0.5 * spindle_hz_per_s * tau);
  }
  /// Speed at a sample (Hz).
  [[nodiscard]] double spindle_hz_at(double sample) const {
    return spindle_hz + spindle_hz_per_s * (sample - reference_sample) / sample_rate_hz;
  }
  /// The sample at which the angle reaches `angle_rad` (Newton from the constant-speed guess).
  [[nodiscard]] double sample_at(double angle_rad) const {
    double n = reference_sample + (angle_rad - reference_angle_rad) * sample_rate_hz /
                                      (2.0 * std::numbers::pi * spindle_hz);
    for (int i = 0; i < 3 && spindle_hz_per_s != 0.0; ++i) {
      n -= (angle_at(n) - angle_rad) * sample_rate_hz / (2.0 * std::numbers::pi * spindle_hz_at(n));
    }
    return n;
  }
  [[nodiscard]] double samples_per_revolution() const { return sample_rate_hz / spindle_hz; }
};

}  // namespace millwatch::signal
