// The windows' agreement on the runout against the σ each window states (WindowScatter): the
// scatter of windows drawn with a known spread is found, a window stating a σ smaller than that
// is widened to it, and one stating more is left as it is.

#include "core/identify/window_scatter.hpp"

#include <gtest/gtest.h>

#include <cmath>
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
// scatter of successive differences is blind to it), each stating σ 0.02: the scatter is found
// within its sampling error (MAD of 59 differences: ~13 %), and the last window's σ's are widened
// to it; with each window stating 1.0, nothing is widened.
TEST(WindowScatter, FindsTheWindowsSpreadAndWidensASmallerSigma) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  WindowScatter small, large;
  FitResult last_small, last_large;
  for (int i = 0; i < 60; ++i) {
    const double rho = 2.0 + 0.01 * i + 0.3 * normal(rng);
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
  bool widened = false;
  const FitResult w = small.widened(last_small, widened);
  EXPECT_TRUE(widened);
  EXPECT_EQ(w.rho_um.sigma, s.rho_um);
  EXPECT_EQ(w.gamma_rad.sigma, s.gamma_rad);
  EXPECT_EQ(w.radius_from_ce1_um[1].sigma, s.radius_from_ce1_um[1]);
  EXPECT_EQ(w.cutting_radius_um[1].sigma, s.radius_from_ce1_um[1]);
  EXPECT_EQ(w.rho_um.value, last_small.rho_um.value);  // values untouched
  EXPECT_EQ(w.rho_um.sigma_stat, 0.02);                // the window's own σ kept apart
  const FitResult unchanged = large.widened(last_large, widened);
  EXPECT_FALSE(widened);
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
  bool widened = true;
  EXPECT_EQ(w.widened(window(2.0, 0.1, -1.0, 0.01), widened).rho_um.sigma, 0.01);
  EXPECT_FALSE(widened);
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

}  // namespace
}  // namespace millwatch::identify
