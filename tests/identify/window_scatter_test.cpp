// The windows' agreement on the runout against the σ each window states (WindowScatter): the
// scatter of windows drawn with a known spread is found, a window stating a σ smaller than that
// is widened to it, and one stating more is left as it is.

#include "core/identify/window_scatter.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

namespace millwatch::identify {
namespace {

/// A fitted two-flute window: ρ, γ and r_CE2 − r_CE1 with the σ it states.
FitResult window(double rho_um, double gamma_rad, double radius_difference_um, double sigma) {
  FitResult f;
  f.ok = true;
  f.rho_um = {"rho_um", rho_um, sigma, sigma, 0.0};
  f.gamma_rad = {"gamma_rad", gamma_rad, sigma, sigma, 0.0};
  f.radius_from_ce1_um = {{"r_ce1", 0.0, 0.0, 0.0, 0.0},
                          {"r_ce2", radius_difference_um, sigma, sigma, 0.0}};
  f.cutting_radius_um = {{"r_ce1", 200.0, sigma, sigma, 0.0},
                         {"r_ce2", 200.0 + radius_difference_um, sigma, sigma, 0.0}};
  return f;
}

// 60 windows whose ρ scatters by 0.3 µm and γ by 0.2 rad about a level that drifts slowly (the
// scatter of successive differences is blind to it, and the drift, 0.12 µm over the record, is
// within the quarters' sampling error), each stating σ 0.02: the scatter is found
// within its sampling error (MAD of 59 differences: ~13 %), and the last window's σ's are widened
// to it; with each window stating 1.0, nothing is widened.
TEST(WindowScatter, FindsTheWindowsSpreadAndWidensASmallerSigma) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  WindowScatter small, large;
  FitResult last_small, last_large;
  for (int i = 0; i < 60; ++i) {
    const double rho = 2.0 + 0.002 * i + 0.3 * normal(rng);
    const double gamma = 3.1 + 0.2 * normal(rng);  // across ±π: unwrapped
    const double difference = -1.5 + 0.05 * normal(rng);
    last_small = window(rho, std::remainder(gamma, 2.0 * std::numbers::pi), difference, 0.02);
    last_large = window(rho, std::remainder(gamma, 2.0 * std::numbers::pi), difference, 1.0);
    small.add(last_small);
    large.add(last_large);
  }
  const WindowScatter::Scatter s = small.scatter();
  EXPECT_EQ(s.windows, 60);
  EXPECT_NEAR(s.rho_um, 0.3, 0.3 * 0.3);
  EXPECT_NEAR(s.gamma_rad, 0.2, 0.2 * 0.3);
  EXPECT_NEAR(s.radius_from_ce1_um[1], 0.05, 0.05 * 0.3);
  EXPECT_EQ(s.radius_from_ce1_um[0], 0.0);
  EXPECT_FALSE(s.rho_drifts);
  WindowScatter::Widening how;
  const FitResult w = small.widened(last_small, how);
  EXPECT_TRUE(how.by_scatter);
  EXPECT_FALSE(how.by_drift);
  EXPECT_EQ(w.rho_um.sigma, s.rho_um);
  EXPECT_EQ(w.gamma_rad.sigma, s.gamma_rad);
  EXPECT_EQ(w.radius_from_ce1_um[1].sigma, s.radius_from_ce1_um[1]);
  EXPECT_EQ(w.cutting_radius_um[1].sigma, s.radius_from_ce1_um[1]);
  EXPECT_EQ(w.rho_um.value, last_small.rho_um.value);  // values untouched
  EXPECT_EQ(w.rho_um.sigma_stat, 0.02);                // the window's own σ kept apart
  const FitResult unchanged = large.widened(last_large, how);
  EXPECT_FALSE(how.by_scatter);
  EXPECT_EQ(unchanged.rho_um.sigma, 1.0);
  EXPECT_EQ(unchanged.gamma_rad.sigma, 1.0);
}

// Below four windows no scatter is stated; failed fits are not windows; another flute count
// starts the record again; only the newest kWindows count.
TEST(WindowScatter, StatesNothingWithoutEnoughWindowsOfOneTool) {
  WindowScatter w;
  for (int i = 0; i < 3; ++i) {
    w.add(window(2.0 + 0.5 * i, 0.1, -1.0, 0.01));
  }
  FitResult failed = window(50.0, 0.0, 0.0, 0.01);
  failed.ok = false;
  w.add(failed);
  EXPECT_EQ(w.windows(), 3);
  EXPECT_EQ(w.scatter().rho_um, 0.0);
  WindowScatter::Widening how{true, true};
  EXPECT_EQ(w.widened(window(2.0, 0.1, -1.0, 0.01), how).rho_um.sigma, 0.01);
  EXPECT_FALSE(how.by_scatter || how.by_drift);
  FitResult three = window(2.0, 0.1, -1.0, 0.01);
  three.radius_from_ce1_um.push_back({"r_ce3", -0.5, 0.01, 0.01, 0.0});
  w.add(three);
  EXPECT_EQ(w.windows(), 1);
  for (int i = 0; i < 100; ++i) {
    w.add(three);
  }
  EXPECT_EQ(w.windows(), static_cast<int>(WindowScatter::kWindows));
  EXPECT_EQ(w.scatter().rho_um, 0.0);  // identical windows
}

/// Windows of a two-flute cut whose runout (u, v) moves from `from` to `to` over `n` windows:
/// r_CE2 − r_CE1 = −2u as the force pins it (σ 0.01 µm of scatter), ρ and γ as fitted (ρ
/// scattering by 0.05 µm), each window stating σ 0.2 µm.
WindowScatter windows_moving(std::array<double, 2> from, std::array<double, 2> to, int n,
                             FitResult& last) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> normal(0.0, 1.0);
  WindowScatter w;
  for (int i = 0; i < n; ++i) {
    const double f = static_cast<double>(i) / (n - 1);
    const double u = from[0] + f * (to[0] - from[0]), v = from[1] + f * (to[1] - from[1]);
    last = window(std::hypot(u, v) + 0.05 * normal(rng), std::atan2(v, u),
                  -2.0 * u + 0.01 * normal(rng), 0.2);
    w.add(last);
  }
  return w;
}

