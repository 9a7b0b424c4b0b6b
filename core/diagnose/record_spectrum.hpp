#pragma once
// Spectral views of a recorded force channel for the diagnosis (core/diagnose/diagnosis.hpp).
//
// The band. Every residual the diagnosis compares is the record's spectrum over [0, band] (the
// band the measurement's low-pass passes, or a part of it): a signal low-passed at f_c over T
// seconds has 2·f_c·T independent real values — the spectrum's bins up to f_c, each a complex
// number —, the effective sample count of the information criterion. The mean (bin 0) is left
// out: the charge amplifiers' offset lives there.
//
// The noise floor. The measurement's white noise, estimated from the data alone: the median of
// the Hann-windowed power spectrum over the band (lines — spindle harmonics, mains, sub-harmonics
// — occupy few bins and leave the median alone; with a Hann window their leakage falls as 1/Δ³),
// over ln 2 (the median of an exponential variable), scaled to an RMS over the band.
//
// Synchronous harmonics. The revolution-synchronous average's harmonics computed directly from
// the samples at their spindle angle φ_n (no angle bins): X_k = (2/n)·Σ x_n·e^{−ikφ_n} over the
// whole revolutions of the record (so that the harmonics are orthogonal: a part revolution would
// leak a thousandth of every line into its neighbours).
//
// Harmonic fit energy. What a trial speed explains of a record: the energy of the least-squares
// projection of every sample onto the mean and the harmonics 1..K at that speed. Summing each
// harmonic's power |X_k|² instead treats the harmonics as orthogonal, which over whole
// revolutions they are only at one trial speed at a time: the sum's slope in the speed still
// carries their overlap's, a first-order pull on its maximum (up to 3.4σ on a 0.4 s record, all
// six seeds above the truth). The projection accounts for the overlap (the Gram matrix of the
// sinusoids, in closed form) on every sample, so its maximum is the least-squares (for white
// noise, maximum-likelihood) speed, and RSS = Σx² − energy exactly.

#include <complex>
#include <cstddef>
#include <span>
#include <vector>

namespace millwatch::diagnose {

/// The largest length ≤ n whose prime factors are 2, 3 and 5 only (a fast FFT).
[[nodiscard]] std::size_t smooth_length(std::size_t n);

/// Bins 0..bins−1 of the DFT of x (X_f = Σ x_n·e^{−2πi·f·n/N}, N = x.size()), optionally with a
/// Hann window.
[[nodiscard]] std::vector<std::complex<double>> spectrum(std::span<const double> x,
                                                         std::size_t bins, bool hann = false);

/// Bins 1..last of the band: last = ⌊band·N/fs⌋, at most N/2 − 1.
[[nodiscard]] std::size_t last_band_bin(std::size_t n, double sample_rate_hz, double band_hz);

/// Mean square over the band of a signal of N samples from its bins 1..last: (2/N²)·Σ|X_f|².
[[nodiscard]] double band_mean_square(std::span<const std::complex<double>> bins, std::size_t n,
                                      std::size_t last);

/// RMS (N) of the record's white noise over the band bins 1..last (see the file comment);
/// bins below `first` (low-frequency drift) are left out of the median.
[[nodiscard]] double noise_floor_rms(std::span<const double> x, std::size_t first,
                                     std::size_t last);

/// Synchronous harmonics X_0..X_K (X_0 the mean) of x at the spindle angle φ_n = 2π·f·n/fs + φ0,
/// over the whole revolutions from sample 0. Returns the samples used (0: less than one
/// revolution).
std::size_t synchronous_harmonics(std::span<const double> x, double sample_rate_hz,
                                  double spindle_hz, int harmonics,
                                  std::vector<std::complex<double>>& out, double phase0_rad = 0.0);

/// Σ over the signals of ‖P·x‖², P the least-squares projection onto the constant and the
/// harmonics 1..K of spindle_hz at the samples' times n/fs (n = 0..N−1, every sample; all the
/// signals of equal length N). K·spindle_hz must stay below fs/2 (the Gram matrix is singular
/// where a harmonic meets its alias). 0 for an empty record.
[[nodiscard]] double harmonic_fit_energy(std::span<const std::vector<double>> signals,
                                         double sample_rate_hz, double spindle_hz, int harmonics);

}  // namespace millwatch::diagnose
