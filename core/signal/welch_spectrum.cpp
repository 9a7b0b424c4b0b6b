#include "core/signal/welch_spectrum.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

#include "core/signal/real_spectrum.hpp"

namespace millwatch::signal {

AmplitudeSpectrum welch_amplitude_spectrum(std::span<const double> x, double rate_hz,
                                           std::size_t max_segment) {
  AmplitudeSpectrum out;
  if (x.size() < 64) {
    return out;
  }
  std::size_t n = 64;
  while (n * 2 <= std::min(x.size(), max_segment)) {
    n *= 2;
  }
  double mean = 0.0;
  std::size_t finite = 0;
  for (const double v : x) {
    if (std::isfinite(v)) {
      mean += v;
      ++finite;
    }
  }
  mean = finite > 0 ? mean / static_cast<double>(finite) : 0.0;
  std::vector<double> window(n);
  double window_sum = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    window[i] = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * static_cast<double>(i) /
                                     static_cast<double>(n));
    window_sum += window[i];
  }
  RealSpectrum spectrum(static_cast<int>(n));
  std::vector<double> segment(n);
  std::vector<double> power(n / 2 + 1, 0.0);
  for (std::size_t start = 0; start + n <= x.size(); start += n / 2) {
    for (std::size_t i = 0; i < n; ++i) {
      const double v = x[start + i];
      segment[i] = (std::isfinite(v) ? v - mean : 0.0) * window[i];
    }
    const auto bins = spectrum.transform(segment);
    for (std::size_t k = 0; k <= n / 2; ++k) {
      power[k] += std::norm(bins[k]);
    }
    ++out.segments;
  }
  out.segment = n;
  out.covered = n + (out.segments - 1) * (n / 2);
  out.frequency_hz.resize(n / 2 + 1);
  out.amplitude.resize(n / 2 + 1);
  for (std::size_t k = 0; k <= n / 2; ++k) {
    out.frequency_hz[k] = static_cast<double>(k) * rate_hz / static_cast<double>(n);
    // Peak amplitude of a sinusoid: 2|X|/Σw (the mean of the segments' powers).
    out.amplitude[k] = 2.0 * std::sqrt(power[k] / static_cast<double>(out.segments)) / window_sum;
  }
  return out;
}

}  // namespace millwatch::signal
