#pragma once
// [001]'s analytic estimate of the first cutting edge's radius r_CE1 from the force signal
// (Abeni et al. 2024, eqs 26-38, Tables A2, A3, 8, 9), with the corrections of physics-notes.
//
// Eq 29 turns the F_y peak difference and the phase angle α into the radius difference
//   I = r_CE1 − r_CE2 = ΔF_y,max / (2·K_ts·a_p) − f/(60·ω)·(α − π)   (f mm/min, ω rad/s, so
//   f/(60ω) is the feed per radian, f_z/π for two flutes).
// With r_CE2 = r_CE1 − I and the runout triangle ([001] eqs 2-4: r_CE2² = r_CE1² + d² −
// 2·r_CE1·d·cos β, β = π − α − δ, sin δ = r_CE1·sin α / d, δ acute) this is the unsquared relation
//   U(r) = L(r) − R(r) = 0,   L = 2r²·sin²α − 2r·I + I² − d²,   R = 2r·cos α·√(d² − r²·sin²α)
// and squaring it (L² − R² = 4·q(r)) gives the quartic of eq 30,
//   q(r) = a·r⁴ + b·r³ + c·r² + e·r + g,   a = sin²α, b = −2·I·sin²α, c = I²·(1 + sin²α) − d²,
//   e = I·d² − I³, g = ((I² − d²)/2)²                                 (eqs 31-35, simplified).
// Its four real roots are ≈ ±d/|sin α| (the squaring's), ≈ −d/2 and the physical one
// ≈ (d + I)/2. The −d/2 root and, for [001]'s data, the large positive one satisfy L = −R; the
// large negative one satisfies U = 0 too but is no radius; and when I ≫ d·|sin α| the large
// positive one satisfies U = 0 with β = π − α − δ < 0 (no triangle). So the physical root is
// the one with r > 0, r·|sin α| ≤ d, β ≥ 0 and U = 0. It equals the law of cosines at O,
// d² = r² + (r − I)² − 2r·(r − I)·cos α, solved in closed form:
//   r_CE1 = (I + √(I² + (d² − I²)/sin²(α/2))) / 2.
// [001] Table 9's "2nd grade" r_CE1 solves c·r² + e·r + g = 0 (dropping a and b), not eq 38
// as printed (√(−g/c), which gives ≈ d/2 for every test).
//
// Lengths in mm, forces in N, K_ts in N/mm², as in the paper.

#include <array>
#include <complex>

namespace millwatch::model {

/// What [001] eq 29 needs from one cut.
struct AbeniInputs {
  double diameter_mm = 0.0;              ///< d, effective tool diameter
  double alpha_rad = 0.0;                ///< α ∈ (0, π], cutting-edge phase angle ([001] eq 36)
  double delta_fy_max_N = 0.0;           ///< ΔF_y,max, F_y peak difference between the edges
  double k_ts_N_per_mm2 = 10000.0;       ///< K_ts, shearing coefficient ([001] Sect. 3.2)
  double axial_depth_mm = 0.0;           ///< a_p (Tables A2/A3 use the measured a_p)
  double feed_mm_per_min = 0.0;          ///< f, table feed rate
  double spindle_speed_rad_per_s = 0.0;  ///< ω
};

/// The quartic of [001] eq 30 in r_CE1 (mm): a·r⁴ + b·r³ + c·r² + e·r + g = 0.
struct AbeniQuartic {
  double a = 0.0;      ///< eq 31, = sin²α
  double b_mm = 0.0;   ///< eq 32, −2·I·sin²α
  double c_mm2 = 0.0;  ///< eq 33, = I²·(1 + sin²α) − d²
  double e_mm3 = 0.0;  ///< eq 34, I·d² − I³
  double g_mm4 = 0.0;  ///< eq 35 (its `l` is I), ((I² − d²)/2)²
};

/// [001] eq 29: I = r_CE1 − r_CE2 (mm).
/// @throws std::invalid_argument naming the field when d, K_ts, a_p or ω is not > 0, f < 0 or
/// α ∉ (0, π]
double abeni_radius_difference_mm(const AbeniInputs& in);

/// [001] eqs 31-35 for radius difference I (mm), tool diameter d (mm) and α (rad).
AbeniQuartic abeni_quartic(double radius_difference_mm, double diameter_mm, double alpha_rad);

/// q(r) in mm⁴.
double evaluate_quartic_mm4(const AbeniQuartic& q, double r_mm);

/// The five terms a·r⁴, b·r³, c·r², e·r, g (mm⁴) at r_CE1 = r_mm, as [001] Table A2 lists them.
std::array<double, 5> abeni_quartic_terms_mm4(const AbeniQuartic& q, double r_mm);

/// All four roots (mm): eigenvalues of the balanced companion matrix (Eigen's
/// PolynomialSolver), real ones polished by Newton steps on q. Sorted by real part.
/// @throws std::invalid_argument when a = 0 (α = π exactly has no quartic: use the quadratic)
std::array<std::complex<double>, 4> abeni_quartic_roots_mm(const AbeniQuartic& q);

/// U(r) = L(r) − R(r) (mm², see the header comment): zero at the physical root (the only one
/// with r > 0 and a triangle, β ≥ 0). NaN where r·|sin α| > d (δ does not exist).
double abeni_unsquared_residual_mm2(double r_ce1_mm, double radius_difference_mm,
                                    double diameter_mm, double alpha_rad);

/// The positive root of c·r² + e·r + g = 0 (mm): [001] Table 9's "2nd grade" r_CE1. NaN if none.
double abeni_quadratic_r_ce1_mm(const AbeniQuartic& q);

/// [001] eq 38 as printed, √(−g/c) (mm); does not reproduce Table 9 (kept to document that).
double abeni_eq38_as_printed_r_ce1_mm(const AbeniQuartic& q);

/// The physical root in closed form, from the law of cosines at O with r_CE2 = r_CE1 − I:
/// (I + √(I² + (d² − I²)/sin²(α/2)))/2 (mm).
double abeni_law_of_cosines_r_ce1_mm(double radius_difference_mm, double diameter_mm,
                                     double alpha_rad);

/// Everything [001] Sect. 3.3-3.4 computes for one cut.
struct AbeniRunoutEstimate {
  double radius_difference_mm = 0.0;               ///< I, eq 29
  AbeniQuartic quartic;                            ///< eqs 30-35
  std::array<std::complex<double>, 4> roots_mm{};  ///< all four roots of eq 30
  int physical_root = -1;  ///< index into roots_mm of the selected root; −1 if none qualifies
  double r_ce1_mm = 0.0;   ///< the selected root ([001] Table 8 "4th grade"); NaN if none
  double unsquared_residual_mm2 = 0.0;   ///< U at the selected root
  double quadratic_r_ce1_mm = 0.0;       ///< c·r² + e·r + g = 0 ([001] Table 9 "2nd grade")
  double law_of_cosines_r_ce1_mm = 0.0;  ///< closed form of the physical root (cross-check)
};

/// [001] eqs 29-35 and the root selection: among the real roots with r > 0, r·|sin α| ≤ d and
/// β = π − α − arcsin(r·sin α / d) ≥ 0 (a runout triangle exists), the one with the smallest
/// relative |U| (|L − R| / (|L| + |R|)), accepted below 1e-6.
/// @throws std::invalid_argument as abeni_radius_difference_mm, or when α = π exactly
AbeniRunoutEstimate abeni_runout_estimate(const AbeniInputs& in);

}  // namespace millwatch::model
