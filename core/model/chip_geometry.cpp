#include "core/model/chip_geometry.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace millwatch::model {
namespace {

constexpr int kMaxNewtonIterations = 30;
/// Newton stops after a step below this: convergence is quadratic (|next step| ≈ C·step² with
/// C = |F''/2F'| ≲ 1, F' ≈ R), so what is left is below 1e-16 rad.
constexpr double kNewtonLastStep_rad = 1e-8;
/// Angles up to this go through the Taylor series in small_sincos().
constexpr double kSeriesLimit_rad = 0.1;

/// sin and cos of a small angle by their Taylor series: |x| ≤ 1e-4 (a Newton step) to x³ and
/// x⁴, |x| ≤ 0.1 to x¹¹ and x¹² (truncation below 1e-22 either way); larger ones by the library.
inline void small_sincos(double x, double& s, double& c) {
  const double x2 = x * x;
  if (x2 <= 1e-8) {
    s = x * (1.0 - x2 * (1.0 / 6));
    c = 1.0 + x2 * (-0.5 + x2 * (1.0 / 24));
    return;
  }
  if (std::fabs(x) > kSeriesLimit_rad) {
    s = std::sin(x);
    c = std::cos(x);
    return;
  }
  s = x * (1.0 + x2 * (-1.0 / 6 +
                       x2 * (1.0 / 120 +
                             x2 * (-1.0 / 5040 + x2 * (1.0 / 362880 + x2 * (-1.0 / 39916800))))));
  c = 1.0 +
      x2 * (-0.5 + x2 * (1.0 / 24 +
                         x2 * (-1.0 / 720 + x2 * (1.0 / 40320 + x2 * (-1.0 / 3628800 +
                                                                      x2 * (1.0 / 479001600))))));
}

/// What the crossing of one table entry needs besides Δ.
struct Ray {
  double ct = 1.0, st = 0.0;  // cos, sin of the immersion θ = τ − ψ_j
  double cx = 0.0, cy = 0.0;  // the centre now, relative to its feed position: ρ·(sin, cos)(τ + γ)
  double sg = 0.0, cg = 1.0;  // sin, cos of γ
  double sk = 0.0, ck = 1.0;  // sin, cos of ψ_k
};

/// Newton-Raphson on F(Δ) = (Q(τ + Δ) − C(τ)) × e(θ) (see the header), from Δ = `delta` where
/// (su, cu) = (sin, cos)(τ + Δ). Each step turns (su, cu) by angle addition, so an iteration
/// calls no library trigonometry.
inline TrochoidChip solve_crossing(const PathGeometry& p, const Ray& r, double delta, double su,
                                   double cu) {
  TrochoidChip out;
  for (int it = 1; it <= kMaxNewtonIterations; ++it) {
    // sin, cos of u + γ and u − ψ_k
    const double so = su * r.cg + cu * r.sg;
    const double co = cu * r.cg - su * r.sg;
    const double sk = su * r.ck - cu * r.sk;
    const double ck = cu * r.ck + su * r.sk;
    // D = Q(τ + Δ) − C(τ)  ([000] eqs 11-12 minus eqs 9)
    const double dx = p.feed_per_rad_um * delta + p.offset_um * so + p.radius_um * sk - r.cx;
    const double dy = p.offset_um * co + p.radius_um * ck - r.cy;
    const double f = dx * r.ct - dy * r.st;  // [000] eq 13 × cos θ
    const double df = (p.feed_per_rad_um + p.offset_um * co + p.radius_um * ck) * r.ct +
                      (p.offset_um * so + p.radius_um * sk) * r.st;
    const double step = f / df;
    delta -= step;
    double ss = 0.0;
    double cs = 1.0;
    small_sincos(step, ss, cs);
    const double su_next = su * cs - cu * ss;  // u − step
    cu = cu * cs + su * ss;
    su = su_next;
    out.iterations = it;
    if (std::fabs(step) < kNewtonLastStep_rad) {
      out.converged = true;
      break;
    }
  }
  // D at the converged Δ for the chip ([000] eqs 16-18 in vector form).
  const double so = su * r.cg + cu * r.sg;
  const double co = cu * r.cg - su * r.sg;
  const double sk = su * r.ck - cu * r.sk;
  const double ck = cu * r.ck + su * r.sk;
  const double dx = p.feed_per_rad_um * delta + p.offset_um * so + p.radius_um * sk - r.cx;
  const double dy = p.offset_um * co + p.radius_um * ck - r.cy;
  out.delta_rad = delta;
  out.chip_um = p.radius_um - (dx * r.st + dy * r.ct);
  return out;
}

/// The runout angle of table t: γ plus disc t's angle. With disc angles, table t is disc t's
/// even when it is the only one (one disc, or ρ = 0 where the angle does not matter).
double table_runout_angle_rad(const PathGeometry& path, std::span<const double> disc_angle_rad,
                              int table) {
  return path.offset_angle_rad +
         (disc_angle_rad.empty() ? 0.0 : disc_angle_rad[static_cast<std::size_t>(table)]);
}

}  // namespace

