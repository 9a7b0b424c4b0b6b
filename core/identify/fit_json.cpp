#include "core/identify/fit_json.hpp"

#include <cmath>
#include <numbers>

namespace millwatch::identify {
namespace {

constexpr double kDegPerRad = 180.0 / std::numbers::pi;

/// A finite number, or null (never NaN in a summary).
nlohmann::json number(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}

}  // namespace

nlohmann::json per_axis(const std::array<double, 3>& values, const std::array<bool, 3>& compared) {
  nlohmann::json out = nlohmann::json::array();
  for (std::size_t a = 0; a < 3; ++a) {
    out.push_back(compared[a] ? number(values[a]) : nlohmann::json(nullptr));
  }
  return out;
}

nlohmann::json to_json(const IdentifiedWindow& w) {
  const FitResult& f = w.fit;
  nlohmann::json fit = {{"ok", f.ok},
                        {"revolutions", w.window_revolutions},
                        {"last_revolution", w.revolution},
                        {"iterations", f.iterations},
                        {"evaluations", f.evaluations},
                        {"harmonics", f.harmonics},
                        {"effective_samples", f.effective_samples},
                        {"fit_ms", number(1e3 * w.fit_seconds)}};
  if (!f.ok) {
    fit["reason"] = f.message;
    return {{"fit", fit}};
  }
  fit["residual_rms_N"] = per_axis(f.residual_rms_N, f.compared);
  fit["measured_rms_N"] = per_axis(f.measured_rms_N, f.compared);
  nlohmann::json pairs = nlohmann::json::array();
  for (const auto& [a, b] : f.correlated) {
    pairs.push_back({a, b});
  }
  fit["correlated"] = pairs;
  // The share of the measured (harmonic) force the model leaves unexplained.
  fit["unexplained_fraction"] = number(unexplained_fraction(f.residual_rms_N, f.measured_rms_N));

  nlohmann::json radii = nlohmann::json::array();
  nlohmann::json radii_std = nlohmann::json::array();
  nlohmann::json from_ce1 = nlohmann::json::array();
  nlohmann::json from_ce1_std = nlohmann::json::array();
  for (const Estimate& e : f.cutting_radius_um) {
    radii.push_back(number(e.value));
    radii_std.push_back(number(e.sigma));
  }
  for (const Estimate& e : f.radius_from_ce1_um) {
    from_ce1.push_back(number(e.value));
    from_ce1_std.push_back(number(e.sigma));
  }
  nlohmann::json runout = {{"rho_um", number(f.rho_um.value)},
                           {"rho_std_um", number(f.rho_um.sigma)},
                           {"gamma_deg", number(f.gamma_rad.value * kDegPerRad)},
                           {"gamma_std_deg", number(f.gamma_rad.sigma * kDegPerRad)},
                           {"r_ce_um", radii},
                           {"r_ce_std_um", radii_std},
                           {"r_minus_r_ce1_um", from_ce1},
                           {"r_minus_r_ce1_std_um", from_ce1_std},
                           {"alignment_deg", number(f.alignment_rad.value * kDegPerRad)},
                           {"flute_labelling", f.flute_labelling},
                           // At a flute's contact edge ρ is the least runout the force allows.
                           {"rho_is_lower_bound", f.runout_at_contact_edge}};
  if (f.edge_flute >= 0) {  // the idle flute (CE number): its deficit is a lower bound
    runout["edge_flute"] = f.edge_flute + 1;
  }
  if (f.config.tool.flutes >= 2) {  // the geometric α: one flute has none
    runout["alpha_deg"] = number(f.alpha_deg.value);
    runout["alpha_std_deg"] = number(f.alpha_deg.sigma);
  }
  nlohmann::json coefficients = nlohmann::json::object();
  // Where the fit left it, not an estimate: no σ.
  const auto add = [&](const Estimate& e) {
    coefficients[e.name] = {{"value", number(e.value)}, {"std", number(e.sigma)}};
    if (!e.determined) {
      coefficients[e.name]["std"] = nullptr;
      coefficients[e.name]["determined"] = false;
    }
  };
  for (const Estimate& e : f.coefficients) {
    // A coefficient no compared axis sees was not fitted (σ 0, determined): left out.
    if (e.sigma > 0.0 || !e.determined) {
      add(e);
    }
  }
  for (const Estimate& e : f.extra) {
    add(e);
  }
  return {{"runout", runout}, {"coefficients", coefficients}, {"fit", fit}};
}

}  // namespace millwatch::identify
