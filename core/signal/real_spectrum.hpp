#pragma once
// The spectrum of a real sequence of a fixed length, by FFTW's real-input transform (r2c):
//   X[k] = Σ_n x[n]·e^{−2πi·k·n/N},  k = 0..N/2
// (the bins above N/2 are the conjugates of those below: X[N − k] = conj X[k]).
//
// The plan is made once per object, under fftw_planner_mutex() (fftw_planner.hpp), so any
// thread may make one. FFTW_ESTIMATE plans the first transform of a length in a process in a few
// milliseconds (~4 ms for 720 points), later ones of that length in tens of microseconds (FFTW
// remembers what it planned). transform() then allocates nothing and takes no lock: ~2 µs for
// 720 points, a third of Eigen's kissfft's time. One object per thread (the buffers are its own).

#include <complex>
#include <span>

struct fftw_plan_s;

namespace millwatch::signal {

class RealSpectrum {
 public:
  RealSpectrum() = default;  ///< no length: transform() must not be called
  /// @param samples N ≥ 1; throws std::invalid_argument below it, std::runtime_error when FFTW
  ///        cannot set it up
  explicit RealSpectrum(int samples);
  ~RealSpectrum();
  RealSpectrum(RealSpectrum&& other) noexcept;
  RealSpectrum& operator=(RealSpectrum&& other) noexcept;
  RealSpectrum(const RealSpectrum&) = delete;
  RealSpectrum& operator=(const RealSpectrum&) = delete;

  [[nodiscard]] int samples() const { return samples_; }

  /// X[0..N/2] of x (x.size() must be N, else std::invalid_argument); valid until the next call.
  std::span<const std::complex<double>> transform(std::span<const double> x);

  /// X[k] for any k ≥ 0 after transform(): the bins above N/2 by conjugate symmetry, k ≥ N
  /// aliased to k mod N (what a full complex DFT of the real x gives). std::invalid_argument for
  /// k < 0 or no length.
  [[nodiscard]] std::complex<double> bin(int k) const;

 private:
  void release();

  int samples_ = 0;
  double* time_ = nullptr;
  std::complex<double>* spectrum_ = nullptr;
  fftw_plan_s* plan_ = nullptr;
};

}  // namespace millwatch::signal
