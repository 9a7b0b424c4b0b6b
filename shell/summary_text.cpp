#include "shell/summary_text.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace millwatch::shell {
namespace {

using nlohmann::json;

bool has_number(const json& j, const char* key) {
  return j.is_object() && j.contains(key) && j[key].is_number();
}

double num(const json& j, const char* key) {
  return has_number(j, key) ? j[key].get<double>() : std::nan("");
}

/// A table row of per-flute values: "  peak Fx [N]     -1.48    -0.85".
std::string flute_row(const std::string& label, const json& values, double scale,
                      const char* format) {
  std::string s = fmt::format("  {:<16}", label);
  for (const auto& v : values) {
    s += v.is_number() ? fmt::format(fmt::runtime(format), v.get<double>() * scale)
                       : fmt::format("{:>10}", "—");
  }
  return s + "\n";
}

}  // namespace

std::string summary_text(const json& j) {
  std::string s;
  const std::string input = j.value("input", std::string("recording"));
  const double samples = num(j, "samples");
  const double duration = num(j, "duration_s");
  s += fmt::format("{}", input);
  if (j.contains("input_format") && j["input_format"].is_string()) {
    s += fmt::format("  ({})", j["input_format"].get<std::string>());
  }
  s += "\n";
  s += fmt::format("  record        {:.3f} s, {:.0f} samples", duration, samples);
  if (has_number(j, "dropped_samples") && j["dropped_samples"].get<double>() > 0) {
    s += fmt::format(", {:.0f} dropped", j["dropped_samples"].get<double>());
  }
  if (has_number(j, "bad_lines") && j["bad_lines"].get<double>() > 0) {
    s += fmt::format(", {:.0f} bad records skipped", j["bad_lines"].get<double>());
  }
  const json& record = j.value("record_in_plane_force_N", json::object());
  if (has_number(record, "rms")) {
    s += fmt::format("; in-plane force {:.3f} N RMS, {:.3f} N max", num(record, "rms"),
                     num(record, "max"));
  }
  s += "\n";
  const double rpm = num(j, "spindle_rpm");
  const double commanded = num(j, "spindle_rpm_commanded");
  if (std::isfinite(rpm)) {
    s += fmt::format("  speed         {:.1f} rpm measured", rpm);
    if (has_number(j, "spindle_rpm_std")) {
      // The revolutions' spread, not the mean's σ (the runout's ± below is an estimate's σ).
      s += fmt::format(" (± {:.1f} rev to rev)", num(j, "spindle_rpm_std"));
    }
    s += fmt::format(", {:.0f} commanded ({:+.2f} %)\n", commanded,
                     100.0 * (rpm - commanded) / commanded);
  } else {
    s += fmt::format("  speed         not measured ({:.0f} rpm commanded)\n", commanded);
  }
  // Measured as the JSON and the warnings count them: every revolution reported; "revolutions"
  // (α and the periods) only those with all their tooth events.
  const double measured = has_number(j, "revolutions_measured") ? num(j, "revolutions_measured")
                                                                : num(j, "revolutions");
  const double cutting = num(j, "revolutions_cutting");
  // No turn heard while cutting: none was, or the record was too short for the tracker to hear
  // any (its warning says how long it needs).
  bool too_short = false;
  for (const auto& w : j.value("warnings", json::array())) {
    too_short = too_short || w.value("kind", std::string()) == "record too short";
  }
  s += cutting > 0.0 || measured > 0.0
           ? fmt::format("  revolutions   {:.0f} measured of ~{:.0f} turned while cutting",
                         measured, cutting)
       : too_short ? std::string("  revolutions   none: the record is too short (warnings below)")
                   : std::string("  revolutions   none: no cutting heard");
  if (measured != num(j, "revolutions")) {
    s += fmt::format(" ({:.0f} with all their tooth events)", num(j, "revolutions"));
  }
  s += "\n";
  const json& alpha = j.value("alpha_deg", json::object());
  if (has_number(alpha, "mean")) {
    s += fmt::format("  alpha         {:.2f}°", num(alpha, "mean"));
    s += has_number(alpha, "std") ? fmt::format(" ± {:.2f}° rev to rev", num(alpha, "std"))
                                  : std::string(" (one revolution: no spread)");
    const json& model = j.value("model", json::object());
    if (has_number(model, "alpha_deg")) {
      s += fmt::format("   (model {:.2f}°)", num(model, "alpha_deg"));
    }
    s += "\n";
  }
  const json& periods = j.value("tooth_period_s", json::array());
  const json& peaks = j.value("peak_force_N", json::object());
  // Peaks come from every revolution with its bounds, periods only from those with every tooth
  // event: a flute that does not cut leaves peaks without periods.
  const json& resultant = peaks.value("resultant", json::array());
  bool any_value = false;
  for (const json* values : {&periods, &resultant}) {
    for (const auto& v : *values) {
      any_value = any_value || v.is_number();
    }
  }
  if (any_value) {
    s += fmt::format("  {:<16}", "flute");
    for (std::size_t f = 0; f < std::max(periods.size(), resultant.size()); ++f) {
      s += fmt::format("{:>10}", f + 1);
    }
    s += "\n";
    // Under the period and the resultant peak, their spread from revolution to revolution.
    const auto spread_row = [&](const json& values) {
      return values.is_array() ? flute_row("  ± rev to rev", values, 1.0, "{:>10.3f}") : "";
    };
    s += flute_row("period [ms]", periods, 1e3, "{:>10.4f}");
    const json& periods_std = j.value("tooth_period_s_std", json());
    if (periods_std.is_array()) {
      s += flute_row("  ± rev to rev", periods_std, 1e3, "{:>10.4f}");
    }
    const char* axes[][2] = {{"fx", "peak Fx [N]"},
                             {"fy", "peak Fy [N]"},
                             {"fz", "peak Fz [N]"},
                             {"resultant", "peak |Fxy| [N]"}};
    for (const auto& a : axes) {
      if (peaks.contains(a[0])) {
        s += flute_row(a[1], peaks[a[0]], 1.0, "{:>10.3f}");
      }
    }
    s += spread_row(j.value("peak_force_N_std", json::object()).value("resultant", json()));
  }
  if (has_number(j, "delta_fy_N")) {
    s += fmt::format("  delta Fy      {:.3f} N", num(j, "delta_fy_N"));
    if (has_number(j, "delta_fy_N_std")) {
      s += fmt::format(" ± {:.3f} rev to rev", num(j, "delta_fy_N_std"));
    }
    const json& model = j.value("model", json::object());
    if (has_number(model, "delta_fy_N")) {
      s += fmt::format("   (model {:.3f} N)", num(model, "delta_fy_N"));
    }
    s += "\n";
  }
  const json& residual = j.value("residual_rms_N", json::object());
  if (has_number(residual, "fx")) {
    s += fmt::format("  residual RMS  fx {:.3f}  fy {:.3f}  fz {:.3f} N", num(residual, "fx"),
                     num(residual, "fy"), num(residual, "fz"));
    if (has_number(residual, "measured")) {
      s += fmt::format("   (measured force {:.3f} N RMS)", num(residual, "measured"));
    }
    s += "\n";
  }
  // What of the lockstep model's revolution was approximate (RunSummary's model.steady_state).
  // (A pointer that does not resolve, through a missing key or a value of another kind, gives
  // the default.)
  const json notes = j.value(json::json_pointer("/model/steady_state/notes"), json::array());
  for (const auto& note : notes.is_array() ? notes : json::array()) {
    if (note.is_string()) {
      s += fmt::format("  model note    {}\n", note.get<std::string>());
    }
  }
  // The identified runout (core/identify), when a window was fitted.
  const json& runout = j.value("runout", json::object());
  if (has_number(runout, "rho_um")) {
    const bool lower_bound = runout.value("rho_is_lower_bound", false);
    s += fmt::format("  runout        {}{:.3f} ± {:.3f} µm at {:.1f}° ± {:.1f}° (identified{})\n",
                     lower_bound ? "≥ " : "", num(runout, "rho_um"), num(runout, "rho_std_um"),
                     num(runout, "gamma_deg"), num(runout, "gamma_std_deg"),
                     lower_bound ? "; at a flute's contact edge: a flute cuts nothing beyond it, "
                                   "so the force bounds the runout from below only"
                                 : "");
    // What the force pins best: CE1's cutting radius against each flute's, as the alerts state
    // it (for two flutes 2ρ·cos γ; ρ·sin γ only through second-order effects of the model).
    const json& radii = runout.value("r_minus_r_ce1_um", json::array());
    const json& radii_std = runout.value("r_minus_r_ce1_std_um", json::array());
    if (radii.is_array() && radii.size() >= 2 && radii_std.size() == radii.size()) {
      // On a contact edge the idle flute's deficit is bounded from below only: for two flutes
      // r_CE1 − r_CE2 itself.
      const auto edge = lower_bound ? runout.value("edge_flute", 0) : 0;
      const bool two_bound = radii.size() == 2 && edge == 2;
      s += "  radii         ";
      for (std::size_t k = 1; k < radii.size(); ++k) {
        if (radii[k].is_number() && radii_std[k].is_number()) {
          s += fmt::format("{}r_CE1 − r_CE{} {}{:.3f} ± {:.3f} µm", k > 1 ? ", " : "", k + 1,
                           two_bound ? "≥ " : "", -radii[k].get<double>(),
                           radii_std[k].get<double>());
        }
      }
      if (two_bound) {
        s += " (flute 2 cuts nothing beyond it: a lower bound)\n";
      } else if (edge > 0) {
        s += fmt::format(
            " (flute {} cuts nothing: its radius lies at least a chip below the "
            "flute's before it)\n",
            edge);
      } else {
        s += radii.size() == 2 ? " (= 2ρ·cos γ: what the force pins)\n" : "\n";
      }
    }
  }
  const json& alerts = j.value("alerts", json::array());
  if (alerts.empty()) {
    s += "  alerts        none\n";
  } else {
    s += fmt::format("  alerts        {}\n", alerts.size());
    for (const auto& a : alerts) {
      // Revolution −1: a sensor alert before the first revolution.
      const auto revolution = a.value("revolution", std::int64_t{0});
      s += fmt::format(
          "    {}  {} {}\n",
          revolution < 0 ? std::string("before rev 0") : fmt::format("rev {:>8}", revolution),
          a.value("active", true) ? "RAISED " : "cleared", a.value("message", std::string()));
    }
  }
  const json& warnings = j.value("warnings", json::array());
  if (warnings.empty()) {
    s += "  warnings      none\n";
  } else {
    s += fmt::format("  warnings      {}\n", warnings.size());
    for (const auto& w : warnings) {
      // Whole: a warning's reason comes last (cut short, it lost it, or split a character).
      s += fmt::format("    {}: {}", w.value("kind", std::string()),
                       w.value("detail", std::string()));
      // Events that count samples say how many (the events are per block or gap: "×2" had read as
      // two samples where three were replaced); others how often they came.
      const auto occurrences = w.value("occurrences", std::int64_t{1});
      const auto counted = w.value("samples", std::int64_t{0});
      if (counted > 0) {
        s += fmt::format(" ({} sample{}{})", counted, counted == 1 ? "" : "s",
                         occurrences > 1 ? fmt::format(" at {} places", occurrences) : "");
      } else if (occurrences > 1) {
        s += fmt::format(" (×{})", occurrences);
      }
      s += "\n";
    }
  }
  return s;
}

}  // namespace millwatch::shell
