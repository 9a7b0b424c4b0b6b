#pragma once
// The runout triangle of [001] eqs 1-4 (Fig. 1) and [003] Section 3 (Fig. 4b), in both directions,
// and its mapping onto the model's runout parameters (core/model/flute_positions.hpp).
//
//   O   spindle axis                    A  edge CE1 (flute 0)     B  edge CE2 (flute 1)
//   O'  tool centre, midpoint of AB     d = |AB|                  α = ∠AOB ∈ (0, π]
//   r_CE1 = |OA|, r_CE2 = |OB|, r0 = |OO'|, δ = ∠OBA ([001] eq 3), β = ∠OAB ([001] eq 4).
//
// γ comes in two flavours (physics-notes):
//   γ_eq1   ∈ [0, π]: the angle at O' between O→O' and O'→A, the γ of [001] eq 1:
//           r_CE1² = (d/2)² + r0² + d·r0·cos γ_eq1.
//   γ_table ∈ [0, π/2]: what [001] Table 7 and [003] Table 5 print, arcsin(r_CE1·sin β / r0).
//           By the law of sines in triangle OO'A, sin γ_eq1 = r_CE1·sin β / r0, so γ_table is
//           γ_eq1 folded into [0, π/2] (γ_table = π − γ_eq1 when γ_eq1 > π/2, i.e. when
//           r_CE1 < d/2 up to O(r0²/d)); it then does not satisfy eq 1.
//
// Model mapping. The model ([000] eq 9, flute_positions.hpp) puts the tool centre at ρ towards
// immersion angle φ + γ_model and flute j at φ − ψ_j, ψ_1 = π for two flutes. So ρ = r0 and
// cos γ_model = cos γ_eq1 (flute 0's radius √(R² + ρ² + 2Rρ·cos γ_model) is eq 1): only the sign
// of γ_model is free, and it decides which edge trails by α (the triangle fixes α but not its
// orientation). The edge shifts are ε_0 = atan2(ρ·sin γ_model, R + ρ·cos γ_model) and
// ε_1 = atan2(−ρ·sin γ_model, R − ρ·cos γ_model), so flute 1 follows flute 0 by
// π + ε_0 − ε_1, which is < π exactly when sin γ_model < 0:
//   γ_model = −γ_eq1  ⇒ flute_spacing_rad(…, 0, 1) = α ≤ π   (flute 1 / CE2 trails CE1 by α)
//   γ_model = +γ_eq1  ⇒ flute_spacing_rad(…, 1, 0) = α ≤ π   (flute 0 / CE1 trails CE2 by α)
// The first is the reading of flute_positions.hpp (α = π + ε_0 − ε_1) and the default here. The
// second is the papers' own kinematics: [001] eqs 8-9 put CE2 at θ + α, i.e. ahead of CE1, and
// eqs 12-13 give CE1 the feed of α (Δs_CE1 = f·α/(60ω)); [003] starts CE2 at ωt = 2π − α. Pass
// EdgeOrder::kCe1TrailsByAlpha to reproduce the papers' chip split (eq 29 assumes it).
//
// Lengths are in mm throughout (the papers' unit); the model's ρ is in µm (`offset_um`). These
// functions are pure geometry for two diametrically opposite edges (ψ_1 = π).

