#include "core/diagnose/speed_scatter.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

#include "core/diagnose/record_spectrum.hpp"

namespace millwatch::diagnose {
namespace {

/// At most this many segments: 14 degrees of freedom for the scatter (its σ then within about
/// ±19 %), each segment long enough to hold its harmonics apart.
constexpr long kMaxSegments = 16;

/// One segment of whole revolutions: its synchronous harmonics per signal, its centre and the
/// samples it used.
struct Segment {
  std::vector<std::vector<std::complex<double>>> harmonics;  // [signal][k]
  double centre = 0.0;                                       // samples
  double samples = 0.0;
};

}  // namespace

double segment_speed_sigma_rel(std::span<const std::vector<double>> signals, double sample_rate_hz,
                               double spindle_hz, int harmonics, int* segments) {
  if (segments != nullptr) {
    *segments = 0;
  }
  if (signals.empty() || harmonics < 1 || !(spindle_hz > 0.0) || !(sample_rate_hz > 0.0)) {
    return 0.0;
  }
  const std::size_t n = signals[0].size();
  const double per_rev = sample_rate_hz / spindle_hz;  // samples per revolution
  const auto revolutions = static_cast<long>(std::floor(static_cast<double>(n) / per_rev));
  const long count = std::min(kMaxSegments, revolutions);
  if (count < 4 || per_rev < 4.0) {
    return 0.0;
  }
  const double theta = 2.0 * std::numbers::pi / per_rev;  // spindle angle per sample
  // The signals less their means: a segment of whole revolutions holds a non-whole number of
  // samples where a revolution does, and a mean left in would leak into its harmonics a little,
  // at a phase of the segment's own (on the white-noise test's 5 N mean, 0.5 % of the variance
  // of σ: small, but not the record's).
  std::vector<std::vector<double>> centred;
  for (const std::vector<double>& x : signals) {
    double mean = 0.0;
    for (const double v : x) {
      mean += v;
    }
    mean /= static_cast<double>(std::max<std::size_t>(x.size(), 1));
    centred.emplace_back(x.size());
    for (std::size_t i = 0; i < x.size(); ++i) {
      centred.back()[i] = x[i] - mean;
    }
  }
  std::vector<Segment> seg;
  for (long j = 0; j < count; ++j) {
    const long rev_lo = revolutions * j / count;
    const long rev_hi = revolutions * (j + 1) / count;
    const auto start =
        static_cast<std::size_t>(std::llround(static_cast<double>(rev_lo) * per_rev));
    // One sample more than the revolutions' span, so that rounding does not cost a revolution
    // (synchronous_harmonics() takes the whole revolutions the span holds).
    const auto span = std::min(
        n - start,
        static_cast<std::size_t>(std::llround(static_cast<double>(rev_hi - rev_lo) * per_rev)) + 1);
    Segment s;
    std::size_t used = 0;
    for (const std::vector<double>& x : centred) {
      s.harmonics.emplace_back();
      used =
          synchronous_harmonics(std::span(x).subspan(start, span), sample_rate_hz, spindle_hz,
                                harmonics, s.harmonics.back(), theta * static_cast<double>(start));
    }
    if (used == 0) {
      continue;
    }
    s.samples = static_cast<double>(used);
    s.centre = static_cast<double>(start) + 0.5 * s.samples;
    seg.push_back(std::move(s));
  }
  const auto m = static_cast<long>(seg.size());
  if (m < 4) {
    return 0.0;
  }
  // The record's harmonics, each segment's weighted by its samples: the rest's is this less the
  // segment's own.
  const std::size_t channels = signals.size();
  const auto k_count = static_cast<std::size_t>(harmonics) + 1;
  std::vector<std::vector<std::complex<double>>> total(channels,
                                                       std::vector<std::complex<double>>(k_count));
  double all_samples = 0.0;
  for (const Segment& s : seg) {
    all_samples += s.samples;
    for (std::size_t a = 0; a < channels; ++a) {
      for (std::size_t k = 1; k < k_count; ++k) {
        total[a][k] += s.samples * s.harmonics[a][k];
      }
    }
  }
  // Each segment's delay against the rest of the record.
  std::vector<double> delay(seg.size());
  for (std::size_t j = 0; j < seg.size(); ++j) {
    const Segment& s = seg[j];
    const double rest = all_samples - s.samples;
    double num = 0.0, den = 0.0;
    for (std::size_t a = 0; a < channels; ++a) {
      for (std::size_t k = 1; k < k_count; ++k) {
        const std::complex<double> other = (total[a][k] - s.samples * s.harmonics[a][k]) / rest;
        const double w = static_cast<double>(k) * theta;
        num += w * (s.harmonics[a][k] * std::conj(other)).imag();
        den += w * w * std::norm(other);
      }
    }
    if (!(den > 0.0)) {
      return 0.0;
    }
    delay[j] = -num / den;
  }
  // The delays' line in the centre times, each delay weighted by its segment's samples (its
  // variance goes as one over them): the slope's standard error.
  const double mean_samples = all_samples / static_cast<double>(m);
  double sw = 0.0, st = 0.0, sd = 0.0;
  for (std::size_t j = 0; j < seg.size(); ++j) {
    const double w = seg[j].samples / mean_samples;
    sw += w;
    st += w * seg[j].centre;
    sd += w * delay[j];
  }
  const double t_mean = st / sw, d_mean = sd / sw;
  double stt = 0.0, std_ = 0.0;
  for (std::size_t j = 0; j < seg.size(); ++j) {
    const double w = seg[j].samples / mean_samples;
    stt += w * (seg[j].centre - t_mean) * (seg[j].centre - t_mean);
    std_ += w * (seg[j].centre - t_mean) * (delay[j] - d_mean);
  }
  const double slope = std_ / stt;
  double rss = 0.0;
  for (std::size_t j = 0; j < seg.size(); ++j) {
    const double w = seg[j].samples / mean_samples;
    const double r = delay[j] - d_mean - slope * (seg[j].centre - t_mean);
    rss += w * r * r;
  }
  if (segments != nullptr) {
    *segments = static_cast<int>(m);
  }
  // A segment's delay against the rest is (m / (m − 1))·e_j less a term common to all segments,
  // e_j its delay against the truth (the rest's noise is 1/(m − 1) of the others' e_i): the
  // scatter about the line is m / (m − 1) times the segments' own (14 % in variance at m = 16,
  // as 1,000 white-noise records show).
  const auto md = static_cast<double>(m);
  return (md - 1.0) / md * std::sqrt(rss / (md - 2.0) / stt);
}

}  // namespace millwatch::diagnose
