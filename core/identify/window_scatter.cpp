#include "core/identify/window_scatter.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>

#include "core/monitor/change_detector.hpp"

namespace millwatch::identify {
namespace {

/// Appends `x` to a series of at most WindowScatter::kWindows values (the oldest dropped).
template <typename T>
void keep(std::vector<T>& series, T x) {
  if (series.size() == WindowScatter::kWindows) {
    series.erase(series.begin());
  }
  series.push_back(x);
}

/// The median of the newest `k` values minus the oldest `k`'s (`scratch`: at least k values).
double quarter_drift(const std::vector<double>& series, std::size_t k, std::span<double> scratch) {
  const std::span<double> work = scratch.first(k);
  std::copy_n(series.begin(), k, work.begin());
  const double oldest = monitor::median_in_place(work);
  std::copy_n(series.end() - static_cast<std::ptrdiff_t>(k), k, work.begin());
  return monitor::median_in_place(work) - oldest;
}

}  // namespace

void WindowScatter::add(const FitResult& fit) {
  if (!fit.ok) {
    return;
  }
  if (fit.radius_from_ce1_um.size() != radius_from_ce1_um_.size()) {
    rho_um_.clear();
    gamma_rad_.clear();
    on_edge_.clear();
    radius_from_ce1_um_.assign(fit.radius_from_ce1_um.size(), {});
  }
  keep(rho_um_, fit.rho_um.value);
  keep(on_edge_, fit.runout_at_contact_edge);
  // γ unwrapped against the window before: its differences are turns apart at most by noise.
  double gamma = fit.gamma_rad.value;
  if (!gamma_rad_.empty()) {
    const double twice_pi = 2.0 * std::numbers::pi;
    gamma = gamma_rad_.back() + std::remainder(gamma - gamma_rad_.back(), twice_pi);
  }
  keep(gamma_rad_, gamma);
  for (std::size_t j = 0; j < radius_from_ce1_um_.size(); ++j) {
    keep(radius_from_ce1_um_[j], fit.radius_from_ce1_um[j].value);
  }
}

WindowScatter::Scatter WindowScatter::scatter() const {
  Scatter s;
  s.windows = windows();
  s.radius_from_ce1_um.assign(radius_from_ce1_um_.size(), 0.0);
  if (s.windows < kLeastWindows) {
    return s;
  }
  std::vector<double> scratch(rho_um_.size());
  using monitor::successive_scatter;
  s.rho_um = successive_scatter(rho_um_, scratch);
  s.gamma_rad = successive_scatter(gamma_rad_, scratch);
  for (std::size_t j = 0; j < radius_from_ce1_um_.size(); ++j) {
    s.radius_from_ce1_um[j] = successive_scatter(radius_from_ce1_um_[j], scratch);
  }
  if (s.windows < kLeastDriftWindows) {
    return s;
  }
  const std::size_t k = rho_um_.size() / 4;
  s.rho_drift_um = quarter_drift(rho_um_, k, scratch);
  s.gamma_drift_rad = quarter_drift(gamma_rad_, k, scratch);
  for (const auto& series : radius_from_ce1_um_) {
    s.radius_drift_um = std::max(s.radius_drift_um, std::fabs(quarter_drift(series, k, scratch)));
  }
  // The two medians' difference for a level without drift: each median of k values with the
  // windows' scatter (monitor::ar1_block_median_sigma, uncorrelated windows).
  const double sampling_um =
      std::numbers::sqrt2 * monitor::ar1_block_median_sigma(s.rho_um, 0.0, static_cast<int>(k));
  // On a contact edge ρ is the least the radii allow, elsewhere the fit's: a record mixing the
  // two is no drift.
  const bool one_kind =
      std::all_of(on_edge_.begin(), on_edge_.end(), [&](bool e) { return e == on_edge_.back(); });
  s.rho_drifts = one_kind && std::fabs(s.rho_drift_um) > 3.0 * sampling_um &&
                 std::fabs(s.rho_drift_um) > 2.0 * s.radius_drift_um;
  return s;
}

FitResult WindowScatter::widened(const FitResult& fit, Widening& how) const {
  FitResult out = fit;
  how = {};
  const Scatter s = scatter();
  if (s.rho_drifts && std::fabs(s.rho_drift_um) > fit.rho_um.sigma) {
    how.by_drift = true;
    out.rho_um.sigma = std::fabs(s.rho_drift_um);
    out.gamma_rad.sigma =
        std::min(std::numbers::pi, std::max(out.gamma_rad.sigma, std::fabs(s.gamma_drift_rad)));
  }
  const auto widen = [&](Estimate& e, double spread) {
    if (spread > 1.5 * e.sigma) {
      how.by_scatter = true;
    }
    e.sigma = std::max(e.sigma, spread);
  };
  widen(out.rho_um, s.rho_um);
  widen(out.gamma_rad, s.gamma_rad);
  if (out.radius_from_ce1_um.size() == s.radius_from_ce1_um.size()) {
    for (std::size_t j = 0; j < s.radius_from_ce1_um.size(); ++j) {
      widen(out.radius_from_ce1_um[j], s.radius_from_ce1_um[j]);
      if (j < out.cutting_radius_um.size()) {
        out.cutting_radius_um[j].sigma =
            std::max(out.cutting_radius_um[j].sigma, s.radius_from_ce1_um[j]);
      }
    }
  }
  return out;
}

}  // namespace millwatch::identify
