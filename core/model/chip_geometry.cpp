#include "core/model/chip_geometry.hpp"

#include <cmath>
#include <numbers>

namespace millwatch::model {
namespace {

constexpr int kMaxNewtonIterations = 30;
constexpr double kNewtonTolerance_rad = 1e-13;

}  // namespace

TrochoidChip trochoidal_chip(const PathGeometry& p, double tau, double psi_j, double psi_k,
                             double delta_guess) {
  const double theta = tau - psi_j;
  const double ct = std::cos(theta);
  const double st = std::sin(theta);
  // Tool centre now, relative to its feed position v·τ (the v·τ terms cancel in Q − C).
  const double cx = p.offset_um * std::sin(tau + p.offset_angle_rad);
  const double cy = p.offset_um * std::cos(tau + p.offset_angle_rad);

  TrochoidChip out;
  double delta = delta_guess;
  double dx = 0.0;
  double dy = 0.0;
  for (int it = 1; it <= kMaxNewtonIterations; ++it) {
    const double tp = tau + delta;
    const double so = std::sin(tp + p.offset_angle_rad);
    const double co = std::cos(tp + p.offset_angle_rad);
    const double sk = std::sin(tp - psi_k);
    const double ck = std::cos(tp - psi_k);
    // D = Q(τ + Δ) − C(τ)  ([000] eqs 11-12 minus eqs 9)
    dx = p.feed_per_rad_um * delta + p.offset_um * so + p.radius_um * sk - cx;
    dy = p.offset_um * co + p.radius_um * ck - cy;
    const double f = dx * ct - dy * st;  // [000] eq 13 × cos θ
    const double df = (p.feed_per_rad_um + p.offset_um * co + p.radius_um * ck) * ct +
                      (p.offset_um * so + p.radius_um * sk) * st;
    const double step = f / df;
    delta -= step;
    out.iterations = it;
    if (std::fabs(step) < kNewtonTolerance_rad) {
      out.converged = true;
      break;
    }
  }
  // Recompute D at the converged Δ for the chip ([000] eqs 16-18 in vector form).
  const double tp = tau + delta;
  dx = p.feed_per_rad_um * delta + p.offset_um * std::sin(tp + p.offset_angle_rad) +
       p.radius_um * std::sin(tp - psi_k) - cx;
  dy = p.offset_um * std::cos(tp + p.offset_angle_rad) + p.radius_um * std::cos(tp - psi_k) - cy;
  out.delta_rad = delta;
  out.chip_um = p.radius_um - (dx * st + dy * ct);
  return out;
}

double circular_chip_um(const PathGeometry& p, double immersion_rad, double pitch_back,
                        double radius_j_um, double radius_k_um) {
  return p.feed_per_rad_um * pitch_back * std::sin(immersion_rad) + radius_j_um - radius_k_um;
}

double pitch_back_rad(std::span<const double> pitch_rad, int flute, int pass_back) {
  const int flutes = static_cast<int>(pitch_rad.size());
  const double two_pi = 2.0 * std::numbers::pi;
  double total = 0.0;
  for (int m = 0; m < pass_back; ++m) {
    const int to = ((flute - m) % flutes + flutes) % flutes;
    const int from = ((flute - m - 1) % flutes + flutes) % flutes;
    double interval =
        pitch_rad[static_cast<std::size_t>(to)] - pitch_rad[static_cast<std::size_t>(from)];
    if (interval <= 0.0) {
      interval += two_pi;
    }
    total += interval;
  }
  return total;
}

void ChipGeometry::configure(const PathGeometry& path, std::span<const double> pitch_rad,
                             int passes, int steps_per_rev, bool trochoidal, double window_from_rad,
                             double window_to_rad) {
  flutes_ = static_cast<int>(pitch_rad.size());
  passes_ = passes;
  steps_ = steps_per_rev;
  table_.resize(static_cast<std::size_t>(flutes_ * passes_ * steps_));
  flute_positions(path.radius_um, pitch_rad, path.offset_um, path.offset_angle_rad,
                  flute_positions_);
  newton_iterations_ = 0;
  for (int j = 0; j < flutes_; ++j) {
    for (int n = 1; n <= passes_; ++n) {
      fill_row(path, pitch_rad, j, n, trochoidal, window_from_rad, window_to_rad);
    }
  }
}

void ChipGeometry::fill_row(const PathGeometry& path, std::span<const double> pitch_rad, int j,
                            int n, bool trochoidal, double window_from_rad, double window_to_rad) {
  double* row = table_.data() + static_cast<std::size_t>((j * passes_ + n - 1) * steps_);
  const int k_flute = ((j - n) % flutes_ + flutes_) % flutes_;
  const double back = pitch_back_rad(pitch_rad, j, n);
  const double psi_j = pitch_rad[static_cast<std::size_t>(j)];
  const double d_phi = 2.0 * std::numbers::pi / steps_;
  const double rj = flute_positions_[static_cast<std::size_t>(j)].radius_um;
  const double rk = flute_positions_[static_cast<std::size_t>(k_flute)].radius_um;
  const double two_pi = 2.0 * std::numbers::pi;
  const double window_rad = window_to_rad - window_from_rad;
  // The earlier flute k sits at ψ_j − back (mod 2π) relative to flute j; the solver works with
  // ψ_k = ψ_j − back so that Δ ≈ −back needs no wrapping. Warm start along the grid.
  const double psi_k = psi_j - back;
  double guess = -back;  // [000] eq 19
  for (int k = 0; k < steps_; ++k) {
    const double immersion = k * d_phi - psi_j;
    const double into_window =
        std::fmod(std::fmod(immersion - window_from_rad, two_pi) + two_pi, two_pi);
    if (!trochoidal || into_window > window_rad) {
      row[k] = circular_chip_um(path, immersion, back, rj, rk);
      guess = -back;
      continue;
    }
    const TrochoidChip c = trochoidal_chip(path, k * d_phi, psi_j, psi_k, guess);
    row[k] = c.chip_um;
    newton_iterations_ += c.iterations;
    guess = c.converged ? c.delta_rad : -back;
  }
}

}  // namespace millwatch::model