TrochoidChip trochoidal_chip(const PathGeometry& p, double tau, double psi_j, double psi_k,
                             double delta_guess) {
  Ray r;
  r.ct = std::cos(tau - psi_j);
  r.st = std::sin(tau - psi_j);
  // Tool centre now, relative to its feed position v·τ (the v·τ terms cancel in Q − C).
  r.cx = p.offset_um * std::sin(tau + p.offset_angle_rad);
  r.cy = p.offset_um * std::cos(tau + p.offset_angle_rad);
  r.sg = std::sin(p.offset_angle_rad);
  r.cg = std::cos(p.offset_angle_rad);
  r.sk = std::sin(psi_k);
  r.ck = std::cos(psi_k);
  return solve_crossing(p, r, delta_guess, std::sin(tau + delta_guess),
                        std::cos(tau + delta_guess));
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

void ChipGeometry::reserve(int flutes, int passes, int steps_per_rev, int discs) {
  table_.reserve(static_cast<std::size_t>(flutes * passes * steps_per_rev) *
                 static_cast<std::size_t>(discs));
  flute_positions_.reserve(static_cast<std::size_t>(discs * flutes));
  rows_.reserve(static_cast<std::size_t>(discs));
  scratch_positions_.reserve(static_cast<std::size_t>(flutes));
  circular_row_.reserve(static_cast<std::size_t>(steps_per_rev));
  in_window_.reserve(static_cast<std::size_t>(steps_per_rev));
}

void ChipGeometry::configure(const PathGeometry& path, std::span<const double> pitch_rad,
                             int passes, int steps_per_rev, bool trochoidal, double window_from_rad,
                             double window_to_rad, std::span<const double> disc_angle_rad) {
  flutes_ = static_cast<int>(pitch_rad.size());
  passes_ = passes;
  steps_ = steps_per_rev;
  discs_ = disc_angle_rad.empty() ? 1 : static_cast<int>(disc_angle_rad.size());
  tables_ = !disc_angle_rad.empty() && path.offset_um > 0.0 ? discs_ : 1;
  const auto per_table = static_cast<std::size_t>(flutes_ * passes_ * steps_);
  if (!disc_angle_rad.empty()) {
    reserve(flutes_, passes_, steps_, discs_);  // so that ρ becoming non-zero allocates nothing
  }
  table_.resize(per_table * static_cast<std::size_t>(tables_));
  flute_positions_.resize(static_cast<std::size_t>(tables_ * flutes_));
  for (int t = 0; t < tables_; ++t) {
    const double gamma = table_runout_angle_rad(path, disc_angle_rad, t);
    flute_positions(path.radius_um, pitch_rad, path.offset_um, gamma, scratch_positions_);
    std::copy(scratch_positions_.begin(), scratch_positions_.end(),
              flute_positions_.begin() + static_cast<std::ptrdiff_t>(t * flutes_));
  }
  if (cos_grid_.size() != static_cast<std::size_t>(steps_)) {
    cos_grid_.resize(static_cast<std::size_t>(steps_));
    sin_grid_.resize(static_cast<std::size_t>(steps_));
    for (int k = 0; k < steps_; ++k) {
      cos_grid_[static_cast<std::size_t>(k)] = std::cos(k * 2.0 * std::numbers::pi / steps_);
      sin_grid_[static_cast<std::size_t>(k)] = std::sin(k * 2.0 * std::numbers::pi / steps_);
    }
  }
  circular_row_.resize(static_cast<std::size_t>(steps_));
  in_window_.resize(static_cast<std::size_t>(steps_));
  newton_iterations_ = 0;
  for (int j = 0; j < flutes_; ++j) {
    fill_window(pitch_rad, j, trochoidal, window_from_rad, window_to_rad);
    for (int n = 1; n <= passes_; ++n) {
      fill_rows(path, pitch_rad, disc_angle_rad, j, n);
    }
  }
}

void ChipGeometry::fill_window(std::span<const double> pitch_rad, int j, bool trochoidal,
                               double window_from_rad, double window_to_rad) {
  const double psi_j = pitch_rad[static_cast<std::size_t>(j)];
  const double d_phi = 2.0 * std::numbers::pi / steps_;
  const double two_pi = 2.0 * std::numbers::pi;
  const double window_rad = window_to_rad - window_from_rad;
  for (int k = 0; k < steps_; ++k) {
    bool trochoid = false;
    if (trochoidal) {
      const double immersion = k * d_phi - psi_j;
      const double into_window =
          std::fmod(std::fmod(immersion - window_from_rad, two_pi) + two_pi, two_pi);
      trochoid = into_window <= window_rad;
    }
    in_window_[static_cast<std::size_t>(k)] = trochoid ? 1 : 0;
  }
}

void ChipGeometry::fill_rows(const PathGeometry& path, std::span<const double> pitch_rad,
                             std::span<const double> disc_angle_rad, int j, int n) {
  const int k_flute = ((j - n) % flutes_ + flutes_) % flutes_;
  const double back = pitch_back_rad(pitch_rad, j, n);
  const double psi_j = pitch_rad[static_cast<std::size_t>(j)];
  const double cpj = std::cos(psi_j);
  const double spj = std::sin(psi_j);
  // What every disc's row shares: the circular chip's feed term v·Δψ_n·sin θ (the radii are
  // added per disc), sin θ = sin(τ − ψ_j) from the grid's τ; where the trochoid is wanted is
  // fill_window()'s.
  const double feed_um = path.feed_per_rad_um * back;
  for (int k = 0; k < steps_; ++k) {
    const auto uk = static_cast<std::size_t>(k);
    circular_row_[uk] = feed_um * (sin_grid_[uk] * cpj - cos_grid_[uk] * spj);
  }
  // The earlier flute k sits at ψ_j − back (mod 2π) relative to flute j; the solver works with
  // ψ_k = ψ_j − back so that Δ ≈ −back needs no wrapping.
  const double psi_k = psi_j - back;
  // The crossing is near u = τ − back: (sin, cos)(u) from the grid's τ turned by −back, then by
  // the guess's small offset from −back.
  const double sb = std::sin(-back);
  const double cb = std::cos(-back);
  const double sk = std::sin(psi_k);
  const double ck = std::cos(psi_k);
  rows_.resize(static_cast<std::size_t>(tables_));
  for (int t = 0; t < tables_; ++t) {
    DiscRow& d = rows_[static_cast<std::size_t>(t)];
    d.row =
        table_.data() + static_cast<std::size_t>(((t * flutes_ + j) * passes_ + n - 1) * steps_);
    const auto positions = flutes_at(t);
    d.rj_um = positions[static_cast<std::size_t>(j)].radius_um;
    d.rk_um = positions[static_cast<std::size_t>(k_flute)].radius_um;
    const double gamma = table_runout_angle_rad(path, disc_angle_rad, t);
    d.sin_gamma = std::sin(gamma);
    d.cos_gamma = std::cos(gamma);
    d.last_rad = -back;  // [000] eq 19
    d.slope_rad = 0.0;
    d.known = 0;
  }
  // Grid step by grid step, every disc's crossing: the discs' solves are independent and
  // overlap in the processor, where one disc's steps form a chain (each starts from the last
  // crossing found, extrapolated linearly from the two before).
  for (int k = 0; k < steps_; ++k) {
    const auto uk = static_cast<std::size_t>(k);
    if (in_window_[uk] == 0) {
      for (DiscRow& d : rows_) {
        d.row[k] = circular_row_[uk] + d.rj_um - d.rk_um;
        d.known = 0;
      }
      continue;
    }
    const double cphi = cos_grid_[uk];
    const double sphi = sin_grid_[uk];
    Ray ray;
    ray.ct = cphi * cpj + sphi * spj;  // θ = τ − ψ_j
    ray.st = sphi * cpj - cphi * spj;
    ray.sk = sk;
    ray.ck = ck;
    for (DiscRow& d : rows_) {
      ray.sg = d.sin_gamma;
      ray.cg = d.cos_gamma;
      ray.cx = path.offset_um * (sphi * d.cos_gamma + cphi * d.sin_gamma);  // ρ·sin(τ + γ)
      ray.cy = path.offset_um * (cphi * d.cos_gamma - sphi * d.sin_gamma);  // ρ·cos(τ + γ)
      const double guess = d.known == 0   ? -back
                           : d.known == 1 ? d.last_rad
                                          : d.last_rad + d.slope_rad;
      double so = 0.0;
      double co = 1.0;
      small_sincos(guess + back, so, co);
      const double sg = sb * co + cb * so;  // (sin, cos)(guess)
      const double cg = cb * co - sb * so;
      const TrochoidChip c =
          solve_crossing(path, ray, guess, sphi * cg + cphi * sg, cphi * cg - sphi * sg);
      d.row[k] = c.chip_um;
      newton_iterations_ += c.iterations;
      if (c.converged) {
        d.slope_rad = d.known > 0 ? c.delta_rad - d.last_rad : 0.0;
        d.last_rad = c.delta_rad;
        d.known = std::min(d.known + 1, 2);
      } else {
        d.known = 0;
      }
    }
  }
}

}  // namespace millwatch::model
