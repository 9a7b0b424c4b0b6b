#include "core/diagnose/catalogue.hpp"

#include <array>

namespace millwatch::diagnose {
namespace {

constexpr std::array<CandidateInfo, 13> kCatalogue = {{
    {"runout", CandidateKind::kModelEffect,
     "once-per-revolution pattern: spindle-frequency harmonics that are not tooth-passing "
     "harmonics; one flute's peak above the other's",
     "effects.runout: tool-centre offset rho towards gamma ([000] eq 9)", "rho_um, gamma_rad"},
    {"min_chip_thickness", CandidateKind::kModelEffect,
     "shape at entry/exit (thin chips) against the peak: the ploughing regime below h_min",
     "effects.min_chip: ploughing coefficients below h_min ([000] eq 5)",
     "h_min_um (and the ploughing coefficients, linear)"},
    {"chip_accumulation", CandidateKind::kModelEffect,
     "sub-harmonics of the tooth-passing frequency (skipped passes) and a once-per-revolution "
     "pattern",
     "effects.min_chip + accumulation + multi_pass: a pass below h_min removes nothing ([002] "
     "eqs 11-12)",
     "h_min_um"},
    {"ploughing_area", CandidateKind::kModelEffect,
     "a force of fixed size while a flute cuts (the area ploughed before its chip reached "
     "h_min), rising over the entry and falling over the exit: where an edge force would be, "
     "shaped by h_min",
     "material.linear_edge.ploughing = area: K_p·A_p, the area ploughed below h_min, in place "
     "of the edge force K_e ([001] eqs 14-21)",
     "h_min_um (and K_tp, K_np, K_ap, linear)"},
    {"tool_deflection", CandidateKind::kModelEffect,
     "peaks flattened against the tooth-passing shape; chip-load imbalance smaller than runout "
     "predicts",
     "effects.deflection: static deflection under the normal force ([000] eqs 21-24)",
     "stiffness_N_per_um (coefficients then fitted jointly)"},
    {"helix_lag", CandidateKind::kModelEffect,
     "entry and exit smeared over the helix lag; tooth-passing harmonics falling faster than a "
     "straight edge's",
     "effects.helix_lag: axial discs trailing the tip ([000] eqs 1-4)", "none (discs)"},
    {"trochoidal_path", CandidateKind::kModelEffect,
     "entry and exit off f_t·sin θ by the chip's curvature term f_t²·cos²θ/(2R); the flutes' "
     "chips shifted against each other by the feed-phase term (large feed per tooth against the "
     "radius)",
     "effects.trochoidal: the exact trochoidal flute path, its crossing found by Newton-Raphson "
     "([002] eqs 2-10, [000] eqs 9-18)",
     "none (geometry)"},
    {"dynamometer_dynamics", CandidateKind::kModelEffect,
     "harmonics near the dynamometer's resonance amplified and shifted in phase",
     "effects.dynamometer: a second-order resonance per axis ([001]/[003])",
     "natural_hz_x, natural_hz_y, damping_ratio_x, damping_ratio_y"},
    {"spindle_speed_error", CandidateKind::kSpindle,
     "tooth-passing lines beside the commanded frequency's; a synchronous average smeared over "
     "the record",
     "the model's time base at the actual speed, chip load at the fixed feed rate "
     "(model::at_actual_speed)",
     "spindle_rpm"},
    {"amplifier_drift", CandidateKind::kMeasurementChain,
     "residual below the spindle frequency: a slow trend per axis",
     "a quadratic polynomial in time per axis added to the measurement",
     "drift_N_per_s_x/_y, curvature_N_x/_y"},
    {"mains_hum", CandidateKind::kMeasurementChain, "lines at 50 or 60 Hz and their odd harmonics",
     "sinusoids at the mains frequency and its 3rd and 5th harmonics per axis",
     "mains_hz, amplitude per harmonic and axis"},
    {"tool_wear", CandidateKind::kTimeVarying,
     "a trend over time: the residual grows through the record, most where the flutes rub "
     "(the whole engagement)",
     "effects.flank_wear: a rubbing force K_w·VB·dz while engaged, VB growing linearly over the "
     "record",
     "wear_mid_um (VB at mid-record), wear_growth_um (over the record)"},
    {"runout_change", CandidateKind::kTimeVarying,
     "a step in time: the once-per-revolution pattern differs before and after (a re-clamped or "
     "chipped tool)",
     "the record split where the synchronous pattern changes most; runout and coefficients fitted "
     "on each side",
     "change_time_s, rho/gamma before and after"},
}};

}  // namespace

std::span<const CandidateInfo> catalogue() {
  return kCatalogue;
}

const CandidateInfo* find_candidate(std::string_view name) {
  for (const auto& c : kCatalogue) {
    if (c.name == name) {
      return &c;
    }
  }
  return nullptr;
}

}  // namespace millwatch::diagnose
