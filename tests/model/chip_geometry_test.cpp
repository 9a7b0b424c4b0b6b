#include "core/model/chip_geometry.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

namespace millwatch::model {
namespace {

constexpr double kPi = std::numbers::pi;

PathGeometry path(double radius_um, double feed_per_tooth_um, int flutes, double offset_um = 0.0,
                  double offset_angle_rad = 0.0) {
  return {radius_um, feed_per_tooth_um * flutes / (2.0 * kPi), offset_um, offset_angle_rad};
}

std::vector<double> uniform_pitch(int flutes) {
  std::vector<double> p(static_cast<std::size_t>(flutes));
  for (int j = 0; j < flutes; ++j) {
    p[static_cast<std::size_t>(j)] = 2.0 * kPi * j / flutes;
  }
  return p;
}

// Without runout the exact trochoidal chip differs from f_t·sin θ by second-order terms. The
// earlier flute's path is a circle around the centre as it was when that flute crossed the ray,
// f' = f_t·(1 − f_t·cos θ/(πR)) behind (N_z = 2: the crossing is f_t·cos θ/R of rotation off
// one pitch), so h ≈ f'·sin θ + f'²·cos²θ/(2R). The curvature term alone is the classic
// f_t²/(2R) bound; the feed-phase term f_t²·sin θ·cos θ/(πR) adds up to 1/π² of it near the
// entry and exit: max over θ of sin θ·cos θ/π + cos²θ/2 is 1/4 + √(1/(4π²) + 1/16), so the
// deviation is bounded by c₂·f_t²/(2R), c₂ = 1.0927, plus third-order terms O(f_t³/R²).
TEST(ChipGeometry, TrochoidalMatchesCircularWithinSecondOrderTermWithoutRunout) {
  for (double ft : {1.0, 5.0, 10.0, 20.0}) {
    const double radius = 200.0;
    const auto p = path(radius, ft, 2);
    double worst = 0.0;
    double worst_central = 0.0;
    for (int k = 0; k <= 1800; ++k) {
      const double theta = k * kPi / 1800.0;
      const auto c = trochoidal_chip(p, theta, 0.0, -kPi, -kPi);
      ASSERT_TRUE(c.converged);
      const double f_eff = ft * (1.0 - ft * std::cos(theta) / (kPi * radius));
      const double second_order = f_eff * std::sin(theta) +
                                  f_eff * f_eff * std::cos(theta) * std::cos(theta) / (2 * radius);
      EXPECT_NEAR(c.chip_um, second_order, 2.0 * ft * ft * ft / (radius * radius)) << theta;
      const double dev = std::fabs(c.chip_um - ft * std::sin(theta));
      worst = std::max(worst, dev);
      if (theta > kPi / 4 && theta < 3 * kPi / 4) {
        worst_central = std::max(worst_central, dev);
      }
    }
    const double classic = ft * ft / (2.0 * radius);
    EXPECT_LE(worst_central, classic) << "f_t = " << ft;
    const double c2 = 2.0 * (0.25 + std::sqrt(1.0 / (4.0 * kPi * kPi) + 1.0 / 16.0));
    EXPECT_LE(worst, c2 * classic + 2.0 * ft * ft * ft / (radius * radius)) << "f_t = " << ft;
    EXPECT_GT(worst, 0.9 * classic);  // the trochoid really differs, by about that much
  }
}

// The Newton solution reproduces [000] eqs 16-18 (with atan2, physics-notes) evaluated at the
// solved time: the same crossing point, computed through the circle around the old centre.
TEST(ChipGeometry, NewtonSolutionSatisfiesPaperEquations16To18) {
  const auto p = path(200.0, 4.0, 2, 1.82, 0.58);
  for (double tau : {0.3, 1.0, 1.57, 2.2, 2.9}) {
    const auto c = trochoidal_chip(p, tau, 0.0, -kPi, -kPi);
    ASSERT_TRUE(c.converged);
    const double t_prev = tau + c.delta_rad;
    // [000] eq 9 (feed along x) at both times
    const double xc = p.feed_per_rad_um * tau + p.offset_um * std::sin(tau + p.offset_angle_rad);
    const double yc = p.offset_um * std::cos(tau + p.offset_angle_rad);
    const double xcp =
        p.feed_per_rad_um * t_prev + p.offset_um * std::sin(t_prev + p.offset_angle_rad);
    const double ycp = p.offset_um * std::cos(t_prev + p.offset_angle_rad);
    const double L = std::hypot(xc - xcp, yc - ycp);        // eq 17
    const double alpha_o = std::atan2(yc - ycp, xc - xcp);  // eq 18 (atan2)
    const double theta = tau;                               // flute 0
    const double h16 = p.radius_um + L * std::sin(theta + alpha_o) -
                       std::sqrt(p.radius_um * p.radius_um -
                                 L * L * std::cos(theta + alpha_o) * std::cos(theta + alpha_o));
    EXPECT_NEAR(c.chip_um, h16, 1e-9) << "tau " << tau;
    EXPECT_LE(c.iterations, 6);
  }
}

// [000] Fig. 4: runout angle 30°, ρ = 3 µm. At f_t = 10 µm both flutes cut; at f_t = 5 µm the
// short flute never engages (f_t < 2ρ·cos 30° = 5.2 µm, physics-notes).
TEST(ChipGeometry, Figure4ShortToothDoesNotCutAtFiveMicrons) {
  const auto pitch = uniform_pitch(2);
  for (double ft : {5.0, 10.0}) {
    ChipGeometry g;
    g.configure(path(200.0, ft, 2, 3.0, 30.0 * kPi / 180.0), pitch, 2, 720, true);
    // flute 0 is the long one here (cos(γ + ψ_0) > 0)
    EXPECT_GT(g.flutes_at()[0].radius_um, g.flutes_at()[1].radius_um);
    double short_max = -1e9;
    double long_max = -1e9;
    for (int k = 0; k < 720; ++k) {
      const int k1 = (k + 360) % 720;  // flute 1's immersion equals flute 0's at k
      short_max = std::max(short_max, std::min(g.at(1, 1, k1), g.at(1, 2, k1)));
      long_max = std::max(long_max, std::min(g.at(0, 1, k), g.at(0, 2, k)));
    }
    if (ft == 5.0) {
      EXPECT_LE(short_max, 0.0) << "short tooth must not cut at 5 um/tooth";
      EXPECT_NEAR(long_max, 2.0 * ft, 0.05);  // the long tooth removes both feeds
    } else {
      EXPECT_GT(short_max, 1.0);
      EXPECT_NEAR(long_max + short_max, 2.0 * ft, 0.2);
    }
  }
}

/// Largest chip of flute j over a revolution against the envelope of the previous `flutes`
/// passes (trochoidal tables), on a 400 µm radius tool with runout ρ at angle 0.
double best_chip_um(int flutes, int flute, double feed_per_tooth_um, double rho_um) {
  ChipGeometry g;
  g.configure(path(400.0, feed_per_tooth_um, flutes, rho_um, 0.0), uniform_pitch(flutes), flutes,
              720 * flutes, true);
  double best = -1e9;
  for (int k = 0; k < g.steps(); ++k) {
    double h = 1e9;
    for (int n = 1; n <= flutes; ++n) {
      h = std::min(h, g.at(flute, n, k));
    }
    best = std::max(best, h);
  }
  return best;
}

// When does a flute stop cutting? At γ = 0 flute j's chip against the pass n back is, at the
// slot centre (θ = π/2, where every pass's chip peaks), n·f_t·s_{j,n} + r_j − r_{j−n}, with the
// radii r_j = √(R² + ρ² + 2Rρ·cos ψ_j) and s_{j,n} = (2πn/N − ε_j + ε_{j−n})/(2πn/N) the flute's
// actual spacing from the pass n back over the nominal one (edge shifts
// ε_j = atan2(ρ·sin ψ_j, R + ρ·cos ψ_j); the trochoid's own correction vanishes at θ = π/2).
// The chip is the smallest over the passes, so flute j never cuts when
//   f_t ≤ f*_j = max_n (r_{j−n} − r_j)/(n·s_{j,n}).
// To first order in ρ (r_j ≈ R + ρ·cos ψ_j, s = 1):
//   N = 2: flute 1 f* = 2ρ (= N_z·ρ, [000] Sect. 2.1).
//   N = 3: radii R + ρ, R − ρ/2, R − ρ/2. Flute 1 (after the long flute) f* = 1.5ρ (n = 1);
//          flute 2 cuts f_t against flute 1 while flute 1 cuts, and only once that stops does
//          it meet flute 0's path two feeds back: f* = (1.5ρ)/2 = 0.75ρ (n = 2).
//   N = 4: radii R + ρ, R, R − ρ, R. Flute 1 (after the long flute) f* = ρ (n = 1). Flute 2
//          (opposite the long one) f* = ρ: against flute 1 (n = 1, ρ/1) and flute 0 (n = 2,
//          2ρ/2) alike. Flute 3 cuts f_t + ρ against flute 2 and 2·f_t against flute 1, but
//          only 3·f_t − ρ against flute 0: f* = ρ/3 (n = 3).
// (Which flute is "the shortest" is not the question for N > 2: flutes 1 and 2 of N = 3 tie.)
// The tables (trochoidal, N passes) must show each flute's largest chip ≤ 0 at 0.99·f*_j and
// > 0 at 1.01·f*_j, and that largest chip equal to min_n(n·f_t·s_{j,n} + r_j − r_{j−n}).
TEST(ChipGeometry, ShortToothThresholdFollowsTheRadiiAndPitchOfEveryFlute) {
  const double rho = 3.0;
  const double radius = 400.0;  // as best_chip_um
  struct FirstOrder {
    int flutes, flute;
    double threshold_per_rho;
  };
  // The first-order thresholds above, which the exact formula must reproduce to O(ρ/R).
  for (const FirstOrder& f :
       {FirstOrder{2, 1, 2.0}, FirstOrder{3, 1, 1.5}, FirstOrder{3, 2, 0.75}, FirstOrder{4, 1, 1.0},
        FirstOrder{4, 2, 1.0}, FirstOrder{4, 3, 1.0 / 3.0}}) {
    SCOPED_TRACE(std::to_string(f.flutes) + " flutes, flute " + std::to_string(f.flute));
    const auto pitch = uniform_pitch(f.flutes);
    std::vector<double> r(pitch.size()), eps(pitch.size());
    for (std::size_t j = 0; j < pitch.size(); ++j) {
      r[j] = std::sqrt(radius * radius + rho * rho + 2.0 * radius * rho * std::cos(pitch[j]));
      eps[j] = std::atan2(rho * std::sin(pitch[j]), radius + rho * std::cos(pitch[j]));
    }
    const int n_z = f.flutes;
    const auto j = static_cast<std::size_t>(f.flute);
    auto spacing = [&](int n) {
      const auto k = static_cast<std::size_t>(((f.flute - n) % n_z + n_z) % n_z);
      const double nominal = 2.0 * kPi * n / n_z;
      return (nominal - eps[j] + eps[k]) / nominal;
    };
    auto behind = [&](int n) {  // r_{j−n} − r_j
      return r[static_cast<std::size_t>(((f.flute - n) % n_z + n_z) % n_z)] - r[j];
    };
    double threshold = -1e9;
    for (int n = 1; n <= n_z; ++n) {
      threshold = std::max(threshold, behind(n) / (n * spacing(n)));
    }
    EXPECT_NEAR(threshold / rho, f.threshold_per_rho, 0.02 * f.threshold_per_rho);
    for (double ratio : {0.99, 1.01}) {
      const double ft = ratio * threshold;
      const double best = best_chip_um(n_z, f.flute, ft, rho);
      double expected = 1e9;  // the chip at the slot centre, the smallest over the passes
      for (int n = 1; n <= n_z; ++n) {
        expected = std::min(expected, n * ft * spacing(n) - behind(n));
      }
      if (ratio < 1.0) {
        EXPECT_LE(best, 0.0) << "f_t/rho = " << ft / rho;
      } else {
        EXPECT_GT(best, 0.0) << "f_t/rho = " << ft / rho;
        // The grid (0.125° for N = 2) misses the peak by f_t·Δθ²/2 < 1e-4 µm; leaving out the
        // pitch factor s would be off by 5-15e-3 µm.
        EXPECT_NEAR(best, expected, 2e-4) << "f_t/rho = " << ft / rho;
      }
    }
  }
}

// Below every short flute's threshold (the smallest is ρ/3, 4 flutes) the long flute 0 alone
// removes a revolution's feed, N_z·f_t, at the slot centre.
TEST(ChipGeometry, BelowTheThresholdsTheLongFluteCutsEveryFeed) {
  const double rho = 3.0;
  for (int flutes : {2, 3, 4}) {
    const double ft = 0.25 * rho;
    EXPECT_NEAR(best_chip_um(flutes, 0, ft, rho), flutes * ft, 0.01 * flutes * ft);
  }
}

// Without looking back more than one pass the long flute is credited with material the short
// flute never removed: f_t + Δr instead of the 2·f_t it really cuts.
TEST(ChipGeometry, SinglePassOverestimatesTheLongFluteWhenTheShortOneMisses) {
  const auto pitch = uniform_pitch(2);
  ChipGeometry g;
  g.configure(path(200.0, 2.0, 2, 3.0, 0.0), pitch, 2, 720, false);
  const int centre = 180;  // θ = π/2 for flute 0
  const double dr = g.flutes_at()[0].radius_um - g.flutes_at()[1].radius_um;
  EXPECT_NEAR(g.at(0, 1, centre), 2.0 + dr, 1e-9);
  EXPECT_NEAR(g.at(0, 2, centre), 4.0, 1e-9);
}

/// The trochoidal crossing solved independently of ChipGeometry's Newton solver: bisection on
/// the cross product of [000] eq 13 (× cos θ) with fresh trigonometry at every point, then the
/// chip along the ray ([000] eqs 16-18 in vector form).
double chip_by_bisection(const PathGeometry& p, double tau, double psi_j, double psi_k,
                         double back) {
  auto crossing = [&](double delta, double* chip) {
    const double theta = tau - psi_j;
    const double tp = tau + delta;
    const double dx = p.feed_per_rad_um * delta + p.offset_um * std::sin(tp + p.offset_angle_rad) +
                      p.radius_um * std::sin(tp - psi_k) -
                      p.offset_um * std::sin(tau + p.offset_angle_rad);
    const double dy = p.offset_um * std::cos(tp + p.offset_angle_rad) +
                      p.radius_um * std::cos(tp - psi_k) -
                      p.offset_um * std::cos(tau + p.offset_angle_rad);
    if (chip != nullptr) {
      *chip = p.radius_um - (dx * std::sin(theta) + dy * std::cos(theta));
    }
    return dx * std::cos(theta) - dy * std::sin(theta);
  };
  double lo = -back - 0.3;
  double hi = -back + 0.3;
  const double f_lo = crossing(lo, nullptr);
  EXPECT_LT(f_lo * crossing(hi, nullptr), 0.0);
  for (int i = 0; i < 80; ++i) {
    const double mid = 0.5 * (lo + hi);
    if ((crossing(mid, nullptr) < 0.0) == (f_lo < 0.0)) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  double chip = 0.0;
  crossing(0.5 * (lo + hi), &chip);
  return chip;
}

// A rigid offset of the tool axis (model_config.hpp RunoutHelix::kRigidAxis): disc i's table is
// the tip's geometry with the runout angle γ + a_i. Each disc's radii are [001] eq 1's
// √(R² + ρ² + 2Rρ·cos(γ + a_i + ψ_j)), its trochoidal entries the crossing solved independently
// (bisection) at γ + a_i, its circular entries f_t·N·Δψ/(2π)·sin θ + r_{j,i} − r_{k,i}.
TEST(ChipGeometry, EachDiscHasTheRunoutAngleItsEdgeSees) {
  const int flutes = 3;
  const auto pitch = uniform_pitch(flutes);
  const double radius = 200.0;
  const double rho = 2.5;
  const double gamma = 0.58;
  const std::vector<double> disc_angles = {0.01, 0.04, 0.07, 0.3};
  const int steps = 360;
  const auto p = path(radius, 4.0, flutes, rho, gamma);
  const double window_from = 0.2;
  const double window_to = 2.9;
  ChipGeometry g;
  g.configure(p, pitch, 2, steps, true, window_from, window_to, disc_angles);
  ASSERT_EQ(g.discs(), 4);
  ASSERT_EQ(g.tables(), 4);
  int trochoidal = 0;
  int circular = 0;
  for (int i = 0; i < 4; ++i) {
    const double gamma_i = gamma + disc_angles[static_cast<std::size_t>(i)];
    for (int j = 0; j < flutes; ++j) {
      const double r = std::sqrt(radius * radius + rho * rho +
                                 2.0 * radius * rho * std::cos(gamma_i + pitch[j]));
      EXPECT_NEAR(g.flutes_at(i)[static_cast<std::size_t>(j)].radius_um, r, 1e-12);
    }
    PathGeometry pi = p;
    pi.offset_angle_rad = gamma_i;
    for (int j = 0; j < flutes; ++j) {
      for (int n = 1; n <= 2; ++n) {
        const int k_flute = ((j - n) % flutes + flutes) % flutes;
        const double back = pitch_back_rad(pitch, j, n);
        for (int k = 0; k < steps; k += 7) {
          const double tau = 2.0 * kPi * k / steps;
          const double theta = std::remainder(tau - pitch[j], 2.0 * kPi);
          const double table = g.at(j, n, k, i);
          if (theta > window_from && theta < window_to) {
            EXPECT_NEAR(table, chip_by_bisection(pi, tau, pitch[j], pitch[j] - back, back), 1e-9)
                << i << " " << j << " " << n << " " << k;
            ++trochoidal;
          } else if (theta < window_from - 0.05 || theta > window_to + 0.05) {
            const double rj = g.flutes_at(i)[static_cast<std::size_t>(j)].radius_um;
            const double rk = g.flutes_at(i)[static_cast<std::size_t>(k_flute)].radius_um;
            EXPECT_NEAR(table, p.feed_per_rad_um * back * std::sin(theta) + rj - rk, 1e-12);
            ++circular;
          }
        }
      }
    }
  }
  EXPECT_GT(trochoidal, 500);
  EXPECT_GT(circular, 200);

  // Without runout every disc's geometry is the same: one table serves them all.
  g.configure(path(radius, 4.0, flutes), pitch, 2, steps, true, window_from, window_to,
              disc_angles);
  EXPECT_EQ(g.tables(), 1);
  EXPECT_EQ(g.row(1, 2, 3), g.row(1, 2, 0));
  // Without disc angles (the tip's pattern, [000] eqs 1-2): one table at γ for every disc.
  ChipGeometry tip;
  tip.configure(p, pitch, 2, steps, true, window_from, window_to);
  EXPECT_EQ(tip.tables(), 1);
  EXPECT_NEAR(tip.flutes_at()[0].radius_um,
              std::sqrt(radius * radius + rho * rho + 2.0 * radius * rho * std::cos(gamma)), 1e-12);
  // One disc with helix has one table, at γ plus that disc's angle.
  ChipGeometry one;
  const std::vector<double> one_angle = {0.3};
  one.configure(p, pitch, 2, steps, true, window_from, window_to, one_angle);
  EXPECT_EQ(one.tables(), 1);
  EXPECT_NEAR(one.flutes_at(0)[0].radius_um,
              std::sqrt(radius * radius + rho * rho + 2.0 * radius * rho * std::cos(gamma + 0.3)),
              1e-12);
}

TEST(ChipGeometry, InterpolationBetweenGridStepsIsLinearAndWraps) {
  const auto pitch = uniform_pitch(2);
  ChipGeometry g;
  g.configure(path(200.0, 4.0, 2), pitch, 2, 720, true);
  EXPECT_NEAR(g.chip_um(0, 1, 10.25), 0.75 * g.at(0, 1, 10) + 0.25 * g.at(0, 1, 11), 1e-12);
  EXPECT_NEAR(g.chip_um(0, 1, -0.5), 0.5 * g.at(0, 1, 719) + 0.5 * g.at(0, 1, 0), 1e-12);
}

TEST(ChipGeometry, PitchBackSumsIntervalsForUnequalPitch) {
  const std::vector<double> pitch = {0.0, 170.0 * kPi / 180.0};
  EXPECT_NEAR(pitch_back_rad(pitch, 1, 1), 170.0 * kPi / 180.0, 1e-12);
  EXPECT_NEAR(pitch_back_rad(pitch, 0, 1), 190.0 * kPi / 180.0, 1e-12);
  EXPECT_NEAR(pitch_back_rad(pitch, 0, 2), 2.0 * kPi, 1e-12);
}

}  // namespace
}  // namespace millwatch::model
