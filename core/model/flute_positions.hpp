#pragma once
// Per-flute cutting radius and angular position under runout, for any number of flutes.
//
// With the tool centre C offset from the spindle axis O by ρ towards immersion angle φ + γ
// ([000] eq 9) and flute j's edge at C + R·e(φ − ψ_j), e(θ) = (sin θ, cos θ), the edge seen
// from O sits at radius r_j and angle φ − ψ_j + ε_j:
//   r_j = √(R² + ρ² + 2Rρ·cos(γ + ψ_j))                       ([001] eq 1 form)
//   ε_j = atan2(ρ·sin(γ + ψ_j), R + ρ·cos(γ + ψ_j))
// so flute j+1 follows flute j by ψ_{j+1} − ψ_j − ε_{j+1} + ε_j. For two flutes that is [001]'s
// cutting-edge phase angle α = π + ε_0 − ε_1 (geometric; the valley-to-valley α of a force
// signal is a different quantity, see physics-notes).

#include <span>
#include <vector>

namespace millwatch::model {

struct FlutePosition {
  double radius_um = 0.0;         ///< r_j, distance of the edge from the spindle axis
  double angle_offset_rad = 0.0;  ///< ε_j, angular shift of the edge caused by runout
};

/// @param tool_radius_um R > 0
/// @param pitch_rad cumulative pitch angles ψ_j (ψ_0 = 0), one per flute
/// @param offset_um ρ ≥ 0, @param offset_angle_rad γ
std::vector<FlutePosition> flute_positions(double tool_radius_um, std::span<const double> pitch_rad,
                                           double offset_um, double offset_angle_rad);

/// The same into `out` (resized; no allocation when it already fits).
void flute_positions(double tool_radius_um, std::span<const double> pitch_rad, double offset_um,
                     double offset_angle_rad, std::vector<FlutePosition>& out);

/// Angle (rad) by which flute `next` follows flute `prev` in the direction of rotation, in (0, 2π).
double flute_spacing_rad(std::span<const double> pitch_rad, std::span<const FlutePosition> flutes,
                         int prev, int next);

}  // namespace millwatch::model
