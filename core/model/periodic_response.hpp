#pragma once
// Periodic steady state of a linear time-invariant system, in the frequency domain.
//
// A waveform x[n], n = 0..N−1, sampled uniformly over one period T of a periodic signal, is the
// sum of its harmonics k = 0..N/2 at frequency k·f₀ (f₀ = 1/T):
//   x[n] = (1/N)·Σ_k X[k]·e^{+2πi·k·n/N},   X[k] = Σ_n x[n]·e^{−2πi·k·n/N}.
// A linear system with frequency response H(f) (convention: input e^{+iωt} → H(f)·e^{+iωt}),
// driven by that signal for ever, outputs the same sum with each X[k] multiplied by H(k·f₀):
//   y[n] = (1/N)·Σ_k H(k·f₀)·X[k]·e^{+2πi·k·n/N}.
// That is the state a causal filter reaches after its start-up transient has died away, with no
// warm-up and no truncation error (for a discrete filter whose sample rate is N·f₀ it is exact;
// otherwise exact for the band-limited interpolant of the samples).
//
// Uses: the dynamometer resonance on the model's revolution (model/steady_state.hpp, H(k·f) of
// dynamometer.hpp), and the monitor's low-pass on the modelled revolution (a causal Butterworth:
// H = signal::ButterworthDesign::response(f); forwards + backwards: |H|²; |H| alone for a
// magnitude-only comparison) — harmonic_gains() turns any such response into the gains.
//
// For a real waveform only the harmonics k = 0..N/2 are independent (k and N − k are conjugate).
// At an even N the Nyquist harmonic k = N/2 is a real cosine (−1)ⁿ: a gain g acts on it as Re(g)
// (the sampled output of cos(πn + arg g)·|g| is Re(g)·(−1)ⁿ).
//
// Set up once per period length (allocates FFTW buffers and plans: complex DFTs, FFTW_ESTIMATE,
// ~0.6 ms for 720 points; plans are made and destroyed under signal::fftw_planner_mutex(), so any
// thread may do it); apply() then allocates nothing, takes no lock and may run in a real-time
// thread.
// One object per thread (the buffers are the object's own).

#include <complex>
#include <cstddef>
#include <span>

struct fftw_plan_s;

namespace millwatch::model {

/// How a complex frequency response H(f) is applied to the harmonics.
enum class ResponseUse {
  kComplex,    ///< H: the causal filter's steady state (gain and lag)
  kMagnitude,  ///< |H|: gain only, no lag
  kPower,      ///< |H|²: the filter run forwards and backwards (zero phase, filtfilt)
};

/// The gain of harmonic k = 0..gains.size()−1 (at frequency k·fundamental_hz):
///   gains[k] = H(k·f₀), |H(k·f₀)| or |H(k·f₀)|² by `use`.
/// @param response callable double frequency_hz → std::complex<double> (e.g. a lambda around
///        ButterworthDesign::response or dynamometer_response)
/// @param fundamental_hz f₀ > 0, the frequency of the waveform's period (spindle frequency for
///        one revolution, spindle frequency / L for a cycle of L revolutions)
template <class Response>
void harmonic_gains(Response&& response, double fundamental_hz, ResponseUse use,
                    std::span<std::complex<double>> gains) {
  for (std::size_t k = 0; k < gains.size(); ++k) {
    const std::complex<double> h = response(static_cast<double>(k) * fundamental_hz);
    switch (use) {
      case ResponseUse::kMagnitude:
        gains[k] = std::abs(h);
        break;
      case ResponseUse::kPower:
        gains[k] = std::norm(h);
        break;
      case ResponseUse::kComplex:
        gains[k] = h;
        break;
    }
  }
}

/// Applies harmonic gains to one period of a real waveform (see the file comment).
class PeriodicResponse {
 public:
  /// An empty object; apply() is then an error until set up.
  PeriodicResponse() = default;
  /// @param samples_per_period N ≥ 2
  /// @throws std::invalid_argument for N < 2
  explicit PeriodicResponse(int samples_per_period);
  ~PeriodicResponse();
  PeriodicResponse(PeriodicResponse&& other) noexcept;
  PeriodicResponse& operator=(PeriodicResponse&& other) noexcept;
  PeriodicResponse(const PeriodicResponse&) = delete;
  PeriodicResponse& operator=(const PeriodicResponse&) = delete;

  /// N, the period length this object was set up for (0 when empty).
  [[nodiscard]] int samples() const { return samples_; }
  /// N/2 + 1: how many gains apply() takes.
  [[nodiscard]] int harmonics() const { return samples_ / 2 + 1; }

  /// Replaces `waveform` (N samples, any unit) by its steady-state response: harmonic k times
  /// gains[k]. Allocates nothing.
  /// @throws std::invalid_argument if waveform.size() ≠ N or gains.size() ≠ N/2 + 1
  void apply(std::span<double> waveform, std::span<const std::complex<double>> gains);

  /// The same with the gains computed from a response (harmonic_gains) into this object's own
  /// buffer; allocates nothing.
  template <class Response>
  void apply(std::span<double> waveform, double fundamental_hz, Response&& response,
             ResponseUse use = ResponseUse::kComplex) {
    harmonic_gains(std::forward<Response>(response), fundamental_hz, use, gain_buffer());
    apply(waveform, std::span<const std::complex<double>>(gain_buffer()));
  }

 private:
  std::span<std::complex<double>> gain_buffer();
  void release();

  int samples_ = 0;
  std::complex<double>* time_ = nullptr;      // fftw_malloc'ed, N (fftw_complex layout)
  std::complex<double>* spectrum_ = nullptr;  // fftw_malloc'ed, N
  std::complex<double>* gains_ = nullptr;     // N/2 + 1
  fftw_plan_s* forward_ = nullptr;
  fftw_plan_s* backward_ = nullptr;
};

}  // namespace millwatch::model
