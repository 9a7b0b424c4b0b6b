#include "core/model/abeni_runout.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <unsupported/Eigen/Polynomials>

namespace millwatch::model {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
/// A root counts as real when |Im z| ≤ this times |z|.
constexpr double kRealTolerance = 1e-8;
/// The physical root must satisfy the unsquared relation to this relative residual.
constexpr double kUnsquaredTolerance = 1e-6;

void require_positive(double value, const char* field) {
  if (!(value > 0.0)) {
    throw std::invalid_argument(std::string("abeni_runout: ") + field + " must be > 0, got " +
                                std::to_string(value));
  }
}

double derivative_mm3(const AbeniQuartic& q, double r) {
  return ((4.0 * q.a * r + 3.0 * q.b_mm) * r + 2.0 * q.c_mm2) * r + q.e_mm3;
}

/// Newton steps on q from a real starting point, kept only while they reduce |q|.
double polish_mm(const AbeniQuartic& q, double r) {
  double value = std::fabs(evaluate_quartic_mm4(q, r));
  for (int k = 0; k < 4 && value > 0.0; ++k) {
    const double slope = derivative_mm3(q, r);
    if (slope == 0.0) {
      break;
    }
    const double next = r - evaluate_quartic_mm4(q, r) / slope;
    const double next_value = std::fabs(evaluate_quartic_mm4(q, next));
    if (!(next_value < value)) {
      break;
    }
    r = next;
    value = next_value;
  }
  return r;
}

/// L and R of the unsquared relation U = L − R; R is NaN without a triangle.
std::array<double, 2> unsquared_sides_mm2(double r, double i, double d, double alpha_rad) {
  const double s = std::sin(alpha_rad);
  const double left = 2.0 * r * r * s * s - 2.0 * r * i + i * i - d * d;
  const double under = d * d - r * r * s * s;
  const double right = under >= 0.0 ? 2.0 * r * std::cos(alpha_rad) * std::sqrt(under) : kNaN;
  return {left, right};
}

}  // namespace

double abeni_radius_difference_mm(const AbeniInputs& in) {
  require_positive(in.diameter_mm, "diameter_mm");
  require_positive(in.k_ts_N_per_mm2, "k_ts_N_per_mm2");
  require_positive(in.axial_depth_mm, "axial_depth_mm");
  require_positive(in.spindle_speed_rad_per_s, "spindle_speed_rad_per_s");
  if (!(in.feed_mm_per_min >= 0.0)) {
    throw std::invalid_argument("abeni_runout: feed_mm_per_min must be >= 0, got " +
                                std::to_string(in.feed_mm_per_min));
  }
  if (!(in.alpha_rad > 0.0 && in.alpha_rad <= kPi)) {
    throw std::invalid_argument("abeni_runout: alpha_rad must be in (0, pi], got " +
                                std::to_string(in.alpha_rad));
  }
  const double feed_per_rad_mm = in.feed_mm_per_min / (60.0 * in.spindle_speed_rad_per_s);
  return in.delta_fy_max_N / (2.0 * in.k_ts_N_per_mm2 * in.axial_depth_mm) -
         feed_per_rad_mm * (in.alpha_rad - kPi);  // [001] eq 29
}

AbeniQuartic abeni_quartic(double radius_difference_mm, double diameter_mm, double alpha_rad) {
  const double i = radius_difference_mm;
  const double d2 = diameter_mm * diameter_mm;
  const double s2 = std::sin(alpha_rad) * std::sin(alpha_rad);
  const double half = 0.5 * (i * i - d2);
  return {
      s2,                       // eq 31: sin⁴α + cos²α·sin²α
      -2.0 * i * s2,            // eq 32
      i * i * (1.0 + s2) - d2,  // eq 33: I² + I²·sin²α − d²·(sin²α + cos²α)
      i * d2 - i * i * i,       // eq 34
      half * half,              // eq 35
  };
}

double evaluate_quartic_mm4(const AbeniQuartic& q, double r_mm) {
  return (((q.a * r_mm + q.b_mm) * r_mm + q.c_mm2) * r_mm + q.e_mm3) * r_mm + q.g_mm4;
}

std::array<double, 5> abeni_quartic_terms_mm4(const AbeniQuartic& q, double r_mm) {
  const double r2 = r_mm * r_mm;
  return {q.a * r2 * r2, q.b_mm * r2 * r_mm, q.c_mm2 * r2, q.e_mm3 * r_mm, q.g_mm4};
}