namespace millwatch::model {

/// Every quantity of the runout triangle. Lengths in mm, angles in rad.
struct RunoutTriangle {
  double diameter_mm = 0.0;      ///< d = |AB|, the tool (edge-to-edge) diameter
  double alpha_rad = 0.0;        ///< α = ∠AOB ∈ (0, π], cutting-edge phase angle
  double r_ce1_mm = 0.0;         ///< r_CE1 = |OA|, rotation radius of edge A (flute 0)
  double r_ce2_mm = 0.0;         ///< r_CE2 = |OB|, rotation radius of edge B (flute 1), [001] eq 2
  double delta_rad = 0.0;        ///< δ = ∠OBA, [001] eq 3
  double beta_rad = 0.0;         ///< β = ∠OAB = π − α − δ, [001] eq 4
  double r0_mm = 0.0;            ///< r0 = |OO'|, runout length
  double gamma_eq1_rad = 0.0;    ///< γ of [001] eq 1, ∈ [0, π]
  double gamma_table_rad = 0.0;  ///< γ as [001] Table 7 / [003] Table 5 print it, ∈ [0, π/2]
};

/// The triangle from the tool diameter, the phase angle and edge A's radius ([001] eqs 2-4 with
/// eq 2 corrected, [003] Sect. 3):
///   δ = arcsin(r_CE1·sin α / d),  β = π − α − δ,
///   r_CE2² = r_CE1² + d² − 2·r_CE1·d·cos β,  r0² = r_CE1² + (d/2)² − r_CE1·d·cos β,
///   γ_eq1 = atan2(2·r_CE1·r_CE2·sin α, r_CE1² − r_CE2²) (angle between OO' = (A+B)/2 and
///   O'A = (A−B)/2), γ_table = γ_eq1 folded into [0, π/2].
/// The cosine laws are evaluated as (r − x)² + 4·r·x·sin²(β/2) to keep r0 ≪ d accurate.
/// @param diameter_mm d > 0; @param alpha_rad α ∈ (0, π]; @param r_ce1_mm r_CE1 > 0 with
/// β = π − α − δ ≥ 0 (a triangle exists; r_CE1 ≈ d/2 in practice)
/// @throws std::invalid_argument naming the parameter when out of range
RunoutTriangle runout_from_edge_radius(double diameter_mm, double alpha_rad, double r_ce1_mm);

/// The triangle from the tool diameter and the runout (r0, γ_eq1):
///   r_CE1 by [001] eq 1, r_CE2² = (d/2)² + r0² − d·r0·cos γ_eq1 (B = O' − (A − O')),
///   α = π − atan2(d·r0·sin γ_eq1, (d/2)² − r0²) ∈ (π/2, π] (OA·OB = r0² − (d/2)²,
///   |OA × OB| = d·r0·sin γ_eq1), β = atan2(r0·sin γ_eq1, d/2 + r0·cos γ_eq1), δ = π − α − β.
/// @param diameter_mm d > 0; @param r0_mm 0 ≤ r0 < d/2; @param gamma_eq1_rad γ_eq1 ∈ [0, π]
/// @throws std::invalid_argument naming the parameter when out of range
RunoutTriangle runout_from_offset(double diameter_mm, double r0_mm, double gamma_eq1_rad);

/// [001] eq 1: r_CE1 = (d/2 + r0)·√(1 + d·r0·(cos γ − 1)/(d/2 + r0)²), in mm.
double r_ce1_from_offset_mm(double diameter_mm, double r0_mm, double gamma_eq1_rad);

/// γ_table from γ_eq1 ∈ [0, π]: the fold into [0, π/2] (= arcsin(r_CE1·sin β / r0)).
double gamma_table_from_eq1_rad(double gamma_eq1_rad);

/// Which edge trails by α in the direction of rotation (see the header comment).
enum class EdgeOrder {
  /// flute 1 (CE2) follows flute 0 (CE1) by α: flute_spacing_rad(…, 0, 1) = α; γ_model = −γ_eq1.
  kCe2TrailsByAlpha,
  /// flute 0 (CE1) follows flute 1 (CE2) by α: flute_spacing_rad(…, 1, 0) = α; γ_model = +γ_eq1.
  /// The kinematics of [001] eqs 6-13 and [003] eqs 3-5.
  kCe1TrailsByAlpha,
};

/// The model's runout parameters, as in `Effects::Runout` (core/model/model_config.hpp).
struct ModelRunout {
  double offset_um = 0.0;  ///< ρ = r0
  double angle_rad = 0.0;  ///< γ_model ∈ [−π, π]
};

/// The model's (ρ, γ_model) for a triangle: ρ = r0 (in µm), γ_model = ∓γ_eq1 by `order`.
/// The model's tool radius is d/2 with ψ = {0, π}; then flute_positions() gives radii
/// r_CE1, r_CE2 and the spacing α between the edges in the order chosen.
ModelRunout model_runout_from_triangle(const RunoutTriangle& triangle,
                                       EdgeOrder order = EdgeOrder::kCe2TrailsByAlpha);

/// A triangle read back from the model's runout parameters, with the edge order they imply.
struct TriangleFromModel {
  RunoutTriangle triangle;
  EdgeOrder order = EdgeOrder::kCe2TrailsByAlpha;
};

/// The inverse of model_runout_from_triangle: γ_model wrapped into [−π, π] gives
/// γ_eq1 = |γ_model| and the order from its sign (γ_model ≤ 0: kCe2TrailsByAlpha).
/// @param diameter_mm model tool diameter d > 0; @param offset_um ρ, 0 ≤ ρ < d/2;
/// @param angle_rad γ_model, any value (wrapped)
/// @throws std::invalid_argument naming the parameter when out of range
TriangleFromModel triangle_from_model_runout(double diameter_mm, double offset_um,
                                             double angle_rad);

}  // namespace millwatch::model
