#pragma once
// The amplitude spectrum of a recorded channel by Welch's method: the mean of the power
// spectra of Hann-windowed segments of one power-of-two length, half overlapping, the record's
// mean removed. Amplitudes are peak amplitudes of sinusoids (2|X|/Σw), so a line at a bin's
// frequency reads its own amplitude.
//
// The transforms go through RealSpectrum, which makes its plan under fftw_planner_mutex(): the
// replay draws its plots while the lockstep model's builder thread may still be planning (two
// planners at once had left both threads spinning in FFTW for good).

#include <cstddef>
#include <span>
#include <vector>

namespace millwatch::signal {

struct AmplitudeSpectrum {
  std::vector<double> frequency_hz;  ///< bin k: k·rate/N
  std::vector<double> amplitude;     ///< peak amplitude, in the samples' unit
  std::size_t segment = 0;           ///< N, the segment length (0: none)
  std::size_t segments = 0;          ///< segments averaged
  std::size_t covered = 0;           ///< samples the segments cover, from the first
};

/// Welch's amplitude spectrum of x (non-finite samples taken as the mean) at rate_hz, segments
/// of the largest power of two ≤ min(x.size(), max_segment), at least 64: empty below 64
/// samples.
[[nodiscard]] AmplitudeSpectrum welch_amplitude_spectrum(std::span<const double> x, double rate_hz,
                                                         std::size_t max_segment);

}  // namespace millwatch::signal
