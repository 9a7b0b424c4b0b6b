#include "core/diagnose/record_spectrum.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <unsupported/Eigen/FFT>

namespace millwatch::diagnose {

std::size_t smooth_length(std::size_t n) {
  for (std::size_t m = n; m > 1; --m) {
    std::size_t r = m;
    for (const std::size_t p : {2U, 3U, 5U}) {
      while (r % p == 0) {
        r /= p;
      }
    }
    if (r == 1) {
      return m;
    }
  }
  return n;
}

std::vector<std::complex<double>> spectrum(std::span<const double> x, std::size_t bins, bool hann) {
  std::vector<double> in(x.begin(), x.end());
  const auto n = in.size();
  if (hann && n > 1) {
    for (std::size_t i = 0; i < n; ++i) {
      in[i] *= 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * static_cast<double>(i) /
                                    static_cast<double>(n));
    }
  }
  std::vector<std::complex<double>> out;
  Eigen::FFT<double> fft;
  fft.fwd(out, in);
  out.resize(std::min(bins, out.size()));
  return out;
}

std::size_t last_band_bin(std::size_t n, double sample_rate_hz, double band_hz) {
  const auto last =
      static_cast<std::size_t>(std::floor(band_hz * static_cast<double>(n) / sample_rate_hz));
  return std::min(last, n / 2 > 1 ? n / 2 - 1 : 0);
}

double band_mean_square(std::span<const std::complex<double>> bins, std::size_t n,
                        std::size_t last) {
  double sum = 0.0;
  for (std::size_t f = 1; f <= last && f < bins.size(); ++f) {
    sum += std::norm(bins[f]);
  }
  const auto nn = static_cast<double>(n);
  return 2.0 * sum / (nn * nn);
}

double noise_floor_rms(std::span<const double> x, std::size_t first, std::size_t last) {
  const std::size_t n = x.size();
  if (n < 8 || last < first + 2) {
    return 0.0;
  }
  const auto s = spectrum(x, last + 1, true);
  std::vector<double> power;
  power.reserve(last - first + 1);
  for (std::size_t f = std::max<std::size_t>(first, 1); f <= last; ++f) {
    power.push_back(std::norm(s[f]));
  }
  const auto mid = power.begin() + static_cast<std::ptrdiff_t>(power.size() / 2);
  std::nth_element(power.begin(), mid, power.end());
  // E|X_f|² = σ²·Σw² for white noise; Σw² = 3N/8 for the Hann window.
  const double sigma2 = *mid / std::log(2.0) / (0.375 * static_cast<double>(n));
  return std::sqrt(sigma2 * 2.0 * static_cast<double>(last) / static_cast<double>(n));
}

namespace {

/// Samples between exact phasors in harmonic_sums(): the rotation's rounding grows by ~1e-16 a
/// step, so a run drifts by ~3e-14 rad at most — below the rounding of θ·n itself (~1e-11 rad
/// at n = 10⁶), which every phasor, exact or not, carries.
constexpr std::size_t kExactPhasorEvery = 256;

/// acc[k] = Σ_n x_n·e^{−ik(θn + φ0)} for k = 0..acc.size() − 1: each sample's phasor raised
/// harmonic by harmonic. The phasor e^{−i(θn + φ0)} is computed (sin, cos) every
/// kExactPhasorEvery samples and rotated by e^{−iθ} in between: a sin and a cos per sample were
/// three quarters of a long record's speed search.
void harmonic_sums(std::span<const double> x, double theta, double phase0_rad,
                   std::span<std::complex<double>> acc) {
  // In real arithmetic: the products std::complex gives when no NaN comes out (the same values,
  // bit for bit, without its check for one at every product). A complex<double> is an array of
  // its real and imaginary parts ([complex.numbers]).
  std::fill(acc.begin(), acc.end(), std::complex<double>{});
  if (acc.empty()) {
    return;
  }
  auto* sums = reinterpret_cast<double*>(acc.data());  // re, im, re, im, …
  const std::size_t harmonics = acc.size() - 1;
  const double rot_re = std::cos(theta), rot_im = -std::sin(theta);
  for (std::size_t start = 0; start < x.size(); start += kExactPhasorEvery) {
    const std::size_t end = std::min(x.size(), start + kExactPhasorEvery);
    const double phase = -(theta * static_cast<double>(start) + phase0_rad);
    double e_re = std::cos(phase), e_im = std::sin(phase);
    for (std::size_t n = start; n < end; ++n) {
      double p_re = x[n], p_im = 0.0;
      sums[0] += p_re;
      for (std::size_t k = 1; k <= harmonics; ++k) {
        const double next_re = p_re * e_re - p_im * e_im;
        const double next_im = p_re * e_im + p_im * e_re;
        p_re = next_re;
        p_im = next_im;
        sums[2 * k] += p_re;
        sums[2 * k + 1] += p_im;
      }
      const double next_re = e_re * rot_re - e_im * rot_im;
      const double next_im = e_re * rot_im + e_im * rot_re;
      e_re = next_re;
      e_im = next_im;
    }
  }
}

}  // namespace

