#pragma once
// Dynamometer dynamics: one second-order resonance per axis with unit static gain,
//   H(s) = ω_n² / (s² + 2ζω_n·s + ω_n²),
// discretised by the bilinear transform pre-warped at ω_n (exact resonance frequency), applied
// sample by sample with state carried across calls. [001]/[003] report the clamped 9317C at
// 2145 Hz (x) and 2192 Hz (y): below some tooth-passing harmonics, so the measured force is
// this filter applied to the cutting force.

#include <array>
#include <complex>

namespace millwatch::model {

/// One axis. Coefficients apart from state; no allocation.
class Resonance {
 public:
  Resonance() = default;
  /// @param natural_hz f_n > 0, below 0.45·sample_rate_hz; @param damping_ratio ζ > 0
  /// @throws std::invalid_argument naming the parameter when out of range
  Resonance(double natural_hz, double damping_ratio, double sample_rate_hz);

  /// Filters one sample (direct form II transposed).
  double step(double x) {
    const double y = b0_ * x + s1_;
    s1_ = b1_ * x - a1_ * y + s2_;
    s2_ = b2_ * x - a2_ * y;
    return y;
  }
  /// Takes the coefficients of `other` and keeps this one's state (a change of step time or
  /// tuning without a transient).
  void retune(const Resonance& other) {
    b0_ = other.b0_;
    b1_ = other.b1_;
    b2_ = other.b2_;
    a1_ = other.a1_;
    a2_ = other.a2_;
    sample_rate_hz_ = other.sample_rate_hz_;
    decay_time_s_ = other.decay_time_s_;
  }
  /// Sets the state to the steady response to a constant input.
  void settle(double x);
  void reset() { s1_ = s2_ = 0.0; }
  /// Discrete frequency response at `frequency_hz`.
  [[nodiscard]] std::complex<double> response(double frequency_hz) const;
  /// Time for the envelope of the free response to decay by e: 1/(ζ·ω_n).
  [[nodiscard]] double decay_time_s() const { return decay_time_s_; }

 private:
  double b0_ = 1.0, b1_ = 0.0, b2_ = 0.0, a1_ = 0.0, a2_ = 0.0;
  double s1_ = 0.0, s2_ = 0.0;
  double sample_rate_hz_ = 1.0;
  double decay_time_s_ = 0.0;
};

/// The continuous-time response of one axis at frequency f (Hz), the same H(s) at s = i·2πf:
///   H(f) = 1 / (1 − (f/f_n)² + 2iζ·f/f_n)
/// (unit gain at DC, 1/(2ζ) at f_n with −90° phase). The steady-state evaluator applies it to
/// every harmonic of the revolution (steady_state.hpp), so it does not depend on an angle grid.
/// @param natural_hz f_n > 0, @param damping_ratio ζ > 0, @param frequency_hz f ≥ 0
std::complex<double> resonance_response(double natural_hz, double damping_ratio,
                                        double frequency_hz);

/// Three axes (x, y, z).
struct Dynamometer {
  std::array<Resonance, 3> axis;
};

}  // namespace millwatch::model
