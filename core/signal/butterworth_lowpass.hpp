#pragma once
// Digital Butterworth low-pass filter ([000] Sect. 5 filters the forces at 3.3 kHz).
//
// Design: the analog prototype's poles p_k = exp(jπ(2k + n + 1)/(2n)), k = 0..n−1, scaled to
// the pre-warped cut-off Ω_c = 2·f_s·tan(π·f_c/f_s) and mapped by the bilinear transform, one
// second-order section per conjugate pair (a first-order one for odd n). With w = tan(π f_c/f_s)
// and q = −2·Re(p) a section is
//   H(z) = w²(1 + z⁻¹)² / ((1 + q·w + w²) + 2(w² − 1)·z⁻¹ + (1 − q·w + w²)·z⁻²),
// so |H(e^{jω})|² = 1/(1 + (tan(ω/2)/tan(ω_c/2))^{2n}) exactly (−3.01 dB at f_c).
//
// Causal use: a LowPassFilter per channel, set up once, then process() on blocks of any size
// (block-size independent, no allocation). The group delay, exact from the coefficients, lets
// downstream stages put event times back where they happened. Offline: filtfilt() runs the
// filter forwards and backwards (zero phase, magnitude |H|²) with odd reflection padding and
// steady-state initial conditions, like scipy.signal.sosfiltfilt.

#include <array>
#include <complex>
#include <span>

namespace millwatch::signal {

inline constexpr int kMaxButterworthOrder = 8;

/// One section, a0 normalised to 1: y = b0·x + b1·x₋₁ + b2·x₋₂ − a1·y₋₁ − a2·y₋₂.
struct Biquad {
  double b0 = 1.0, b1 = 0.0, b2 = 0.0, a1 = 0.0, a2 = 0.0;
};

struct ButterworthDesign {
  double sample_rate_hz = 0.0;
  double cutoff_hz = 0.0;
  int order = 0;
  int sections = 0;
  std::array<Biquad, (kMaxButterworthOrder + 1) / 2> sos{};

  /// @param sample_rate_hz > 0; @param cutoff_hz in (0, 0.45·sample_rate_hz);
  /// @param order 1..8. @throws std::invalid_argument naming the parameter and its range.
  static ButterworthDesign lowpass(double sample_rate_hz, double cutoff_hz, int order = 4);

  /// Frequency response H(e^{j2πf/f_s}).
  [[nodiscard]] std::complex<double> response(double frequency_hz) const;
  /// Group delay −dφ/dω at `frequency_hz`, in samples (exact, from the coefficients).
  [[nodiscard]] double group_delay_samples(double frequency_hz) const;
  [[nodiscard]] double group_delay_s(double frequency_hz) const {
    return group_delay_samples(frequency_hz) / sample_rate_hz;
  }
  /// Phase delay −φ(ω)/ω at `frequency_hz` (> 0), in seconds: how late a pure tone comes out.
  [[nodiscard]] double phase_delay_s(double frequency_hz) const;
};

/// Filter state of one channel: two delay elements per section (direct form II transposed).
struct ButterworthState {
  std::array<std::array<double, 2>, (kMaxButterworthOrder + 1) / 2> z{};
};

/// One channel of causal low-pass filtering.
class LowPassFilter {
 public:
  LowPassFilter() = default;
  explicit LowPassFilter(const ButterworthDesign& design) : design_(design) {}

  double step(double x) {
    for (int s = 0; s < design_.sections; ++s) {
      const Biquad& c = design_.sos[static_cast<std::size_t>(s)];
      auto& z = state_.z[static_cast<std::size_t>(s)];
      const double y = c.b0 * x + z[0];
      z[0] = c.b1 * x - c.a1 * y + z[1];
      z[1] = c.b2 * x - c.a2 * y;
      x = y;
    }
    return x;
  }
  /// Filters `in` into `out` (same size; may be the same memory).
  void process(std::span<const double> in, std::span<double> out);
  /// Zero state: the filter starts from rest.
  void reset() { state_ = {}; }
  /// The state of a long constant input `x` (no start-up transient when a stream starts mid-cut).
  void settle(double x);
  [[nodiscard]] const ButterworthDesign& design() const { return design_; }

 private:
  ButterworthDesign design_;
  ButterworthState state_;
};

/// Zero-phase filtering of a whole record (offline): forwards, then backwards, with odd
/// reflection padding of the ends and steady-state initial conditions. Allocates a work buffer.
/// `out` may alias `in`.
void filtfilt(const ButterworthDesign& design, std::span<const double> in, std::span<double> out);

}  // namespace millwatch::signal