// ρ·sin γ drifting while the radii hold (what unmodelled flank wear did to a 2-flute slot: ρ
// 0.84 → 3.05 µm for a runout of 0.8 µm, r_CE1 − r_CE2 within 0.04 µm, the last window ± 0.22):
// the drift is found (the quarters' medians 3/4 of the way apart) and the last window's σ of ρ
// and γ are widened to it. A step of the runout that the radii see, as large, is no drift; nor
// are edge windows then others, nor a steady runout.
TEST(WindowScatter, RhoDriftingWhileTheRadiiHoldWidensItsSigma) {
  FitResult last;
  const WindowScatter drifting = windows_moving({0.7, 0.4}, {0.7, 3.0}, 48, last);
  const WindowScatter::Scatter s = drifting.scatter();
  const double total_um = std::hypot(0.7, 3.0) - std::hypot(0.7, 0.4);
  std::printf("drift %.3f um of %.3f, gamma %.1f deg, radii %.3f um\n", s.rho_drift_um, total_um,
              s.gamma_drift_rad * 180 / std::numbers::pi, s.radius_drift_um);
  EXPECT_TRUE(s.rho_drifts);
  EXPECT_NEAR(s.rho_drift_um, 0.75 * total_um, 0.1 * total_um);
  EXPECT_LT(s.radius_drift_um, 0.03);
  WindowScatter::Widening how;
  const FitResult w = drifting.widened(last, how);
  EXPECT_TRUE(how.by_drift);
  EXPECT_EQ(w.rho_um.sigma, std::fabs(s.rho_drift_um));
  EXPECT_GT(w.gamma_rad.sigma, 0.5);  // γ turned by about 40°
  EXPECT_LT(std::fabs(w.rho_um.value - std::hypot(0.7, 0.4)), 2.0 * w.rho_um.sigma);
  EXPECT_EQ(w.rho_um.value, last.rho_um.value);

  const WindowScatter stepped = windows_moving({0.7, 0.4}, {1.9, 0.4}, 48, last);
  EXPECT_GT(stepped.scatter().radius_drift_um, 1.5);
  EXPECT_FALSE(stepped.scatter().rho_drifts);
  // Windows on a contact edge (ρ stated as the radii's bound) then off it: no drift either.
  WindowScatter mixed;
  for (int i = 0; i < 48; ++i) {
    FitResult w2 = window(i < 24 ? 0.7 : 2.0, 0.0, -1.4, 0.05);
    w2.runout_at_contact_edge = i < 24;
    mixed.add(w2);
  }
  EXPECT_FALSE(mixed.scatter().rho_drifts);
  const WindowScatter steady = windows_moving({0.7, 0.4}, {0.7, 0.4}, 48, last);
  EXPECT_FALSE(steady.scatter().rho_drifts);
  EXPECT_EQ(steady.widened(last, how).rho_um.sigma, 0.2);
  EXPECT_FALSE(how.by_drift);
}

}  // namespace
}  // namespace millwatch::identify
