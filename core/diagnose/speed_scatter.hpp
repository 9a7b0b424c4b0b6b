#pragma once
// The spindle speed's uncertainty from the record's own scatter, for the diagnosis's
// spindle_speed_error (diagnosis.cpp's find_speed()).
//
// The speed the diagnosis finds is the one whose harmonics explain most of the record; its σ
// from the curvature of that fit assumes that what the harmonics leave is the white noise of
// the noise floor. On a real cut it is not: revolutions differ from one another (the material,
// a worn edge, the spindle's own wander), and that difference sits beside the harmonics, where
// the median of the spectrum does not see it. On the PHM 2010 window c1_cut315 (17 revolutions,
// a residual 59× the noise floor) the curvature gave ±0.0084 rpm; halves of the record disagree
// by ten times that.
//
// Here the record is cut into J segments of whole revolutions (J ≤ 16). Each segment's
// synchronous harmonics X_jk at the found speed are compared with those of the rest of the
// record, X̄_k (leave-one-out, so that a segment's noise is not in its own template): a delay d_j
// (samples) shifts harmonic k by −k·θ·d_j (θ the spindle angle per sample), and the least-squares
// delay, linear in the segment's harmonics (no phase to unwrap),
//   d_j = −Σ_k kθ·Im(X_jk·conj X̄_k) / Σ_k (kθ)²·|X̄_k|²,
// summed over the channels. A speed off by a fraction ε delays the segment at sample t by −ε·t:
// the delays' line through the segments' centre times has slope −ε, and its standard error, from
// the scatter of the delays about the line (J − 2 degrees of freedom), is the speed's relative σ
// from the record itself. For white noise it is the curvature's σ (to within the scatter of an
// estimate on J − 2 degrees of freedom); where revolutions differ by more, it is larger.

#include <cstddef>
#include <span>
#include <vector>

namespace millwatch::diagnose {

/// The speed's relative σ (σ_rpm / rpm) from the scatter of the delays of the record's segments
/// at spindle_hz (see the file comment), over the signals (equal lengths) with harmonics 1..K;
/// 0 where the record holds fewer than four whole revolutions or no harmonic power. Also the
/// number of segments used, when asked.
[[nodiscard]] double segment_speed_sigma_rel(std::span<const std::vector<double>> signals,
                                             double sample_rate_hz, double spindle_hz,
                                             int harmonics, int* segments = nullptr);

}  // namespace millwatch::diagnose
