#include "core/identify/average_force_regression.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>

namespace millwatch::identify {
namespace {

constexpr double kPi = std::numbers::pi;

/// Least-squares line y = slope·x + intercept with σ from the residual (n ≥ 3).
ForceLine fit_line(const std::vector<double>& x, const std::vector<double>& y) {
  ForceLine l;
  const auto n = static_cast<Eigen::Index>(x.size());
  Eigen::MatrixXd a(n, 2);
  Eigen::VectorXd b(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    a(i, 0) = x[static_cast<std::size_t>(i)];
    a(i, 1) = 1.0;
    b[i] = y[static_cast<std::size_t>(i)];
  }
  const Eigen::Matrix2d ata = a.transpose() * a;
  const Eigen::Vector2d p = ata.ldlt().solve(a.transpose() * b);
  const Eigen::VectorXd r = b - a * p;
  const double s2 = r.squaredNorm() / static_cast<double>(n - 2);
  const Eigen::Matrix2d cov = s2 * ata.inverse();
  l.fitted = true;
  l.slope_N_per_mm2 = p[0];
  l.intercept_N_per_mm = p[1];
  l.slope_std_N_per_mm2 = std::sqrt(std::max(0.0, cov(0, 0)));
  l.intercept_std_N_per_mm = std::sqrt(std::max(0.0, cov(1, 1)));
  l.residual_rms_N_per_mm = std::sqrt(r.squaredNorm() / static_cast<double>(n));
  return l;
}

Estimate estimate(const char* name, double value, double sigma) {
  Estimate e;
  e.name = name;
  e.value = value;
  e.sigma = e.sigma_stat = sigma;
  return e;
}

/// Solves 2π·(p, q) = M·(k1, k2) for (k1, k2) with σ, (p, q) independent with σ (σp, σq).
std::array<Estimate, 2> solve2(const Eigen::Matrix2d& m, double p, double sp, double q, double sq,
                               const char* n1, const char* n2) {
  const Eigen::Matrix2d inv = m.inverse();
  const Eigen::Vector2d k = inv * Eigen::Vector2d(2.0 * kPi * p, 2.0 * kPi * q);
  const Eigen::Matrix2d cov =
      inv * Eigen::Vector2d(4.0 * kPi * kPi * sp * sp, 4.0 * kPi * kPi * sq * sq).asDiagonal() *
      inv.transpose();
  return {estimate(n1, k[0], std::sqrt(cov(0, 0))), estimate(n2, k[1], std::sqrt(cov(1, 1)))};
}

}  // namespace

std::array<double, 2> immersion_rad(const model::ModelConfig& model) {
  const double radius_mm = 0.5 * model.tool.diameter_mm;
  const double ae_mm = std::clamp(model.process.radial_depth_mm, 0.0, 2.0 * radius_mm);
  const double swept = std::acos(std::clamp((radius_mm - ae_mm) / radius_mm, -1.0, 1.0));
  switch (model.process.operation) {
    case model::Operation::kSlot:
      return {0.0, kPi};
    case model::Operation::kUpMilling:
      return {0.0, swept};
    case model::Operation::kDownMilling:
      return {kPi - swept, kPi};
  }
  return {0.0, kPi};
}

AverageForceRegression average_force_regression(const std::vector<MeanForceCut>& cuts) {
  AverageForceRegression out;
  out.cuts = static_cast<int>(cuts.size());
  if (cuts.size() < 3) {
    // A line through fewer than three points has no residual to judge its uncertainty by.
    out.message = "needs at least three cuts (" + std::to_string(cuts.size()) +
                  " given): a line through " +
                  (cuts.size() == 2 ? std::string("two points") : std::string("fewer")) +
                  " leaves nothing to judge its uncertainty by";
    return out;
  }
  const auto [ts, te] = immersion_rad(cuts.front().model);
  for (const auto& c : cuts) {
    const auto [s, e] = immersion_rad(c.model);
    if (std::fabs(s - ts) > 1e-6 || std::fabs(e - te) > 1e-6) {
      out.message =
          "the cuts differ in engagement (operation or radial depth): one line per "
          "axis needs the same immersion in every cut";
      return out;
    }
  }
  double lo = 1e300, hi = -1e300;
  for (const auto& c : cuts) {
    lo = std::min(lo, c.chip_load_um);
    hi = std::max(hi, c.chip_load_um);
  }
  if (!(hi - lo > 0.01 * hi)) {
    out.message =
        "needs at least two distinct feeds per tooth (all cuts at " + std::to_string(hi) + " um)";
    return out;
  }
  out.immersion_start_rad = ts;
  out.immersion_exit_rad = te;
  std::vector<double> x;
  std::array<std::vector<double>, 3> y;
  std::array<bool, 3> all{true, true, true};
  for (const auto& c : cuts) {
    x.push_back(1e-3 * c.chip_load_um);  // mm
    const double na = c.model.tool.flutes * c.model.process.axial_depth_mm;
    for (std::size_t a = 0; a < 3; ++a) {
      y[a].push_back(c.mean_force_N[a] / na);
      all[a] = all[a] && c.measured[a] && std::isfinite(c.mean_force_N[a]);
    }
  }
  if (!all[0] || !all[1]) {
    out.message = "needs the mean fx and fy of every cut";
    return out;
  }
  for (std::size_t a = 0; a < 3; ++a) {
    if (all[a]) {
      out.lines[a] = fit_line(x, y[a]);
    }
  }
  // The immersion integrals over [θ_s, θ_e].
  const double i_sc = 0.5 * (std::pow(std::sin(te), 2) - std::pow(std::sin(ts), 2));
  const double i_ss = 0.5 * (te - ts) - 0.25 * (std::sin(2.0 * te) - std::sin(2.0 * ts));
  const double i_c = std::sin(te) - std::sin(ts);
  const double i_s = std::cos(ts) - std::cos(te);
  const ForceLine& lx = out.lines[0];
  const ForceLine& ly = out.lines[1];
  // 2π·(slope_x, slope_y) = [[−I_sc, −I_ss], [I_ss, −I_sc]]·(K_tc, K_nc)
  Eigen::Matrix2d cutting;
  cutting << -i_sc, -i_ss, i_ss, -i_sc;
  const auto kc = solve2(cutting, lx.slope_N_per_mm2, lx.slope_std_N_per_mm2, ly.slope_N_per_mm2,
                         ly.slope_std_N_per_mm2, "k_tc_N_per_mm2", "k_nc_N_per_mm2");
  // 2π·(icpt_x, icpt_y) = [[−I_c, −I_s], [I_s, −I_c]]·(K_te, K_ne)
  Eigen::Matrix2d edge;
  edge << -i_c, -i_s, i_s, -i_c;
  const auto ke =
      solve2(edge, lx.intercept_N_per_mm, lx.intercept_std_N_per_mm, ly.intercept_N_per_mm,
             ly.intercept_std_N_per_mm, "k_te_N_per_mm", "k_ne_N_per_mm");
  out.coefficients = {kc[0], kc[1], ke[0], ke[1]};
  if (out.lines[2].fitted) {
    const ForceLine& lz = out.lines[2];
    const double f = 2.0 * kPi;
    out.coefficients.push_back(
        estimate("k_ac_N_per_mm2", f * lz.slope_N_per_mm2 / i_s, f * lz.slope_std_N_per_mm2 / i_s));
    out.coefficients.push_back(estimate("k_ae_N_per_mm", f * lz.intercept_N_per_mm / (te - ts),
                                        f * lz.intercept_std_N_per_mm / (te - ts)));
  }
  out.ok = true;
  out.message = "fitted";
  return out;
}

}  // namespace millwatch::identify
