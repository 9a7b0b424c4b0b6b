#include "core/model/runout_geometry.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include "core/model/flute_positions.hpp"
#include "core/model/model_config.hpp"

namespace millwatch::model {
namespace {

constexpr double kPi = std::numbers::pi;

double rad(double deg) {
  return deg * kPi / 180.0;
}
double deg(double rad) {
  return rad * 180.0 / kPi;
}

/// Truncation to `decimals` places (how [003] Table 4 seems to print α).
double truncated(double x, int decimals) {
  const double scale = std::pow(10.0, decimals);
  return std::floor(x * scale) / scale;
}

// ---------------------------------------------------------------------------------------------
// [001] Table 7: r0 and γ from d = 0.789 mm, α of Table A1 (degrees, 2 decimals) and the
// experimental r_CE1 of Table 8 (5 decimals; Table 6 prints the same to 4).
// ---------------------------------------------------------------------------------------------

struct Table7Row {
  int test;
  double alpha_deg;   // Table A1
  double r_ce1_mm;    // Table 8, "Experimental r_CE1"
  double r0_mm;       // Table 7
  double gamma_rad;   // Table 7
  double a_table_a3;  // Table A3 column a = sin²α, 5 decimals
};

constexpr double kAbeniDiameterMm = 0.789;  // [001] Table 3, effective diameter

constexpr std::array<Table7Row, 14> kTable7 = {{
    {1, 179.87, 0.38018, 0.014, 0.032, 0.00001},
    {2, 177.96, 0.38777, 0.010, 0.803, 0.00127},
    {3, 179.34, 0.39082, 0.004, 0.552, 0.00013},
    {4, 179.33, 0.39078, 0.004, 0.557, 0.00014},
    {5, 178.65, 0.38308, 0.012, 0.385, 0.00056},
    {6, 176.73, 0.38961, 0.012, 1.149, 0.00326},
    {7, 179.87, 0.38651, 0.008, 0.057, 0.00001},
    {8, 176.74, 0.39800, 0.012, 1.281, 0.00323},
    {9, 178.09, 0.39479, 0.007, 1.535, 0.00111},
    {10, 178.78, 0.39397, 0.004, 1.440, 0.00045},
    {11, 179.74, 0.40104, 0.007, 0.136, 0.00002},
    {12, 175.79, 0.39145, 0.015, 1.346, 0.00540},
    {13, 177.82, 0.39754, 0.008, 1.195, 0.00145},
    {14, 177.42, 0.39983, 0.010, 1.038, 0.00202},
}};

// Half a unit in the last printed place, plus a hair for binary representation.
constexpr double kHalf3 = 0.0005 + 1e-12;
constexpr double kHalf5 = 0.000005 + 1e-12;

RunoutTriangle table7_triangle(const Table7Row& row, double alpha_shift_deg = 0.0) {
  return runout_from_edge_radius(kAbeniDiameterMm, rad(row.alpha_deg + alpha_shift_deg),
                                 row.r_ce1_mm);
}

// r0 reproduces for every test directly (it hardly depends on α's last digit).
TEST(RunoutGeometry, Abeni2024Table7RunoutLengthForAllTests) {
  for (const auto& row : kTable7) {
    EXPECT_NEAR(table7_triangle(row).r0_mm, row.r0_mm, kHalf3) << "test " << row.test;
  }
}

// γ as printed is the folded arcsin(r_CE1·sin β / r0). Eight rows reproduce from the printed α
// directly. Six do not: γ is sensitive to α (tests 1 and 7: π − α = 0.13°, so α's ±0.005°
// rounding is ±4 % of γ), and the authors evaluated α before rounding it for Table A1 — the
// formula gives the values below, each within the range α ± 0.005° spans (checked next), and
// Abeni2024Tables7AndA3AgreeOnOneAlphaPerTest finds one α per test that fits Table 7 and
// Table A3 together.
TEST(RunoutGeometry, Abeni2024Table7GammaAsPrinted) {
  struct Off {
    int test;
    double formula_rad;  // what the printed α gives, 4 decimals
  };
  const std::array<Off, 6> off = {
      {{1, 0.0312}, {2, 0.8019}, {4, 0.5542}, {7, 0.0559}, {13, 1.1941}, {14, 1.0385}}};
  for (const auto& row : kTable7) {
    const double gamma = table7_triangle(row).gamma_table_rad;
    const auto it =
        std::find_if(off.begin(), off.end(), [&](const Off& o) { return o.test == row.test; });
    if (it == off.end()) {
      EXPECT_NEAR(gamma, row.gamma_rad, kHalf3) << "test " << row.test;
    } else {
      EXPECT_NEAR(gamma, it->formula_rad, 0.00005 + 1e-12) << "test " << row.test;
      EXPECT_GT(std::fabs(gamma - row.gamma_rad), kHalf3) << "test " << row.test;
    }
  }
}

// Every printed γ lies in the range that α's printed rounding (±0.005°) and r_CE1's (±0.000005)
// span, widened by γ's own rounding.
TEST(RunoutGeometry, Abeni2024Table7GammaWithinTheInputsRounding) {
  for (const auto& row : kTable7) {
    double lo = 10.0;
    double hi = -10.0;
    for (int k = -10; k <= 10; ++k) {
      for (double dr : {-0.000005, 0.0, 0.000005}) {
        const double g = runout_from_edge_radius(kAbeniDiameterMm, rad(row.alpha_deg + k * 0.0005),
                                                 row.r_ce1_mm + dr)
                             .gamma_table_rad;
        lo = std::min(lo, g);
        hi = std::max(hi, g);
      }
    }
    EXPECT_LE(lo, row.gamma_rad + kHalf3) << "test " << row.test;
    EXPECT_GE(hi, row.gamma_rad - kHalf3) << "test " << row.test;
  }
}

// The same unrounded α explains Table 7 and Table A3's a = sin²α (whose tests 6, 12 and 14 do
// not reproduce from the printed α either: sin²(176.73°) = 0.003254 prints 0.00325, not 0.00326).
// For every test one α within the printed ±0.005° gives r0, γ (Table 7) and a (Table A3) as
// printed, all at once.
TEST(RunoutGeometry, Abeni2024Tables7AndA3AgreeOnOneAlphaPerTest) {
  for (const auto& row : kTable7) {
    bool found = false;
    for (int k = -500; k <= 500 && !found; ++k) {
      const double shift = k * 1e-5;
      const auto t = table7_triangle(row, shift);
      const double s = std::sin(rad(row.alpha_deg + shift));
      found = std::fabs(t.r0_mm - row.r0_mm) <= kHalf3 &&
              std::fabs(t.gamma_table_rad - row.gamma_rad) <= kHalf3 &&
              std::fabs(s * s - row.a_table_a3) <= kHalf5;
    }
    EXPECT_TRUE(found) << "test " << row.test;
  }
}

// The tables' γ is γ_eq1 folded into [0, π/2]: it equals arcsin(r_CE1·sin β / r0), and where
// γ_eq1 > π/2 (r_CE1² < (d/2)² + r0², tests with r_CE1 below d/2) it does not satisfy eq 1,
// while γ_eq1 does.
TEST(RunoutGeometry, Abeni2024Table7GammaIsEq1GammaFolded) {
  int folded = 0;
  for (const auto& row : kTable7) {
    const auto t = table7_triangle(row);
    EXPECT_NEAR(t.gamma_table_rad, std::asin(row.r_ce1_mm * std::sin(t.beta_rad) / t.r0_mm), 1e-9)
        << "test " << row.test;
    EXPECT_NEAR(r_ce1_from_offset_mm(kAbeniDiameterMm, t.r0_mm, t.gamma_eq1_rad), row.r_ce1_mm,
                1e-12)
        << "test " << row.test;
    const double radius = 0.5 * kAbeniDiameterMm;
    if (row.r_ce1_mm * row.r_ce1_mm < radius * radius + t.r0_mm * t.r0_mm) {
      ++folded;
      EXPECT_GT(t.gamma_eq1_rad, 0.5 * kPi) << "test " << row.test;
      EXPECT_NEAR(t.gamma_table_rad, kPi - t.gamma_eq1_rad, 1e-15) << "test " << row.test;
      EXPECT_GT(std::fabs(r_ce1_from_offset_mm(kAbeniDiameterMm, t.r0_mm, t.gamma_table_rad) -
                          row.r_ce1_mm),
                1e-4)
          << "test " << row.test;
    } else {
      EXPECT_NEAR(t.gamma_table_rad, t.gamma_eq1_rad, 1e-15) << "test " << row.test;
    }
  }
  EXPECT_EQ(folded, 9);  // tests 1-7, 10, 12
}

// ---------------------------------------------------------------------------------------------
// [003] Table 5: d = 0.782 mm, r_CE1 = d/2 + Δr ([003] eq 6, printed `Δrr`), α from Table 4.
// Lengths printed in µm, γ in degrees. Table 4's α look truncated to 3 decimals
// (physics-notes), so the true α lies in [α, α + 0.001°).
// ---------------------------------------------------------------------------------------------

constexpr double kAttanasioDiameterMm = 0.782;

double attanasio_r_ce1_mm(double delta_r_um) {
  return 0.5 * kAttanasioDiameterMm + delta_r_um / 1000.0;  // [003] eq 6
}

// Test 1 (α = 178.311°, Δr = 2 µm): r0 = 6.0868 µm prints 6.087. γ = 71.238° prints 71.23 only
// truncated (like Table 4's α); within α's truncation interval γ spans (71.227, 71.238], which
// holds 71.23, but there no α rounds r0 to 6.087 and γ to 71.23 together (r0 ≥ 6.0865 needs
// α ≤ 178.3111°, γ < 71.235 needs α ≥ 178.3113°), so γ was truncated. r_CE2 = 389.085 µm
// for the whole interval: the printed 389.06 is a slip — it is what r_CE1 = 393 µm gives at
// test 2's α = 178.600° (389.058), a likely origin.
TEST(RunoutGeometry, Attanasio2018Table5Test1) {
  const double r_ce1 = attanasio_r_ce1_mm(2.0);
  EXPECT_NEAR(r_ce1 * 1000.0, 393.00, 1e-9);
  const auto t = runout_from_edge_radius(kAttanasioDiameterMm, rad(178.311), r_ce1);
  EXPECT_NEAR(t.r0_mm * 1000.0, 6.087, 0.0005);
  EXPECT_NEAR(deg(t.gamma_table_rad), 71.238, 0.0005);
  EXPECT_DOUBLE_EQ(truncated(deg(t.gamma_table_rad), 2), 71.23);
  for (int k = 0; k < 1000; ++k) {
    const double alpha_deg = 178.311 + k * 1e-6;
    const auto u = runout_from_edge_radius(kAttanasioDiameterMm, rad(alpha_deg), r_ce1);
    EXPECT_NEAR(u.r_ce2_mm * 1000.0, 389.085, 0.001) << alpha_deg;
    const bool r0_as_printed = std::fabs(u.r0_mm * 1000.0 - 6.087) <= 0.0005;
    const bool gamma_as_printed = std::fabs(deg(u.gamma_table_rad) - 71.23) <= 0.005;
    EXPECT_FALSE(r0_as_printed && gamma_as_printed) << alpha_deg;
  }
  const auto slip = runout_from_edge_radius(kAttanasioDiameterMm, rad(178.600), r_ce1);
  EXPECT_NEAR(slip.r_ce2_mm * 1000.0, 389.06, 0.005);
}

// Test 3 (α = 179.986°, Δr = 2 µm): r_CE2 = 389.00 µm reproduces. γ is hypersensitive
// (π − α = 0.014°, dγ/dα ≈ −98): α = 179.986° exactly gives γ = 1.368° and r0 = 2.0006 µm, but
// inside the truncation interval α ≈ 179.98695° gives both printed values, 2.000 and 1.275.
TEST(RunoutGeometry, Attanasio2018Table5Test3) {
  const double r_ce1 = attanasio_r_ce1_mm(2.0);
  const auto t = runout_from_edge_radius(kAttanasioDiameterMm, rad(179.986), r_ce1);
  EXPECT_NEAR(t.r_ce2_mm * 1000.0, 389.00, 0.005);
  EXPECT_NEAR(deg(t.gamma_table_rad), 1.368, 0.0005);
  EXPECT_NEAR(t.r0_mm * 1000.0, 2.0006, 0.00005);
  int matching = 0;
  for (int k = 0; k < 1000; ++k) {
    const double alpha_deg = 179.986 + k * 1e-6;
    const auto u = runout_from_edge_radius(kAttanasioDiameterMm, rad(alpha_deg), r_ce1);
    EXPECT_NEAR(u.r_ce2_mm * 1000.0, 389.00, 0.005);
    if (std::fabs(u.r0_mm * 1000.0 - 2.000) <= 0.0005 &&
        std::fabs(deg(u.gamma_table_rad) - 1.275) <= 0.0005) {
      ++matching;
      EXPECT_NEAR(alpha_deg, 179.98695, 0.00001);
    }
  }
  EXPECT_GT(matching, 0);
}

// Test 2: the authors set runout to zero by choice (Δr = 0 selected by [003] eq 14, simulated
// without runout), although α = 178.600° ≠ 180°. The printed column (r_CE1 = r_CE2 = 391.00,
// r0 = 0, γ = 0) is the r0 = 0 triangle, whose α is 180°; the geometry with the measured α and
// r_CE1 = d/2 would give r0 = 4.777 µm and γ = 89.65°.
TEST(RunoutGeometry, Attanasio2018Table5Test2IsZeroRunoutByChoice) {
  const auto chosen = runout_from_offset(kAttanasioDiameterMm, 0.0, 0.0);
  EXPECT_NEAR(chosen.r_ce1_mm * 1000.0, 391.00, 1e-9);
  EXPECT_NEAR(chosen.r_ce2_mm * 1000.0, 391.00, 1e-9);
  EXPECT_DOUBLE_EQ(chosen.alpha_rad, kPi);
  const auto measured =
      runout_from_edge_radius(kAttanasioDiameterMm, rad(178.600), attanasio_r_ce1_mm(0.0));
  EXPECT_NEAR(measured.r0_mm * 1000.0, 4.777, 0.0005);
  EXPECT_NEAR(measured.r_ce2_mm * 1000.0, 391.058, 0.0005);
  EXPECT_NEAR(deg(measured.gamma_table_rad), 89.65, 0.005);
}

// ---------------------------------------------------------------------------------------------
// The geometry itself: both directions against an explicit construction, and round trips.
// ---------------------------------------------------------------------------------------------

struct Point {
  double x, y;
};
double norm(Point p) {
  return std::hypot(p.x, p.y);
}
/// Unsigned angle between two vectors.
double angle_between(Point u, Point v) {
  return std::atan2(std::fabs(u.x * v.y - u.y * v.x), u.x * v.x + u.y * v.y);
}

// O at the origin, O' = (r0, 0), A = O' + (d/2)·(cos γ, sin γ), B = O' − (A − O'): the
// triangle's sides and angles measured on the points.
TEST(RunoutGeometry, MatchesAnExplicitConstruction) {
  const double d = 0.8;
  for (double r0 : {0.0005, 0.004, 0.03, 0.2}) {
    for (double gamma : {0.0, 0.2, 1.0, 0.5 * kPi, 2.0, 3.0, kPi}) {
      const Point a{r0 + 0.5 * d * std::cos(gamma), 0.5 * d * std::sin(gamma)};
      const Point b{r0 - 0.5 * d * std::cos(gamma), -0.5 * d * std::sin(gamma)};
      const Point o_to_centre{r0, 0.0};
      const Point centre_to_a{a.x - r0, a.y};
      const Point ab{b.x - a.x, b.y - a.y};
      const double alpha = angle_between(a, b);
      const double beta = angle_between({-a.x, -a.y}, ab);
      const double delta = angle_between({-b.x, -b.y}, {-ab.x, -ab.y});
      ASSERT_NEAR(angle_between(o_to_centre, centre_to_a), gamma, 1e-12);

      const auto t = runout_from_offset(d, r0, gamma);
      EXPECT_NEAR(t.r_ce1_mm, norm(a), 1e-14) << r0 << " " << gamma;
      EXPECT_NEAR(t.r_ce2_mm, norm(b), 1e-14) << r0 << " " << gamma;
      EXPECT_NEAR(t.alpha_rad, alpha, 1e-13) << r0 << " " << gamma;
      EXPECT_NEAR(t.beta_rad, beta, 1e-13) << r0 << " " << gamma;
      EXPECT_NEAR(t.delta_rad, delta, 1e-13) << r0 << " " << gamma;
      EXPECT_NEAR(r_ce1_from_offset_mm(d, r0, gamma), norm(a), 1e-14);

      const auto f = runout_from_edge_radius(d, alpha, norm(a));
      EXPECT_NEAR(f.r_ce2_mm, norm(b), 1e-13) << r0 << " " << gamma;
      EXPECT_NEAR(f.r0_mm, r0, 1e-12) << r0 << " " << gamma;
      EXPECT_NEAR(f.beta_rad, beta, 1e-12) << r0 << " " << gamma;
      EXPECT_NEAR(f.delta_rad, delta, 1e-12) << r0 << " " << gamma;
      if (gamma > 0.0 && gamma < kPi) {  // at 0 and π the triangle is flat and γ is 0 or π
        EXPECT_NEAR(f.gamma_eq1_rad, gamma, 1e-9) << r0 << " " << gamma;
      }
      EXPECT_NEAR(f.gamma_table_rad, std::min(gamma, kPi - gamma), 1e-9) << r0 << " " << gamma;
    }
  }
}

// (d, α, r_CE1) → (r0, γ_eq1) → (r_CE1, r_CE2, α, β, δ) and back, across the range of α that
// micro-milling runout produces and beyond, including α = π (flat triangle).
TEST(RunoutGeometry, RoundTripFromEdgeRadius) {
  const double d = 0.789;
  for (double alpha_deg : {150.0, 170.0, 175.79, 178.0, 179.5, 179.99, 179.9999, 180.0}) {
    for (double r_ce1 : {0.37, 0.3940, 0.3945, 0.3950, 0.41}) {
      const auto t = runout_from_edge_radius(d, rad(alpha_deg), r_ce1);
      if (t.r0_mm >= 0.5 * d) {
        continue;
      }
      const auto back = runout_from_offset(d, t.r0_mm, t.gamma_eq1_rad);
      EXPECT_NEAR(back.r_ce1_mm, r_ce1, 1e-13) << alpha_deg << " " << r_ce1;
      EXPECT_NEAR(back.r_ce2_mm, t.r_ce2_mm, 1e-13) << alpha_deg << " " << r_ce1;
      EXPECT_NEAR(back.alpha_rad, rad(alpha_deg), 1e-12) << alpha_deg << " " << r_ce1;
      EXPECT_NEAR(back.beta_rad, t.beta_rad, 1e-12) << alpha_deg << " " << r_ce1;
      EXPECT_NEAR(back.delta_rad, t.delta_rad, 1e-12) << alpha_deg << " " << r_ce1;
      EXPECT_NEAR(back.gamma_table_rad, t.gamma_table_rad, 1e-12);
    }
  }
}

TEST(RunoutGeometry, RoundTripFromOffset) {
  const double d = 0.4;
  for (double r0 : {0.0, 1e-6, 1.82e-3, 0.01, 0.1}) {
    for (double gamma : {0.0, 0.58, 1.2, 0.5 * kPi, 2.4, 3.1, kPi}) {
      const auto t = runout_from_offset(d, r0, gamma);
      const auto back = runout_from_edge_radius(d, t.alpha_rad, t.r_ce1_mm);
      EXPECT_NEAR(back.r0_mm, r0, 1e-13) << r0 << " " << gamma;
      EXPECT_NEAR(back.r_ce2_mm, t.r_ce2_mm, 1e-13) << r0 << " " << gamma;
      if (r0 > 0.0 && gamma > 0.0 && gamma < kPi) {
        EXPECT_NEAR(back.gamma_eq1_rad, gamma, 1e-9) << r0 << " " << gamma;
      }
    }
  }
}

TEST(RunoutGeometry, RejectsImpossibleTriangles) {
  EXPECT_THROW(runout_from_edge_radius(0.0, 3.0, 0.4), std::invalid_argument);
  EXPECT_THROW(runout_from_edge_radius(0.8, 0.0, 0.4), std::invalid_argument);
  EXPECT_THROW(runout_from_edge_radius(0.8, 3.5, 0.4), std::invalid_argument);
  EXPECT_THROW(runout_from_edge_radius(0.8, 3.0, -0.4), std::invalid_argument);
  EXPECT_THROW(runout_from_edge_radius(0.8, 3.0, 2.0), std::invalid_argument);  // α + δ > π
  EXPECT_THROW(runout_from_offset(0.8, 0.4, 1.0), std::invalid_argument);       // r0 ≥ d/2
  EXPECT_THROW(runout_from_offset(0.8, 0.01, -0.1), std::invalid_argument);
  EXPECT_THROW(runout_from_offset(0.8, 0.01, 3.2), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// The model's runout parameters: ρ = r0, γ_model = ∓γ_eq1.
// ---------------------------------------------------------------------------------------------

std::vector<double> two_flute_pitch_rad(double diameter_mm) {
  Tool tool;
  tool.diameter_mm = diameter_mm;
  tool.flutes = 2;
  return flute_pitch_angles_rad(tool);
}

// For several (r0, γ) the model's flute_positions() puts flute 0 at r_CE1 and flute 1 at r_CE2,
// and with γ_model = −γ_eq1 flute 1 follows flute 0 by α (< π); with γ_model = +γ_eq1 (the
// papers' order) flute 0 follows flute 1 by α.
TEST(RunoutGeometry, ModelFlutePositionsReproduceTheTriangle) {
  const double d = 0.789;
  const auto pitch = two_flute_pitch_rad(d);
  ASSERT_EQ(pitch.size(), 2U);
  ASSERT_NEAR(pitch[1], kPi, 1e-15);
  const double radius_um = d * 500.0;
  int cases = 0;
  for (double r0_um : {0.5, 1.82, 4.0, 12.0, 15.0}) {
    for (double gamma : {0.03, 0.58, 1.28, 0.5 * kPi, 2.0, 3.11}) {
      const auto t = runout_from_offset(d, r0_um / 1000.0, gamma);
      ASSERT_LT(t.alpha_rad, kPi);

      const auto m = model_runout_from_triangle(t);  // default: CE2 trails by α
      EXPECT_DOUBLE_EQ(m.offset_um, r0_um);
      EXPECT_DOUBLE_EQ(m.angle_rad, -gamma);
      const auto flutes = flute_positions(radius_um, pitch, m.offset_um, m.angle_rad);
      EXPECT_NEAR(flutes[0].radius_um, t.r_ce1_mm * 1000.0, 1e-10) << r0_um << " " << gamma;
      EXPECT_NEAR(flutes[1].radius_um, t.r_ce2_mm * 1000.0, 1e-10) << r0_um << " " << gamma;
      EXPECT_NEAR(flute_spacing_rad(pitch, flutes, 0, 1), t.alpha_rad, 1e-12)
          << r0_um << " " << gamma;

      const auto p = model_runout_from_triangle(t, EdgeOrder::kCe1TrailsByAlpha);
      EXPECT_DOUBLE_EQ(p.angle_rad, gamma);
      const auto mirrored = flute_positions(radius_um, pitch, p.offset_um, p.angle_rad);
      EXPECT_NEAR(mirrored[0].radius_um, t.r_ce1_mm * 1000.0, 1e-10);
      EXPECT_NEAR(mirrored[1].radius_um, t.r_ce2_mm * 1000.0, 1e-10);
      EXPECT_NEAR(flute_spacing_rad(pitch, mirrored, 1, 0), t.alpha_rad, 1e-12);
      EXPECT_NEAR(flute_spacing_rad(pitch, mirrored, 0, 1), 2.0 * kPi - t.alpha_rad, 1e-12);
      ++cases;
    }
  }
  EXPECT_EQ(cases, 30);
}

// The same for [001] Table 7's runout: r_CE1 of Table 8, α of Table A1 → (ρ, γ_model) → the
// model's flutes sit at r_CE1 and r_CE2 with spacing α.
TEST(RunoutGeometry, ModelReproducesAbeni2024Runouts) {
  const auto pitch = two_flute_pitch_rad(kAbeniDiameterMm);
  for (const auto& row : kTable7) {
    const auto t = table7_triangle(row);
    const auto m = model_runout_from_triangle(t);
    const auto flutes = flute_positions(kAbeniDiameterMm * 500.0, pitch, m.offset_um, m.angle_rad);
    EXPECT_NEAR(flutes[0].radius_um, row.r_ce1_mm * 1000.0, 1e-9) << "test " << row.test;
    EXPECT_NEAR(flutes[1].radius_um, t.r_ce2_mm * 1000.0, 1e-9) << "test " << row.test;
    EXPECT_NEAR(flute_spacing_rad(pitch, flutes, 0, 1), rad(row.alpha_deg), 1e-12)
        << "test " << row.test;
  }
}

// Any γ_model: its wrap into [−π, π] has the sign that orders the edges, and reading the model
// back gives the triangle its flutes show.
TEST(RunoutGeometry, TriangleFromModelRunoutInvertsTheMapping) {
  const double d = 0.4;
  const auto pitch = two_flute_pitch_rad(d);
  for (double angle : {-6.0, -3.0, -1.0, -0.2, 0.0, 0.58, 0.88, 2.5, 4.0, 6.2}) {
    const double offset_um = 1.82;
    const auto back = triangle_from_model_runout(d, offset_um, angle);
    const auto flutes = flute_positions(d * 500.0, pitch, offset_um, angle);
    EXPECT_NEAR(back.triangle.r_ce1_mm * 1000.0, flutes[0].radius_um, 1e-10) << angle;
    EXPECT_NEAR(back.triangle.r_ce2_mm * 1000.0, flutes[1].radius_um, 1e-10) << angle;
    const int lead = back.order == EdgeOrder::kCe2TrailsByAlpha ? 0 : 1;
    EXPECT_NEAR(flute_spacing_rad(pitch, flutes, lead, 1 - lead), back.triangle.alpha_rad, 1e-12)
        << angle;
    EXPECT_EQ(back.order,
              std::sin(angle) > 0.0 ? EdgeOrder::kCe1TrailsByAlpha : EdgeOrder::kCe2TrailsByAlpha)
        << angle;
    const auto again = model_runout_from_triangle(back.triangle, back.order);
    EXPECT_NEAR(again.offset_um, offset_um, 1e-12);
    EXPECT_NEAR(again.angle_rad, std::remainder(angle, 2.0 * kPi), 1e-12) << angle;
  }
}

// The model's default runout ([000] condition 1: 1.82 µm at 0.58 rad on the 0.4 mm tool) read as
// a runout triangle: γ_model > 0, so flute 0 (CE1) trails flute 1 by α as in [001]'s kinematics.
TEST(RunoutGeometry, ModelDefaultRunoutAsATriangle) {
  const ModelConfig config;
  const auto back = triangle_from_model_runout(
      config.tool.diameter_mm, config.effects.runout.offset_um, config.effects.runout.angle_rad);
  EXPECT_EQ(back.order, EdgeOrder::kCe1TrailsByAlpha);
  EXPECT_NEAR(back.triangle.gamma_eq1_rad, 0.58, 1e-15);
  // r_CE1 − r_CE2 ≈ 2ρ·cos γ and π − α ≈ (2ρ/R)·sin γ for ρ ≪ R.
  EXPECT_NEAR((back.triangle.r_ce1_mm - back.triangle.r_ce2_mm) * 1000.0,
              2.0 * 1.82 * std::cos(0.58), 1e-4);
  EXPECT_NEAR(kPi - back.triangle.alpha_rad, 2.0 * 1.82 / 200.0 * std::sin(0.58), 1e-5);
}

}  // namespace
}  // namespace millwatch::model
