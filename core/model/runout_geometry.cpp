#include "core/model/runout_geometry.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace millwatch::model {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kUmPerMm = 1000.0;

void require(bool ok, const std::string& what) {
  if (!ok) {
    throw std::invalid_argument(what);
  }
}

/// Law of cosines √(r² + x² − 2·r·x·cos β) as √((r − x)² + 4·r·x·sin²(β/2)): no cancellation
/// when the result is small against r and x.
double cosine_law(double r, double x, double beta_rad) {
  const double s = std::sin(0.5 * beta_rad);
  return std::sqrt((r - x) * (r - x) + 4.0 * r * x * s * s);
}

}  // namespace

double gamma_table_from_eq1_rad(double gamma_eq1_rad) {
  return gamma_eq1_rad <= 0.5 * kPi ? gamma_eq1_rad : kPi - gamma_eq1_rad;
}

double r_ce1_from_offset_mm(double diameter_mm, double r0_mm, double gamma_eq1_rad) {
  const double reach = 0.5 * diameter_mm + r0_mm;
  if (reach == 0.0) {
    return 0.0;
  }
  return reach *
         std::sqrt(1.0 + diameter_mm * r0_mm * (std::cos(gamma_eq1_rad) - 1.0) / (reach * reach));
}

RunoutTriangle runout_from_edge_radius(double diameter_mm, double alpha_rad, double r_ce1_mm) {
  require(diameter_mm > 0.0,
          "runout_from_edge_radius: diameter_mm must be > 0, got " + std::to_string(diameter_mm));
  require(
      alpha_rad > 0.0 && alpha_rad <= kPi,
      "runout_from_edge_radius: alpha_rad must be in (0, pi], got " + std::to_string(alpha_rad));
  require(r_ce1_mm > 0.0 && r_ce1_mm * std::sin(alpha_rad) <= diameter_mm,
          "runout_from_edge_radius: r_ce1_mm must be > 0 with r_ce1*sin(alpha) <= d, got " +
              std::to_string(r_ce1_mm));
  RunoutTriangle t;
  t.diameter_mm = diameter_mm;
  t.alpha_rad = alpha_rad;
  t.r_ce1_mm = r_ce1_mm;
  t.delta_rad = std::asin(r_ce1_mm * std::sin(alpha_rad) / diameter_mm);  // [001] eq 3
  t.beta_rad = kPi - alpha_rad - t.delta_rad;                             // [001] eq 4
  require(t.beta_rad >= -1e-15,
          "runout_from_edge_radius: no triangle (alpha + delta > pi) for r_ce1_mm " +
              std::to_string(r_ce1_mm));
  if (t.beta_rad < 0.0) {
    t.beta_rad = 0.0;
  }
  t.r_ce2_mm = cosine_law(r_ce1_mm, diameter_mm, t.beta_rad);  // [001] eq 2, corrected
  t.r0_mm = cosine_law(r_ce1_mm, 0.5 * diameter_mm, t.beta_rad);
  t.gamma_eq1_rad = std::atan2(2.0 * r_ce1_mm * t.r_ce2_mm * std::sin(alpha_rad),
                               (r_ce1_mm - t.r_ce2_mm) * (r_ce1_mm + t.r_ce2_mm));
  t.gamma_table_rad = gamma_table_from_eq1_rad(t.gamma_eq1_rad);
  return t;
}

RunoutTriangle runout_from_offset(double diameter_mm, double r0_mm, double gamma_eq1_rad) {
  require(diameter_mm > 0.0,
          "runout_from_offset: diameter_mm must be > 0, got " + std::to_string(diameter_mm));
  const double radius = 0.5 * diameter_mm;
  require(r0_mm >= 0.0 && r0_mm < radius,
          "runout_from_offset: r0_mm must be in [0, d/2), got " + std::to_string(r0_mm));
  require(
      gamma_eq1_rad >= 0.0 && gamma_eq1_rad <= kPi,
      "runout_from_offset: gamma_eq1_rad must be in [0, pi], got " + std::to_string(gamma_eq1_rad));
  const double c = std::cos(0.5 * gamma_eq1_rad);
  const double s = std::sin(0.5 * gamma_eq1_rad);
  RunoutTriangle t;
  t.diameter_mm = diameter_mm;
  t.r0_mm = r0_mm;
  t.gamma_eq1_rad = gamma_eq1_rad;
  t.gamma_table_rad = gamma_table_from_eq1_rad(gamma_eq1_rad);
  // [001] eq 1, written as (R − r0)² + 4·R·r0·cos²(γ/2); the edges sit at O' ± (A − O').
  t.r_ce1_mm = std::sqrt((radius - r0_mm) * (radius - r0_mm) + 4.0 * radius * r0_mm * c * c);
  t.r_ce2_mm = std::sqrt((radius - r0_mm) * (radius - r0_mm) + 4.0 * radius * r0_mm * s * s);
  // OA·OB = r0² − R², |OA × OB| = 2·R·r0·sin γ.
  t.alpha_rad = std::atan2(2.0 * radius * r0_mm * std::sin(gamma_eq1_rad),
                           (radius - r0_mm) * (radius + r0_mm));
  t.alpha_rad = kPi - t.alpha_rad;
  t.beta_rad =
      std::atan2(r0_mm * std::sin(gamma_eq1_rad), radius + r0_mm * std::cos(gamma_eq1_rad));
  t.delta_rad = kPi - t.alpha_rad - t.beta_rad;
  return t;
}

ModelRunout model_runout_from_triangle(const RunoutTriangle& triangle, EdgeOrder order) {
  const double sign = order == EdgeOrder::kCe2TrailsByAlpha ? -1.0 : 1.0;
  return {triangle.r0_mm * kUmPerMm, sign * triangle.gamma_eq1_rad};
}

TriangleFromModel triangle_from_model_runout(double diameter_mm, double offset_um,
                                             double angle_rad) {
  require(std::isfinite(angle_rad),
          "triangle_from_model_runout: angle_rad must be finite, got " + std::to_string(angle_rad));
  const double wrapped = std::remainder(angle_rad, 2.0 * kPi);  // [−π, π]
  TriangleFromModel out;
  out.triangle = runout_from_offset(diameter_mm, offset_um / kUmPerMm, std::fabs(wrapped));
  out.order = wrapped > 0.0 ? EdgeOrder::kCe1TrailsByAlpha : EdgeOrder::kCe2TrailsByAlpha;
  return out;
}

}  // namespace millwatch::model
