#include "core/model/abeni_runout.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <numbers>

#include "core/model/runout_geometry.hpp"

namespace millwatch::model {
namespace {

constexpr double kPi = std::numbers::pi;

double rad(double deg) {
  return deg * kPi / 180.0;
}

// [001]: effective diameter 0.789 mm (Table 3), v_c = 80 m/min (Table 4) with the spindle speed
// set from the nominal 0.8 mm: n = v_c/(π·0.8 mm) = 31,831 rpm, ω = 2·v_c/0.8 mm = 3333.3 rad/s.
constexpr double kDiameterMm = 0.789;
constexpr double kNominalDiameterMm = 0.8;
constexpr double kCuttingSpeedMmPerS = 80.0 * 1000.0 / 60.0;
constexpr double kSpindleRadPerS = 2.0 * kCuttingSpeedMmPerS / kNominalDiameterMm;
constexpr double kKtsNPerMm2 = 10000.0;  // [001] Sect. 3.2-3.3

struct Row {
  int test;
  double fz_mm;            // Table 6
  double feed_mm_per_min;  // Table 6
  double ap_mm;            // Table 6, measured a_p
  double delta_fy_N;       // Table A1
  double alpha_deg;        // Table A1
  // Table A3
  double i_mm, a, b_mm, c_mm2, e_mm3, g_mm4;
  // Table 8
  double r_experimental_mm, r_fourth_mm, variation_mm, error_percent;
  // Table 9
  double r_second_mm, variation_percent;
};

constexpr std::array<Row, 14> kRows = {{
    {1, 0.0010, 64, 0.2607, 0.007, 179.87, 0.00000, 0.00001, 0.0, -0.62252, 0.00000, 0.09688,
     0.38018, 0.39450, 0.01432, 3.63, 0.39450, 0.00007},
    {2, 0.0045, 286, 0.2373, 0.073, 177.96, 0.00007, 0.00127, 0.0, -0.62252, 0.00004, 0.09688,
     0.38777, 0.39460, 0.00683, 1.73, 0.39453, 0.01591},
    {3, 0.0020, 127, 0.2385, 0.080, 179.34, 0.00002, 0.00013, 0.0, -0.62252, 0.00002, 0.09688,
     0.39082, 0.39452, 0.00370, 0.94, 0.39451, 0.00166},
    {4, 0.0060, 382, 0.2502, 0.047, 179.33, 0.00003, 0.00014, 0.0, -0.62252, 0.00002, 0.09688,
     0.39078, 0.39452, 0.00374, 0.95, 0.39452, 0.00173},
    {5, 0.0025, 159, 0.2391, 0.073, 178.65, 0.00003, 0.00056, 0.0, -0.62252, 0.00002, 0.09688,
     0.38308, 0.39454, 0.01146, 2.91, 0.39452, 0.00694},
    {6, 0.0040, 255, 0.2374, 0.047, 176.73, 0.00008, 0.00326, 0.0, -0.62252, 0.00005, 0.09688,
     0.38961, 0.39470, 0.00509, 1.29, 0.39454, 0.04082},
    {7, 0.0015, 95, 0.2545, 0.047, 179.87, 0.00001, 0.00001, 0.0, -0.62252, 0.00001, 0.09688,
     0.38651, 0.39451, 0.00799, 2.03, 0.39451, 0.00007},
    {8, 0.0030, 191, 0.2590, 0.113, 176.74, 0.00008, 0.00323, 0.0, -0.62252, 0.00005, 0.09688,
     0.39800, 0.39470, -0.00330, -0.84, 0.39454, 0.04046},
    {9, 0.0035, 223, 0.2616, 0.107, 178.09, 0.00006, 0.00111, 0.0, -0.62252, 0.00004, 0.09688,
     0.39479, 0.39458, -0.00021, -0.05, 0.39453, 0.01384},
    {10, 0.0005, 32, 0.2641, 0.060, 178.78, 0.00001, 0.00045, 0.0, -0.62252, 0.00001, 0.09688,
     0.39397, 0.39453, 0.00056, 0.14, 0.39451, 0.00568},
    {11, 0.0065, 414, 0.2676, 0.073, 179.74, 0.00002, 0.00002, 0.0, -0.62252, 0.00001, 0.09688,
     0.40104, 0.39451, -0.00653, -1.65, 0.39451, 0.00026},
    {12, 0.0055, 350, 0.2541, 0.080, 175.79, 0.00014, 0.00540, 0.0, -0.62252, 0.00009, 0.09688,
     0.39145, 0.39484, 0.00339, 0.86, 0.39457, 0.06759},
    {13, 0.0050, 318, 0.3119, 0.080, 177.82, 0.00007, 0.00145, 0.0, -0.62252, 0.00005, 0.09688,
     0.39754, 0.39461, -0.00293, -0.74, 0.39454, 0.01814},
    {14, 0.0070, 446, 0.2477, 0.093, 177.42, 0.00012, 0.00202, 0.0, -0.62252, 0.00007, 0.09688,
     0.39983, 0.39466, -0.00517, -1.31, 0.39456, 0.02531},
}};

// Half a unit in the last printed place (plus a hair for binary representation).
constexpr double kHalf5 = 0.000005 + 1e-12;

AbeniInputs inputs(const Row& row, double alpha_shift_deg = 0.0) {
  AbeniInputs in;
  in.diameter_mm = kDiameterMm;
  in.alpha_rad = rad(row.alpha_deg + alpha_shift_deg);
  in.delta_fy_max_N = row.delta_fy_N;
  in.k_ts_N_per_mm2 = kKtsNPerMm2;
  in.axial_depth_mm = row.ap_mm;
  in.feed_mm_per_min = row.feed_mm_per_min;
  in.spindle_speed_rad_per_s = kSpindleRadPerS;
  return in;
}

/// The largest change of `f` when α moves within its printed rounding (±0.005°, Table A1).
double alpha_rounding_spread(const Row& row, const std::function<double(const AbeniInputs&)>& f) {
  const double centre = f(inputs(row));
  double spread = 0.0;
  for (int k = -10; k <= 10; ++k) {
    spread = std::max(spread, std::fabs(f(inputs(row, k * 0.0005)) - centre));
  }
  return spread;
}

// The spindle speed behind Table 6's feed rates: f = f_z·N·n with n from the nominal diameter
// rounds to the printed f for all tests, which pins ω = 2πn/60 = 3333.3 rad/s for eq 29.
TEST(AbeniRunout, Abeni2024Table6FeedRatesFixTheSpindleSpeed) {
  const double rpm = kCuttingSpeedMmPerS * 60.0 / (kPi * kNominalDiameterMm);
  EXPECT_NEAR(2.0 * kPi * rpm / 60.0, kSpindleRadPerS, 1e-9);
  for (const auto& row : kRows) {
    EXPECT_EQ(std::round(row.fz_mm * 2.0 * rpm), row.feed_mm_per_min) << "test " << row.test;
    // f/(60ω) is the feed per radian, f_z/π for two flutes (physics-notes)
    EXPECT_NEAR(row.feed_mm_per_min / (60.0 * kSpindleRadPerS), row.fz_mm / kPi,
                0.5 / (60.0 * kSpindleRadPerS));
  }
}

// Table A3: I (eq 29), a, b, c, e, g (eqs 31-35), 5 decimals. Everything reproduces from the
// printed inputs except four entries, explained by the inputs' own rounding:
//  - a = sin²α of tests 6, 12, 14: the printed α gives 0.00325, 0.00539, 0.00203; α ± 0.005°
//    (Table A1's rounding) spans the printed values (runout_geometry_test finds one α per test
//    that fits Table 7 and Table A3 together).
//  - e of test 3: Table 6's f = 127 mm/min gives e = 1.4994e-5 (prints 0.00001); the unrounded
//    f = f_z·N·n = 127.32 mm/min gives 1.5006e-5, the printed 0.00002.
TEST(AbeniRunout, Abeni2024TableA3) {
  for (const auto& row : kRows) {
    const auto est = abeni_runout_estimate(inputs(row));
    const auto& q = est.quartic;
    EXPECT_NEAR(est.radius_difference_mm, row.i_mm, kHalf5) << "test " << row.test;
    EXPECT_NEAR(q.b_mm, row.b_mm, kHalf5) << "test " << row.test;
    EXPECT_NEAR(q.c_mm2, row.c_mm2, kHalf5) << "test " << row.test;
    EXPECT_NEAR(q.g_mm4, row.g_mm4, kHalf5) << "test " << row.test;
    if (row.test == 6 || row.test == 12 || row.test == 14) {
      const double formula = row.test == 6 ? 0.00325 : row.test == 12 ? 0.00539 : 0.00203;
      EXPECT_NEAR(q.a, formula, kHalf5) << "test " << row.test;
      const double spread = alpha_rounding_spread(row, [](const AbeniInputs& in) {
        return std::sin(in.alpha_rad) * std::sin(in.alpha_rad);
      });
      EXPECT_NEAR(q.a, row.a, kHalf5 + spread) << "test " << row.test;
    } else {
      EXPECT_NEAR(q.a, row.a, kHalf5) << "test " << row.test;
    }
    if (row.test == 3) {
      EXPECT_NEAR(q.e_mm3, 1.4994e-5, 1e-9);
      auto unrounded = inputs(row);
      unrounded.feed_mm_per_min = row.fz_mm * 2.0 * kSpindleRadPerS * 60.0 / (2.0 * kPi);
      EXPECT_NEAR(unrounded.feed_mm_per_min, 127.32, 0.005);
      const auto q2 =
          abeni_quartic(abeni_radius_difference_mm(unrounded), kDiameterMm, unrounded.alpha_rad);
      EXPECT_NEAR(q2.e_mm3, row.e_mm3, kHalf5);
    } else {
      EXPECT_NEAR(q.e_mm3, row.e_mm3, kHalf5) << "test " << row.test;
    }
  }
}

// Table 8: the quartic's physical root ("4th grade", Lin–Bairstow in the paper) for every test,
// 5 decimals; Δ = analytical − experimental and the error Δ/analytical as printed, within
// their rounding plus what α's rounding moves r_CE1 by; test 7's Δ is one unit off (below).
TEST(AbeniRunout, Abeni2024Table8FourthGrade) {
  for (const auto& row : kRows) {
    const auto est = abeni_runout_estimate(inputs(row));
    ASSERT_GE(est.physical_root, 0) << "test " << row.test;
    EXPECT_NEAR(est.r_ce1_mm, row.r_fourth_mm, kHalf5) << "test " << row.test;
    const double spread = alpha_rounding_spread(
        row, [](const AbeniInputs& in) { return abeni_runout_estimate(in).r_ce1_mm; });
    EXPECT_LT(spread, 1e-6) << "test " << row.test;
    const double variation = est.r_ce1_mm - row.r_experimental_mm;
    if (row.test == 7) {
      // A last-digit slip: Δ = 0.394505 − 0.38651 = 0.0079954 mm prints 0.00800, not 0.00799;
      // no input rounding moves r_CE1 by the 0.4 µm needed (ΔF_y's ±0.0005 N moves it 0.05 µm).
      EXPECT_NEAR(variation, 0.0079954, 1e-7);
      EXPECT_NEAR(variation, row.variation_mm, 2.0 * kHalf5);
    } else {
      EXPECT_NEAR(variation, row.variation_mm, kHalf5 + spread) << "test " << row.test;
    }
    EXPECT_NEAR(100.0 * variation / est.r_ce1_mm, row.error_percent,
                0.005 + 100.0 * spread / est.r_ce1_mm + 1e-9)
        << "test " << row.test;
  }
}

// Table 9: "2nd grade" r_CE1 = the positive root of c·r² + e·r + g = 0, 5 decimals, and the
// difference (4th − 2nd)/4th in % (5 decimals of %), within its rounding plus α's rounding
// (the difference is ~1e-4 mm and moves by up to 6e-7 mm over α ± 0.005°).
TEST(AbeniRunout, Abeni2024Table9SecondGrade) {
  for (const auto& row : kRows) {
    const auto est = abeni_runout_estimate(inputs(row));
    EXPECT_NEAR(est.quadratic_r_ce1_mm, row.r_second_mm, kHalf5) << "test " << row.test;
    const auto percent = [](const AbeniInputs& in) {
      const auto e = abeni_runout_estimate(in);
      return 100.0 * (e.r_ce1_mm - e.quadratic_r_ce1_mm) / e.r_ce1_mm;
    };
    EXPECT_NEAR(percent(inputs(row)), row.variation_percent,
                0.000005 + alpha_rounding_spread(row, percent) + 1e-12)
        << "test " << row.test;
  }
}

// Eq 38 as printed, √(−g/c), is ≈ d/2 = 0.394500 mm whatever the test (g ≈ d⁴/4, c ≈ −d²):
// it is not what Table 9 lists (only test 1's 0.39450 coincides).
TEST(AbeniRunout, Abeni2024Eq38AsPrintedDoesNotGiveTable9) {
  for (const auto& row : kRows) {
    const auto est = abeni_runout_estimate(inputs(row));
    const double printed_eq38 = abeni_eq38_as_printed_r_ce1_mm(est.quartic);
    EXPECT_NEAR(printed_eq38, 0.5 * kDiameterMm, 5e-7) << "test " << row.test;
    if (row.test != 1) {
      EXPECT_GT(std::fabs(printed_eq38 - row.r_second_mm), kHalf5) << "test " << row.test;
    }
  }
}

bool is_round_to_3_significant(double value, double printed) {
  const double unit = std::pow(10.0, std::floor(std::log10(std::fabs(printed))) - 2.0);
  return std::fabs(value - printed) <= 0.5 * unit * (1.0 + 1e-9);
}

// Table A2: test 8's quartic terms a·r⁴, b·r³, c·r², e·r, g at its experimental r_CE1 = 0.398 mm
// for K_ts from 1 to 10⁶ N/mm² (3 significant digits). With the printed ΔF_y = 0.113 N, 27 of
// the 35 entries reproduce; the b, e and g entries at K_ts ≤ 1000 (where ΔF_y/(2K_ts·a_p)
// dominates I) come out 0.2-0.4 % low — the authors' ΔF_y carried more digits. ΔF_y = 0.11335 N,
// inside 0.113's rounding, reproduces all 35.
TEST(AbeniRunout, Abeni2024TableA2SensitivityToKts) {
  struct A2Row {
    double k_ts;
    std::array<double, 5> terms;
  };
  const std::array<A2Row, 7> table = {{
      {1.0, {8.11e-5, -8.92e-5, -9.10e-2, 5.01e-2, 8.25e-2}},
      {10.0, {8.11e-5, -8.94e-6, -9.85e-2, 5.43e-3, 9.67e-2}},
      {100.0, {8.11e-5, -9.14e-7, -9.86e-2, 5.56e-4, 9.69e-2}},
      {1000.0, {8.11e-5, -1.11e-7, -9.86e-2, 6.77e-5, 9.69e-2}},
      {10000.0, {8.11e-5, -3.11e-8, -9.86e-2, 1.89e-5, 9.69e-2}},
      {100000.0, {8.11e-5, -2.30e-8, -9.86e-2, 1.40e-5, 9.69e-2}},
      {1000000.0, {8.11e-5, -2.22e-8, -9.86e-2, 1.35e-5, 9.69e-2}},
  }};
  const Row& test8 = kRows[7];
  ASSERT_EQ(test8.test, 8);
  const double r_ce1_mm = 0.398;  // Table 6, test 8
  const auto terms_for = [&](double delta_fy_N, double k_ts) {
    auto in = inputs(test8);
    in.delta_fy_max_N = delta_fy_N;
    in.k_ts_N_per_mm2 = k_ts;
    const auto q = abeni_quartic(abeni_radius_difference_mm(in), kDiameterMm, in.alpha_rad);
    return abeni_quartic_terms_mm4(q, r_ce1_mm);
  };
  int misses_printed = 0;
  for (const auto& row : table) {
    const auto printed_fy = terms_for(0.113, row.k_ts);
    const auto unrounded_fy = terms_for(0.11335, row.k_ts);
    for (std::size_t j = 0; j < 5; ++j) {
      EXPECT_TRUE(is_round_to_3_significant(unrounded_fy[j], row.terms[j]))
          << "K_ts " << row.k_ts << " term " << j << ": " << unrounded_fy[j];
      if (!is_round_to_3_significant(printed_fy[j], row.terms[j])) {
        ++misses_printed;
        EXPECT_TRUE(row.k_ts <= 1000.0 && (j == 1 || j == 3 || j == 4)) << row.k_ts << " " << j;
        EXPECT_NEAR(printed_fy[j] / row.terms[j], 1.0, 0.005) << row.k_ts << " " << j;
      }
    }
  }
  EXPECT_EQ(misses_printed, 8);
}

// The root structure behind the selection, for every test: four real roots ≈ −d/|sin α|,
// ≈ −d/2, the physical one and ≈ +d/|sin α|. The physical root satisfies the unsquared relation
// U = L − R = 0 and equals the law of cosines' closed form; the −d/2 and +d/|sin α| roots
// satisfy L = −R instead; the −d/|sin α| root satisfies U = 0 as well but is negative.
TEST(AbeniRunout, Abeni2024RootsAndTheirSelection) {
  for (const auto& row : kRows) {
    const auto in = inputs(row);
    const auto est = abeni_runout_estimate(in);
    const double s = std::fabs(std::sin(in.alpha_rad));
    const double d = kDiameterMm;
    const double i = est.radius_difference_mm;
    for (const auto& z : est.roots_mm) {
      EXPECT_EQ(z.imag(), 0.0) << "test " << row.test;
      EXPECT_LT(std::fabs(evaluate_quartic_mm4(est.quartic, z.real())),
                1e-12 * std::max(1.0, std::pow(z.real(), 4) * est.quartic.a))
          << "test " << row.test;
    }
    EXPECT_NEAR(est.roots_mm[0].real() * s / d, -1.0, 2e-3) << "test " << row.test;
    EXPECT_NEAR(est.roots_mm[1].real(), -0.5 * d, 5e-4) << "test " << row.test;
    EXPECT_NEAR(est.roots_mm[3].real() * s / d, 1.0, 2e-3) << "test " << row.test;
    ASSERT_EQ(est.physical_root, 2) << "test " << row.test;
    EXPECT_NEAR(est.r_ce1_mm, 0.5 * (d + i), 5e-4) << "test " << row.test;
    EXPECT_NEAR(est.r_ce1_mm, est.law_of_cosines_r_ce1_mm, 1e-14) << "test " << row.test;
    EXPECT_LT(std::fabs(est.unsquared_residual_mm2), 1e-14) << "test " << row.test;

    const auto sides = [&](double r) {
      const double left = 2.0 * r * r * s * s - 2.0 * r * i + i * i - d * d;
      return std::array<double, 2>{left,
                                   left - abeni_unsquared_residual_mm2(r, i, d, in.alpha_rad)};
    };
    for (std::size_t k : {1U, 3U}) {
      const auto [left, right] = sides(est.roots_mm[k].real());
      EXPECT_LT(std::fabs(left + right), 1e-8 * (std::fabs(left) + std::fabs(right)))
          << "test " << row.test << " root " << k;
      EXPECT_GT(std::fabs(left), 0.1 * d * d) << "test " << row.test << " root " << k;
    }
    const auto [left0, right0] = sides(est.roots_mm[0].real());
    EXPECT_LT(std::fabs(left0 - right0), 1e-8 * (std::fabs(left0) + std::fabs(right0)))
        << "test " << row.test;
  }
}

// Squaring the unsquared relation gives eq 30 exactly: L² − R² = 4·q(r) wherever R is real.
TEST(AbeniRunout, QuarticIsTheSquaredRelation) {
  for (double alpha_deg : {150.0, 176.74, 179.87}) {
    for (double i : {-2e-3, 0.0, 7.6e-5, 0.01}) {
      const double alpha = rad(alpha_deg);
      const auto q = abeni_quartic(i, kDiameterMm, alpha);
      EXPECT_NEAR(q.a,
                  std::pow(std::sin(alpha), 4) + std::pow(std::cos(alpha) * std::sin(alpha), 2),
                  1e-15);  // eq 31 as printed
      EXPECT_NEAR(q.c_mm2,
                  i * i + i * i * std::pow(std::sin(alpha), 2) -
                      kDiameterMm * kDiameterMm * std::pow(std::sin(alpha), 2) -
                      kDiameterMm * kDiameterMm * std::pow(std::cos(alpha), 2),
                  1e-15);  // eq 33 as printed
      for (double r : {-0.3, 0.1, 0.3945, 0.5, 0.7}) {
        const double s = std::sin(alpha);
        const double left = 2.0 * r * r * s * s - 2.0 * r * i + i * i - kDiameterMm * kDiameterMm;
        const double right = left - abeni_unsquared_residual_mm2(r, i, kDiameterMm, alpha);
        EXPECT_NEAR(left * left - right * right, 4.0 * evaluate_quartic_mm4(q, r), 1e-14)
            << alpha_deg << " " << i << " " << r;
      }
    }
  }
}

// Independent truth from the runout geometry: build a triangle from (d, α, r_CE1), set ΔF_y so
// that eq 29 gives its I = r_CE1 − r_CE2, and the estimate returns r_CE1 — also far from the
// paper's near-zero runout (α = 150°, where the quadratic of Table 9 is far off).
TEST(AbeniRunout, RecoversTheEdgeRadiusOfARunoutTriangle) {
  const double d = kDiameterMm;
  for (double alpha_deg : {150.0, 170.0, 176.0, 179.9, 179.999}) {
    for (double r_ce1 : {0.385, 0.3945, 0.40}) {
      const auto t = runout_from_edge_radius(d, rad(alpha_deg), r_ce1);
      AbeniInputs in;
      in.diameter_mm = d;
      in.alpha_rad = rad(alpha_deg);
      in.axial_depth_mm = 0.25;
      in.feed_mm_per_min = 191.0;
      in.spindle_speed_rad_per_s = kSpindleRadPerS;
      const double feed_per_rad = in.feed_mm_per_min / (60.0 * in.spindle_speed_rad_per_s);
      in.delta_fy_max_N = 2.0 * in.k_ts_N_per_mm2 * in.axial_depth_mm *
                          (t.r_ce1_mm - t.r_ce2_mm + feed_per_rad * (in.alpha_rad - kPi));
      const auto est = abeni_runout_estimate(in);
      EXPECT_NEAR(est.radius_difference_mm, r_ce1 - t.r_ce2_mm, 1e-15);
      ASSERT_GE(est.physical_root, 0) << alpha_deg << " " << r_ce1;
      EXPECT_NEAR(est.r_ce1_mm, r_ce1, 1e-12) << alpha_deg << " " << r_ce1;
      EXPECT_NEAR(est.law_of_cosines_r_ce1_mm, r_ce1, 1e-12) << alpha_deg << " " << r_ce1;
    }
  }
}

// At α = π (in double precision sin α ≈ 1e-16, a ≈ 1e-32) the companion matrix is extreme, yet
// the physical root is still (d + I)/2 — no runout direction, r_CE1 + r_CE2 = d.
TEST(AbeniRunout, HandlesAlphaOfExactlyPi) {
  AbeniInputs in = inputs(kRows[7]);
  in.alpha_rad = kPi;
  const auto est = abeni_runout_estimate(in);
  ASSERT_GE(est.physical_root, 0);
  EXPECT_NEAR(est.r_ce1_mm, 0.5 * (kDiameterMm + est.radius_difference_mm), 1e-14);
  EXPECT_NEAR(est.quadratic_r_ce1_mm, est.r_ce1_mm, 1e-14);
}

TEST(AbeniRunout, RejectsInputsOutOfRange) {
  const AbeniInputs good = inputs(kRows[0]);
  auto bad = good;
  bad.diameter_mm = 0.0;
  EXPECT_THROW(abeni_runout_estimate(bad), std::invalid_argument);
  bad = good;
  bad.k_ts_N_per_mm2 = -1.0;
  EXPECT_THROW(abeni_runout_estimate(bad), std::invalid_argument);
  bad = good;
  bad.axial_depth_mm = 0.0;
  EXPECT_THROW(abeni_runout_estimate(bad), std::invalid_argument);
  bad = good;
  bad.spindle_speed_rad_per_s = 0.0;
  EXPECT_THROW(abeni_runout_estimate(bad), std::invalid_argument);
  bad = good;
  bad.alpha_rad = 3.2;
  EXPECT_THROW(abeni_runout_estimate(bad), std::invalid_argument);
  bad = good;
  bad.feed_mm_per_min = -1.0;
  EXPECT_THROW(abeni_runout_estimate(bad), std::invalid_argument);
}

}  // namespace
}  // namespace millwatch::model
