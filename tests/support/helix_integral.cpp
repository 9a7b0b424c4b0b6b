#include "tests/support/helix_integral.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace millwatch::test {

double helix_integral_fx_N(const model::ModelConfig& c, double phi_rad) {
  constexpr double kPi = std::numbers::pi;
  const double radius = c.tool.diameter_mm / 2;
  const double t = c.process.axial_depth_mm * std::tan(c.tool.helix_deg * kPi / 180.0);
  const double beta = std::acos((2 * radius * radius - t * t) / (2 * radius * radius));
  const double kt = c.material.linear_edge.k_tc_N_per_mm2;
  const double kn = c.material.linear_edge.k_nc_N_per_mm2;
  const double ft_mm = c.process.feed_per_tooth_um * 1e-3;
  // ∫ −h(θ)(K_t cos θ + K_n sin θ) dθ with h = f_t sin θ, over the engaged part of [a, b].
  const auto integral_fx = [&](double a, double b) {
    a = std::max(a, 0.0);
    b = std::min(b, kPi);
    if (b <= a) {
      return 0.0;
    }
    const auto prim = [&](double x) {
      return -ft_mm * (kt * std::sin(x) * std::sin(x) / 2 + kn * (x / 2 - std::sin(2 * x) / 4));
    };
    return prim(b) - prim(a);
  };
  double sum = 0.0;
  for (int j = 0; j < 2; ++j) {
    for (const double wrap : {0.0, 2.0 * kPi, -2.0 * kPi}) {
      const double top = phi_rad - j * kPi + wrap;  // immersion of the tip (lag 0)
      sum += integral_fx(top - beta, top);
    }
  }
  return c.process.axial_depth_mm / beta * sum;
}

}  // namespace millwatch::test
