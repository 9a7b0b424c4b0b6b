#pragma once
// Small statistical pieces for change detection on streams of features, designed for a stated
// false-alarm rate: a one-sided CUSUM with Siegmund's run-length approximation, the threshold
// for a wanted in-control average run length (ARL₀), and a robust summary of a baseline series
// (median, σ from the MAD, lag-1 autocorrelation) with the σ of a block statistic it implies.
//
// The CUSUM works on a standardised input z_n = (x_n − μ)/σ, which is N(δ, 1) when the mean
// has shifted by δσ. AlertEngine feeds it block medians of per-revolution flute features; other
// statistics (e.g. identified runout) can be fed the same way.

#include <span>

namespace millwatch::monitor {

/// Siegmund's approximation of the average run length of the one-sided CUSUM
///   S_n = max(0, S_{n−1} + z_n − k),  alarm when S_n > h,
/// for z_n ~ N(δ, 1) independent (D. Siegmund, Sequential Analysis, 1985; the form quoted in
/// Montgomery's Introduction to Statistical Quality Control, CUSUM chapter):
///   ARL(δ) = (exp(−2Δb) + 2Δb − 1)/(2Δ²),  Δ = δ − k,  b = h + 1.166   (= b² for Δ = 0).
/// In control (δ = 0) this is within a few per cent of the exact value for k ≤ 1.5; for larger
/// k it underestimates the ARL (so a threshold designed with it errs on the safe side).
/// @param k reference value (allowance), k ≥ 0, in units of σ
/// @param h decision threshold, h ≥ 0, in units of σ
/// @param shift δ, the true mean shift in units of σ
/// @return the ARL in input steps (may be +inf)
double cusum_average_run_length(double k, double h, double shift = 0.0);

/// The smallest threshold h ≥ 0 whose in-control ARL (Siegmund) is at least `arl` steps.
/// @param k allowance in σ, k ≥ 0
/// @param arl wanted in-control average run length in steps, arl ≥ 1
double cusum_threshold_for(double k, double arl);

/// z with P(Z > z) = p for a standard normal Z; p ∈ (0, 1).
double normal_upper_quantile(double p);

/// One-sided upward CUSUM on standardised input (see cusum_average_run_length). Values, no
/// allocation.
class Cusum {
 public:
  Cusum() = default;
  /// @param k allowance in σ (≥ 0); @param h threshold in σ (≥ 0)
  Cusum(double k, double h) : k_(k), h_(h) {}

  /// Adds one standardised value; returns true when the statistic exceeds h.
  bool update(double z) {
    statistic_ += z - k_;
    if (statistic_ <= 0.0) {
      statistic_ = 0.0;
      run_ = 0;
    } else {
      ++run_;
    }
    return statistic_ > h_;
  }
  void reset() {
    statistic_ = 0.0;
    run_ = 0;
  }
  [[nodiscard]] double statistic() const { return statistic_; }
  /// Steps since the statistic last was zero: the CUSUM's estimate of when the change began.
  [[nodiscard]] int run() const { return run_; }
  [[nodiscard]] double k() const { return k_; }
  [[nodiscard]] double h() const { return h_; }

 private:
  double k_ = 0.5;
  double h_ = 5.0;
  double statistic_ = 0.0;
  int run_ = 0;
};

/// Robust summary of a series: median, σ = 1.4826·MAD (σ for Gaussian data), and the lag-1
/// autocorrelation ρ of the series clipped to median ± 5σ.
struct RobustSummary {
  double median = 0.0;
  double sigma = 0.0;
  double rho1 = 0.0;
};

/// @param values the series (in order, for ρ)
/// @param scratch at least values.size() elements, overwritten; nothing is allocated
RobustSummary robust_summary(std::span<const double> values, std::span<double> scratch);

/// Median of `values` (reordered in place); 0 for an empty span. Nothing is allocated.
double median_in_place(std::span<double> values);

/// σ of one value of a series about its level from the successive differences
/// d_i = x_{i+1} − x_i: 1.4826·median|d − median d|/√2 — blind to a slow trend and to a single
/// step (windows of a cut before and after a change). 0 with no difference, or when `scratch`
/// holds fewer than values.size() − 1 elements (overwritten). Nothing is allocated.
double successive_scatter(std::span<const double> values, std::span<double> scratch);

/// σ of the median of `block` consecutive values of a stationary series whose single values
/// have σ = `sigma` and lag-1 autocorrelation ρ, taken as AR(1):
///   σ_block = 1.2533 · σ · √((1 + ρ)/(1 − ρ)) / √block,
/// ρ clamped to [0, 0.95]. (1 + ρ)/(1 − ρ) is the long-run variance factor of an AR(1), an
/// upper bound of the finite-block factor that also covers the correlation between adjacent
/// blocks; 1.2533 = √(π/2) is the median's σ relative to the mean's for Gaussian data.
double ar1_block_median_sigma(double sigma, double rho1, int block);

}  // namespace millwatch::monitor