std::size_t synchronous_harmonics(std::span<const double> x, double sample_rate_hz,
                                  double spindle_hz, int harmonics,
                                  std::vector<std::complex<double>>& out, double phase0_rad) {
  out.assign(static_cast<std::size_t>(harmonics + 1), {0.0, 0.0});
  const double revs_per_sample = spindle_hz / sample_rate_hz;
  const double whole = std::floor(static_cast<double>(x.size()) * revs_per_sample);
  if (whole < 1.0) {
    return 0;
  }
  const auto used =
      std::min(x.size(), static_cast<std::size_t>(std::llround(whole / revs_per_sample)));
  const double step = 2.0 * std::numbers::pi * revs_per_sample;
  std::vector<std::complex<double>> acc(out.size());
  harmonic_sums(x.first(used), step, phase0_rad, acc);
  const auto u = static_cast<double>(used);
  out[0] = acc[0] / u;
  for (int k = 1; k <= harmonics; ++k) {
    out[static_cast<std::size_t>(k)] = 2.0 * acc[static_cast<std::size_t>(k)] / u;
  }
  return used;
}

namespace {

/// Σ_{n<N} e^{iθn} = (1 − e^{iθN}) / (1 − e^{iθ}); N where θ is a multiple of 2π.
std::complex<double> phasor_sum(double theta, std::size_t n) {
  const std::complex<double> denominator = 1.0 - std::polar(1.0, theta);
  if (std::abs(denominator) < 1e-12) {
    return {static_cast<double>(n), 0.0};
  }
  return (1.0 - std::polar(1.0, theta * static_cast<double>(n))) / denominator;
}

/// The Gram matrix HᵀH of the columns 1, cos(kθn), sin(kθn) (k = 1..K; in that order, the
/// constant first) over n = 0..N−1, from the product-to-sum identities.
Eigen::MatrixXd harmonic_gram(double theta, std::size_t n, int harmonics) {
  const int size = 2 * harmonics + 1;
  auto cos_column = [](int k) { return k == 0 ? 0 : 2 * k - 1; };
  Eigen::MatrixXd g(size, size);
  for (int a = 0; a <= harmonics; ++a) {
    for (int b = 0; b <= harmonics; ++b) {
      const std::complex<double> difference = phasor_sum((a - b) * theta, n);
      const std::complex<double> sum = phasor_sum((a + b) * theta, n);
      g(cos_column(a), cos_column(b)) = 0.5 * (difference.real() + sum.real());  // cos·cos
      if (b > 0) {
        g(cos_column(a), 2 * b) = 0.5 * (sum.imag() - difference.imag());  // cos a · sin b
      }
      if (a > 0) {
        g(2 * a, cos_column(b)) = 0.5 * (sum.imag() + difference.imag());  // sin a · cos b
      }
      if (a > 0 && b > 0) {
        g(2 * a, 2 * b) = 0.5 * (difference.real() - sum.real());  // sin·sin
      }
    }
  }
  return g;
}

}  // namespace

double harmonic_fit_energy(std::span<const std::vector<double>> signals, double sample_rate_hz,
                           double spindle_hz, int harmonics) {
  if (signals.empty() || signals[0].empty() || harmonics < 1) {
    return 0.0;
  }
  const std::size_t n = signals[0].size();
  const double theta = 2.0 * std::numbers::pi * spindle_hz / sample_rate_hz;
  const Eigen::LDLT<Eigen::MatrixXd> gram(harmonic_gram(theta, n, harmonics));
  std::vector<std::complex<double>> acc(static_cast<std::size_t>(harmonics) + 1);
  Eigen::VectorXd projection(2 * harmonics + 1);  // Hᵀx
  double energy = 0.0;
  for (const std::vector<double>& x : signals) {
    harmonic_sums(x, theta, 0.0, acc);
    projection(0) = acc[0].real();
    for (int k = 1; k <= harmonics; ++k) {  // Σx·cos = Re, Σx·sin = −Im of Σx·e^{−ikθn}
      projection(2 * k - 1) = acc[static_cast<std::size_t>(k)].real();
      projection(2 * k) = -acc[static_cast<std::size_t>(k)].imag();
    }
    energy += projection.dot(gram.solve(projection));
  }
  return energy;
}

}  // namespace millwatch::diagnose