std::array<std::complex<double>, 4> abeni_quartic_roots_mm(const AbeniQuartic& q) {
  if (q.a == 0.0) {
    throw std::invalid_argument("abeni_quartic_roots_mm: a = sin^2(alpha) is 0, no quartic");
  }
  Eigen::Matrix<double, 5, 1> coefficients;  // increasing degree
  coefficients << q.g_mm4, q.e_mm3, q.c_mm2, q.b_mm, q.a;
  const Eigen::PolynomialSolver<double, 4> solver(coefficients);
  std::array<std::complex<double>, 4> roots;
  for (int k = 0; k < 4; ++k) {
    std::complex<double> z = solver.roots()[k];
    if (std::fabs(z.imag()) <= kRealTolerance * std::abs(z)) {
      z = {polish_mm(q, z.real()), 0.0};
    }
    roots[static_cast<std::size_t>(k)] = z;
  }
  std::sort(roots.begin(), roots.end(),
            [](const auto& x, const auto& y) { return x.real() < y.real(); });
  return roots;
}

double abeni_unsquared_residual_mm2(double r_ce1_mm, double radius_difference_mm,
                                    double diameter_mm, double alpha_rad) {
  const auto [left, right] =
      unsquared_sides_mm2(r_ce1_mm, radius_difference_mm, diameter_mm, alpha_rad);
  return left - right;
}

double abeni_quadratic_r_ce1_mm(const AbeniQuartic& q) {
  const double disc = q.e_mm3 * q.e_mm3 - 4.0 * q.c_mm2 * q.g_mm4;
  if (disc < 0.0 || q.c_mm2 == 0.0) {
    return kNaN;
  }
  // Stable pair: t = −(e + sign(e)·√disc)/2, roots t/c and g/t.
  const double t = -0.5 * (q.e_mm3 + std::copysign(std::sqrt(disc), q.e_mm3));
  const double r1 = t / q.c_mm2;
  const double r2 = t != 0.0 ? q.g_mm4 / t : -r1;
  const double best = std::max(r1, r2);
  return best > 0.0 ? best : kNaN;
}

double abeni_eq38_as_printed_r_ce1_mm(const AbeniQuartic& q) {
  return std::sqrt(-q.g_mm4 / q.c_mm2);  // [001] eq 38, positive sign
}

double abeni_law_of_cosines_r_ce1_mm(double radius_difference_mm, double diameter_mm,
                                     double alpha_rad) {
  const double i = radius_difference_mm;
  const double s = std::sin(0.5 * alpha_rad);
  return 0.5 * (i + std::sqrt(i * i + (diameter_mm * diameter_mm - i * i) / (s * s)));
}

AbeniRunoutEstimate abeni_runout_estimate(const AbeniInputs& in) {
  AbeniRunoutEstimate out;
  out.radius_difference_mm = abeni_radius_difference_mm(in);
  const double i = out.radius_difference_mm;
  const double d = in.diameter_mm;
  out.quartic = abeni_quartic(i, d, in.alpha_rad);
  out.roots_mm = abeni_quartic_roots_mm(out.quartic);
  out.quadratic_r_ce1_mm = abeni_quadratic_r_ce1_mm(out.quartic);
  out.law_of_cosines_r_ce1_mm = abeni_law_of_cosines_r_ce1_mm(i, d, in.alpha_rad);

  double best = kUnsquaredTolerance;
  out.r_ce1_mm = kNaN;
  out.unsquared_residual_mm2 = kNaN;
  for (std::size_t k = 0; k < out.roots_mm.size(); ++k) {
    const double r = out.roots_mm[k].real();
    if (out.roots_mm[k].imag() != 0.0 || !(r > 0.0)) {
      continue;
    }
    const auto [left, right] = unsquared_sides_mm2(r, i, d, in.alpha_rad);
    if (std::isnan(right)) {
      continue;  // r·|sin α| > d: δ of [001] eq 3 does not exist
    }
    const double beta = kPi - in.alpha_rad - std::asin(r * std::sin(in.alpha_rad) / d);
    if (beta < -1e-12) {
      continue;  // [001] eq 4: β < 0, no triangle (the large positive root when I ≫ d·sin α)
    }
    const double relative = std::fabs(left - right) / (std::fabs(left) + std::fabs(right));
    if (relative <= best) {
      best = relative;
      out.physical_root = static_cast<int>(k);
      out.r_ce1_mm = r;
      out.unsquared_residual_mm2 = left - right;
    }
  }
  return out;
}

}  // namespace millwatch::model
