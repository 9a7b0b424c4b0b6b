#include "core/model/force_law.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace millwatch::model {
namespace {

// [000] eq 5 with Table 2 in mm units: at f_t = 4 µm per mm of depth the tangential force is
// K_tc·0.004^a_tc ≈ 25 N/mm, so a_p = 40 µm gives ≈ 1 N (the paper's 0.5-2 N).
TEST(ForceLaw, PowerLawUsesMillimetreUnitsOfTable2) {
  Material m;  // cp-Ti, Table 2
  const ForceLaw law(m, 0.04, 0.2, true);
  const auto f = law.element(4.0, 0.04);
  EXPECT_NEAR(f.tangential_N, 465.4 * std::pow(0.004, 0.5288) * 0.04, 1e-12);
  EXPECT_GT(f.tangential_N, 0.9);
  EXPECT_LT(f.tangential_N, 1.1);
  EXPECT_EQ(f.axial_N, 0.0);  // Table 2 has no axial coefficients
}

TEST(ForceLaw, PowerLawSwitchesRegimeAtMinimumChip) {
  Material m;
  const ForceLaw law(m, 0.04, 0.2, true);
  EXPECT_TRUE(law.ploughing(0.19));
  EXPECT_FALSE(law.ploughing(0.2));
  EXPECT_NEAR(law.element(0.19, 1.0).normal_N, 79.64 * std::pow(0.19e-3, 0.2577), 1e-12);
  EXPECT_NEAR(law.element(0.21, 1.0).normal_N, 122.8 * std::pow(0.21e-3, 0.32), 1e-12);
  const ForceLaw single(m, 0.04, 0.2, false);  // min_chip off: cutting coefficients always
  EXPECT_NEAR(single.element(0.19, 1.0).normal_N, 122.8 * std::pow(0.19e-3, 0.32), 1e-12);
}

TEST(ForceLaw, ForceScalesWithDiscThicknessAndVanishesWithoutChip) {
  Material m;
  const ForceLaw law(m, 0.04, 0.2, true);
  EXPECT_NEAR(law.element(3.0, 0.02).tangential_N * 2.0, law.element(3.0, 0.04).tangential_N,
              1e-14);
  EXPECT_EQ(law.element(0.0, 0.04).tangential_N, 0.0);
  EXPECT_EQ(law.element(-1.0, 0.04).normal_N, 0.0);
}

TEST(ForceLaw, LinearEdgeIsAffineInChip) {
  Material m;
  m.law = ForceLawKind::kLinearEdge;
  const ForceLaw law(m, 0.1, 0.0, false);
  const auto f1 = law.element(1.0, 1.0);
  const auto f3 = law.element(3.0, 1.0);
  // slope K_c (per mm of chip) and intercept K_e
  EXPECT_NEAR((f3.tangential_N - f1.tangential_N) / 2e-3, m.linear_edge.k_tc_N_per_mm2, 1e-9);
  EXPECT_NEAR(f1.tangential_N - 1e-3 * m.linear_edge.k_tc_N_per_mm2, m.linear_edge.k_te_N_per_mm,
              1e-12);
}

// [003] eqs 7-8: F_t = K_s0·S^(1 − 1/m): doubling the chip multiplies F_t by 2^(1 − 1/m).
TEST(ForceLaw, KronenbergScalesWithSectionToThePowerOneMinusInverseM) {
  Material m;
  m.law = ForceLawKind::kKronenberg;
  m.kronenberg.m = 4.0;
  const double ap = 0.15;
  const ForceLaw law(m, ap, 0.0, false);
  const double f1 = law.element(5.0, ap).tangential_N;
  const double f2 = law.element(10.0, ap).tangential_N;
  EXPECT_NEAR(f2 / f1, std::pow(2.0, 0.75), 1e-12);
  // Full-depth section S = h·a_p: F_t = K_s0·S^(1−1/m)
  EXPECT_NEAR(f1, m.kronenberg.k_s0_N_per_mm2 * std::pow(5e-3 * ap, 0.75), 1e-12);
  EXPECT_NEAR(law.element(5.0, ap).normal_N, 0.5 * f1, 1e-12);
}

TEST(ForceLaw, NormalDerivativesInLogChipMatchFiniteDifferences) {
  struct Case {
    const char* name;
    Material material;
    double area_mm2;
  };
  std::vector<Case> cases;
  Material power;  // [000] Table 2: two regimes
  cases.push_back({"power law", power, 0.0});
  Material linear;
  linear.law = ForceLawKind::kLinearEdge;
  cases.push_back({"linear edge", linear, 0.0});
  Material kronenberg;
  kronenberg.law = ForceLawKind::kKronenberg;
  cases.push_back({"kronenberg", kronenberg, 0.0});
  Material plough;  // [002] eq 17 below h_min
  plough.law = ForceLawKind::kLinearEdge;
  plough.linear_edge.a_n_Nmm = 183.3;
  plough.linear_edge.b_n = 0.5;
  cases.push_back({"linear edge, plough law", plough, 0.0});
  Material tangential_only = plough;  // F_n = 0 below h_min, whatever B_n
  tangential_only.linear_edge.a_n_Nmm = 0.0;
  tangential_only.linear_edge.a_t_Nmm = 114.7;
  cases.push_back({"linear edge, tangential plough law only", tangential_only, 0.0});
  Material area;  // [001] eqs 18-21
  area.law = ForceLawKind::kLinearEdge;
  area.linear_edge.ploughing_area = true;
  area.linear_edge.k_np_N_per_mm3 = 6000.0;
  cases.push_back({"linear edge, ploughed area", area, 2e-5});
  for (const Case& c : cases) {
    const ForceLaw law(c.material, 0.04, 0.2, true);
    // h = 0.1 µm is below h_min = 0.2 µm: the ploughing regime of the laws that have one.
    for (double h : {0.1, 0.5, 2.0, 7.0}) {
      SCOPED_TRACE(std::string(c.name) + ", h " + std::to_string(h));
      const double u = std::log(h);
      const auto s = law.normal_with_slope(h, u, 0.004, c.area_mm2);
      const auto f = [&](double x) { return law.normal_N(std::exp(x), 0.004, c.area_mm2); };
      const double d = 1e-4;
      const double d1 = (f(u + d) - f(u - d)) / (2 * d);
      const double d2 = (f(u + d) - 2 * f(u) + f(u - d)) / (d * d);
      EXPECT_NEAR(s.force_N, f(u), 1e-15);
      EXPECT_NEAR(s.d_du_N, d1, 1e-6 * std::fabs(d1) + 1e-12);
      EXPECT_NEAR(s.d2_du2_N, d2, 1e-4 * std::fabs(d2) + 1e-9);
    }
  }
}

}  // namespace
}  // namespace millwatch::model
