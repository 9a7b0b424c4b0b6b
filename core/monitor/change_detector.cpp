#include "core/monitor/change_detector.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace millwatch::monitor {

double cusum_average_run_length(double k, double h, double shift) {
  const double delta = shift - k;
  const double b = h + 1.166;
  const double x = -2.0 * delta * b;
  if (std::fabs(x) < 1e-6) {
    return b * b * (1.0 + x / 3.0);  // (eˣ − 1 − x)/(2Δ²) = b²·(1 + x/3 + …)
  }
  const double e = std::expm1(x) - x;  // exp(−2Δb) + 2Δb − 1
  return e / (2.0 * delta * delta);    // +inf once exp overflows
}

double cusum_threshold_for(double k, double arl) {
  if (cusum_average_run_length(k, 0.0) >= arl) {
    return 0.0;
  }
  double lo = 0.0;
  double hi = 1.0;
  while (cusum_average_run_length(k, hi) < arl) {
    lo = hi;
    hi *= 2.0;
  }
  for (int i = 0; i < 100 && hi - lo > 1e-9 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (cusum_average_run_length(k, mid) < arl ? lo : hi) = mid;
  }
  return hi;
}

double normal_upper_quantile(double p) {
  // P(Z > z) = erfc(z/√2)/2 decreases in z: bisection.
  double lo = -40.0;
  double hi = 40.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (0.5 * std::erfc(mid / std::sqrt(2.0)) > p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double median_in_place(std::span<double> values) {
  const std::size_t n = values.size();
  if (n == 0) {
    return 0.0;
  }
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(n / 2);
  std::nth_element(values.begin(), mid, values.end());
  const double upper = *mid;
  if (n % 2 == 1) {
    return upper;
  }
  return 0.5 * (upper + *std::max_element(values.begin(), mid));
}

double successive_scatter(std::span<const double> values, std::span<double> scratch) {
  if (values.size() < 2 || scratch.size() < values.size() - 1) {
    return 0.0;
  }
  const std::span<double> d = scratch.first(values.size() - 1);
  for (std::size_t i = 0; i < d.size(); ++i) {
    d[i] = values[i + 1] - values[i];
  }
  const double centre = median_in_place(d);
  for (double& x : d) {
    x = std::fabs(x - centre);
  }
  return 1.4826 * median_in_place(d) / std::numbers::sqrt2;
}

RobustSummary robust_summary(std::span<const double> values, std::span<double> scratch) {
  RobustSummary s;
  const std::size_t n = values.size();
  if (n == 0 || scratch.size() < n) {
    return s;
  }
  const std::span<double> work = scratch.first(n);
  std::copy(values.begin(), values.end(), work.begin());
  s.median = median_in_place(work);
  for (std::size_t i = 0; i < n; ++i) {
    work[i] = std::fabs(values[i] - s.median);
  }
  s.sigma = 1.4826 * median_in_place(work);
  if (s.sigma <= 0.0 || n < 3) {
    return s;
  }
  const double clip = 5.0 * s.sigma;
  auto centred = [&](std::size_t i) { return std::clamp(values[i] - s.median, -clip, clip); };
  double mean = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    mean += centred(i);
  }
  mean /= static_cast<double>(n);
  double c0 = 0.0;
  double c1 = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double a = centred(i) - mean;
    c0 += a * a;
    if (i + 1 < n) {
      c1 += a * (centred(i + 1) - mean);
    }
  }
  s.rho1 = c0 > 0.0 ? c1 / c0 : 0.0;
  return s;
}

double ar1_block_median_sigma(double sigma, double rho1, int block) {
  const double rho = std::clamp(rho1, 0.0, 0.95);
  return std::sqrt(0.5 * std::numbers::pi) * sigma * std::sqrt((1.0 + rho) / (1.0 - rho)) /
         std::sqrt(static_cast<double>(std::max(block, 1)));
}

}  // namespace millwatch::monitor
