#pragma once
// Mechanistic force laws: elemental tangential, normal (radial) and axial force on one axial disc
// of one flute for a given uncut chip thickness.
//
//   power law   [000] eq 5 (Table 2), [002] eq 17:  dF = K·h^a·dz, h and dz in mm
//   linear edge [002] eq 18, [001] eqs 18-21:       dF = (K_c·h + K_e)·dz, or K_c·h·dz + K_p·A_p·dz
//   Kronenberg  [003] eqs 7-8:                      dF_t = K_s0·S^(−1/m)·h·dz, S = h·a_p
//
// Tangential opposes the cutting velocity, normal points from the edge towards the tool axis
// (both as forces on the tool; see model_config.hpp for the projection, [000] eq 7).

#include <cmath>

#include "core/model/model_config.hpp"

namespace millwatch::model {

/// Forces on one disc element, newtons.
struct ElementForce {
  double tangential_N = 0.0;
  double normal_N = 0.0;
  double axial_N = 0.0;
};

/// [002] eq 17's ploughing law below h_min is set (any of its coefficients): the linear edge
/// law then takes it there instead of the shearing law.
[[nodiscard]] bool has_plough_law(const LinearEdge& c);

/// Evaluates the material's force law for one element. Precomputes what does not depend on h.
class ForceLaw {
 public:
  ForceLaw() = default;
  /// @param material force law and coefficients
  /// @param axial_depth_mm a_p (Kronenberg's chip section uses the full depth)
  /// @param h_min_um minimum chip thickness; ploughing coefficients apply below it when
  ///        `regimes` is true
  ForceLaw(const Material& material, double axial_depth_mm, double h_min_um, bool regimes);

  /// Whether a chip of h_um is in the ploughing regime.
  [[nodiscard]] bool ploughing(double h_um) const { return regimes_ && h_um < h_min_um_; }

  /// Force on one disc of thickness dz_mm for chip h_um ≥ 0 (zero chip: zero force).
  /// @param ploughed_area_mm2 A_p for the [001] ploughing-area variant (ignored otherwise)
  [[nodiscard]] ElementForce element(double h_um, double dz_mm,
                                     double ploughed_area_mm2 = 0.0) const;

  /// The same with ln(h_um) already known (saves a logarithm in the model's inner loop).
  [[nodiscard]] ElementForce element_given_log(double h_um, double log_h_um, double dz_mm,
                                               double ploughed_area_mm2 = 0.0) const;

  /// Normal force only, same arguments; used by the deflection balance ([000] eq 22).
  [[nodiscard]] double normal_N(double h_um, double dz_mm, double ploughed_area_mm2 = 0.0) const;

  /// Normal force and its first two derivatives in u = ln(h / 1 µm), at h_um > 0 given also
  /// ln(h_um): Newton's or Halley's method on [000] eq 22 in logarithmic chip coordinates. For
  /// F = K·h^a they are a·F and a²·F, with no division (dF/dh = (dF/du)/h).
  struct NormalSlope {
    double force_N = 0.0;
    double d_du_N = 0.0;
    double d2_du2_N = 0.0;
  };
  [[nodiscard]] NormalSlope normal_with_slope(double h_um, double log_h_um, double dz_mm,
                                              double ploughed_area_mm2 = 0.0) const {
    if (material_.law != ForceLawKind::kPowerLaw) {
      return normal_with_slope_other(h_um, log_h_um, dz_mm, ploughed_area_mm2);
    }
    // Inline: the deflection balance's Newton step calls it at every iteration.
    const auto& c = material_.power_law;
    const bool p = ploughing(h_um);
    const double k = p ? c.k_np_Nmm : c.k_nc_Nmm;
    const double a = p ? c.a_np : c.a_nc;
    const double f = k == 0.0 ? 0.0 : k * dz_mm * std::exp(a * (log_h_um + kLogMmPerUm));
    return {f, a * f, a * a * f};  // F = K·dz·h_mm^a: dF/du = a·F, d²F/du² = a²·F
  }

  /// F_n = slope·h + intercept on a branch of chips h > 0 where the normal force is affine in
  /// h: the linear-edge law's ([002] eq 18, [001] eqs 18-21 with the area given), but for the
  /// chips below h_min (`below_h_min`) where [002] eq 17's power law applies. `valid` false
  /// elsewhere (power law, Kronenberg).
  struct AffineNormal {
    bool valid = false;
    double slope_N_per_um = 0.0;
    double intercept_N = 0.0;
  };
  [[nodiscard]] AffineNormal affine_normal(double dz_mm, double ploughed_area_mm2,
                                           bool below_h_min) const {
    const auto& c = material_.linear_edge;
    if (material_.law != ForceLawKind::kLinearEdge ||
        (below_h_min && regimes_ && !c.ploughing_area && has_plough_law(c))) {
      return {};
    }
    const double edge_N_per_mm =
        c.ploughing_area ? c.k_np_N_per_mm3 * ploughed_area_mm2 : c.k_ne_N_per_mm;
    return {true, c.k_nc_N_per_mm2 * 1e-3 * dz_mm, edge_N_per_mm * dz_mm};
  }

  [[nodiscard]] bool uses_ploughed_area() const {
    return material_.law == ForceLawKind::kLinearEdge && material_.linear_edge.ploughing_area;
  }

 private:
  static constexpr double kLogMmPerUm = -6.907755278982137;  // ln(1e-3), as std::log gives it
  /// normal_with_slope() of the linear-edge and Kronenberg laws.
  [[nodiscard]] NormalSlope normal_with_slope_other(double h_um, double log_h_um, double dz_mm,
                                                    double ploughed_area_mm2) const;
  /// The coefficients of Material without its name, so that copying allocates nothing.
  struct Coefficients {
    ForceLawKind law = ForceLawKind::kPowerLaw;
    PowerLaw power_law;
    LinearEdge linear_edge;
    Kronenberg kronenberg;
  };
  Coefficients material_;
  double axial_depth_mm_ = 0.0;
  double h_min_um_ = 0.0;
  bool regimes_ = false;
};

}  // namespace millwatch::model
