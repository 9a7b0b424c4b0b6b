#include "core/model/force_law.hpp"

#include <cmath>

namespace millwatch::model {
namespace {

constexpr double kMmPerUm = 1e-3;

/// K·h^a with h in mm; 0 for K = 0 or h ≤ 0.
double power(double k, double a, double h_mm) {
  if (k == 0.0 || h_mm <= 0.0) {
    return 0.0;
  }
  return k * std::exp(a * std::log(h_mm));
}

/// K·exp(a·log h) with log h precomputed.
double power_log(double k, double a, double log_h_mm) {
  return k == 0.0 ? 0.0 : k * std::exp(a * log_h_mm);
}

ElementForce power_law(const PowerLaw& c, double log_h, double dz_mm, bool ploughing) {
  // [000] eq 5a/5b; the axial pair is [002] eq 17. log_h = ln(h / 1 mm).
  if (ploughing) {
    return {power_log(c.k_tp_Nmm, c.a_tp, log_h) * dz_mm,
            power_log(c.k_np_Nmm, c.a_np, log_h) * dz_mm,
            power_log(c.k_ap_Nmm, c.a_ap, log_h) * dz_mm};
  }
  return {power_log(c.k_tc_Nmm, c.a_tc, log_h) * dz_mm,
          power_log(c.k_nc_Nmm, c.a_nc, log_h) * dz_mm,
          power_log(c.k_ac_Nmm, c.a_ac, log_h) * dz_mm};
}

ElementForce linear_edge(const LinearEdge& c, double h_mm, double dz_mm, bool ploughing,
                         double area_mm2) {
  if (c.ploughing_area) {
    // [001] eqs 18-21: shear on h plus ploughing on the ploughed area A_p.
    return {(c.k_tc_N_per_mm2 * h_mm + c.k_tp_N_per_mm3 * area_mm2) * dz_mm,
            (c.k_nc_N_per_mm2 * h_mm + c.k_np_N_per_mm3 * area_mm2) * dz_mm,
            (c.k_ac_N_per_mm2 * h_mm + c.k_ap_N_per_mm3 * area_mm2) * dz_mm};
  }
  if (ploughing && has_plough_law(c)) {
    // [002] eq 17: elastic-plastic regime below the minimum chip thickness.
    return {power(c.a_t_Nmm, c.b_t, h_mm) * dz_mm, power(c.a_n_Nmm, c.b_n, h_mm) * dz_mm,
            power(c.a_a_Nmm, c.b_a, h_mm) * dz_mm};
  }
  // [002] eq 18: shearing plus edge (ploughing) force per unit length.
  return {(c.k_tc_N_per_mm2 * h_mm + c.k_te_N_per_mm) * dz_mm,
          (c.k_nc_N_per_mm2 * h_mm + c.k_ne_N_per_mm) * dz_mm,
          (c.k_ac_N_per_mm2 * h_mm + c.k_ae_N_per_mm) * dz_mm};
}

ElementForce kronenberg(const Kronenberg& c, double h_mm, double dz_mm, double axial_depth_mm) {
  // [003] eqs 7-8: K_s = K_s0·S^(-1/m) with S = h·a_p; dF_t = K_s·h·dz.
  const double section_mm2 = h_mm * axial_depth_mm;
  const double ks = c.k_s0_N_per_mm2 * std::exp(-std::log(section_mm2) / c.m);
  const double ft = ks * h_mm * dz_mm;
  return {ft, c.radial_ratio * ft, c.axial_ratio * ft};
}

}  // namespace

bool has_plough_law(const LinearEdge& c) {
  return c.a_t_Nmm != 0.0 || c.a_n_Nmm != 0.0 || c.a_a_Nmm != 0.0;
}

ForceLaw::ForceLaw(const Material& material, double axial_depth_mm, double h_min_um, bool regimes)
    : material_{material.law, material.power_law, material.linear_edge, material.kronenberg},
      axial_depth_mm_(axial_depth_mm),
      h_min_um_(h_min_um),
      regimes_(regimes) {}

ElementForce ForceLaw::element(double h_um, double dz_mm, double ploughed_area_mm2) const {
  return h_um > 0.0 ? element_given_log(h_um, std::log(h_um), dz_mm, ploughed_area_mm2)
                    : ElementForce{};
}

ElementForce ForceLaw::element_given_log(double h_um, double log_h_um, double dz_mm,
                                         double ploughed_area_mm2) const {
  if (h_um <= 0.0) {
    return {};
  }
  const double h_mm = h_um * kMmPerUm;
  switch (material_.law) {
    case ForceLawKind::kLinearEdge:
      return linear_edge(material_.linear_edge, h_mm, dz_mm, ploughing(h_um), ploughed_area_mm2);
    case ForceLawKind::kKronenberg:
      return kronenberg(material_.kronenberg, h_mm, dz_mm, axial_depth_mm_);
    case ForceLawKind::kPowerLaw:
      break;
  }
  return power_law(material_.power_law, log_h_um + kLogMmPerUm, dz_mm, ploughing(h_um));
}

double ForceLaw::normal_N(double h_um, double dz_mm, double ploughed_area_mm2) const {
  if (h_um <= 0.0) {
    return 0.0;
  }
  if (material_.law == ForceLawKind::kPowerLaw) {
    const auto& c = material_.power_law;
    const double h_mm = h_um * kMmPerUm;
    return ploughing(h_um) ? power(c.k_np_Nmm, c.a_np, h_mm) * dz_mm
                           : power(c.k_nc_Nmm, c.a_nc, h_mm) * dz_mm;
  }
  return element(h_um, dz_mm, ploughed_area_mm2).normal_N;
}

ForceLaw::NormalSlope ForceLaw::normal_with_slope_other(double h_um, double log_h_um, double dz_mm,
                                                        double ploughed_area_mm2) const {
  const double log_h_mm = log_h_um + kLogMmPerUm;
  switch (material_.law) {
    case ForceLawKind::kPowerLaw:
      return normal_with_slope(h_um, log_h_um, dz_mm, ploughed_area_mm2);
    case ForceLawKind::kKronenberg: {
      const auto& c = material_.kronenberg;
      const double e = 1.0 - 1.0 / c.m;
      const double f = c.radial_ratio * c.k_s0_N_per_mm2 * dz_mm *
                       std::exp(e * log_h_mm - std::log(axial_depth_mm_) / c.m);
      return {f, e * f, e * e * f};
    }
    case ForceLawKind::kLinearEdge:
      break;
  }
  const auto& c = material_.linear_edge;
  const double f = normal_N(h_um, dz_mm, ploughed_area_mm2);
  if (!c.ploughing_area && ploughing(h_um) && has_plough_law(c)) {
    return {f, c.b_n * f, c.b_n * c.b_n * f};  // [002] eq 17, A_n·h^B_n (0 when A_n is)
  }
  // Linear in h, c·h + constant: dF/du = c·h = d²F/du².
  const double d_du = c.k_nc_N_per_mm2 * kMmPerUm * dz_mm * h_um;
  return {f, d_du, d_du};
}

}  // namespace millwatch::model
