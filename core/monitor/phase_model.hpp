#pragma once
// The spindle angle as a function of sample index, as the tracker locks it:
//   angle(n) = reference_angle_rad + 2π·spindle_hz·(n − reference_sample)/sample_rate_hz
// (unwrapped). The angle's zero is the tracker's (no encoder), arbitrary but steady while locked.

#include <cmath>
#include <numbers>

namespace millwatch::monitor {

struct PhaseModel {
  double reference_sample = 0.0;
  double reference_angle_rad = 0.0;
  double spindle_hz = 0.0;
  double sample_rate_hz = 1.0;
  bool valid = false;

  [[nodiscard]] double angle_at(double sample) const {
    return reference_angle_rad +
           2.0 * std::numbers::pi * spindle_hz * (sample - reference_sample) / sample_rate_hz;
  }
  [[nodiscard]] double sample_at(double angle_rad) const {
    return reference_sample + (angle_rad - reference_angle_rad) * sample_rate_hz /
                                  (2.0 * std::numbers::pi * spindle_hz);
  }
  [[nodiscard]] double samples_per_revolution() const { return sample_rate_hz / spindle_hz; }
};

}  // namespace millwatch::monitor
