#pragma once
// The model configuration: tool, process, material and the switchable physical effects.
//
// Frame and sign convention (the whole project uses it; see README "Conventions"):
//   x  feed direction, y  cross-feed, z  tool axis pointing from the workpiece to the spindle.
//   Immersion angle θ of a flute ([000] eqs 1, 9-10): θ = 0 on +y, θ = π/2 on +x (straight
//   ahead of the tool), increasing with time; the tool turns clockwise seen from the spindle.
//   A slot engages θ ∈ [0, π].
//   Forces are the force exerted ON THE TOOL by the workpiece ([000] eq 7, [002] eq 19).
//   A dynamometer under the workpiece reads the opposite sign; the monitor's axis map turns
//   its reading into this frame.
//   Flute j sits at θ_j = φ − ψ_j where φ is the spindle angle and ψ_j its cumulative pitch
//   (ψ_0 = 0). Runout offsets the tool centre from the spindle axis by ρ towards immersion
//   angle φ + γ ([000] eq 9; γ is [000]'s runout angle "α", renamed to keep α for [001]'s
//   cutting-edge phase angle). φ, θ_j and γ refer to the tool tip (z = 0, the bottom of the
//   cut); with helix the edge at height z trails the tip by lag(z) ≈ z·tan λ/R, and how the
//   runout follows it is Effects::Runout::helix.
//
// Defaults are [000]'s cp-Ti case (0.4 mm 2-flute 30° helix, 25,000 rpm, a_p 40 µm, Table 2).

#include <array>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace millwatch::model {

enum class Operation { kSlot, kUpMilling, kDownMilling };

struct Tool {
  double diameter_mm = 0.4;
  int flutes = 2;
  double helix_deg = 30.0;
  double edge_radius_um = 1.78;
  /// Angular spacing from flute j to flute j+1 (deg), one entry per flute, summing to 360.
  /// Empty means uniform pitch. MillingModel snaps it to its angle grid; the steady-state
  /// evaluator (steady_state.hpp) uses it exactly.
  std::vector<double> pitch_deg;
};

struct Process {
  Operation operation = Operation::kSlot;
  double spindle_rpm = 25000.0;
  double feed_per_tooth_um = 4.0;
  double axial_depth_mm = 0.04;
  /// Radial depth of cut a_e; a slot uses the full diameter whatever this says.
  double radial_depth_mm = 0.4;
};

enum class ForceLawKind { kPowerLaw, kLinearEdge, kKronenberg };

/// Two-regime power law, [000] eq 5 with Table 2: dF = K·h^a·dz with h and dz in mm, so K is in
/// N/mm^(1+a) (suffix _Nmm). Cutting coefficients apply for h ≥ h_min, ploughing ones below
/// (when the min_chip effect is on; otherwise the cutting ones always). The axial pair is the
/// [002] eq 17 form; zero K means no Fz.
struct PowerLaw {
  double k_tc_Nmm = 465.4, a_tc = 0.5288;
  double k_nc_Nmm = 122.8, a_nc = 0.32;
  double k_tp_Nmm = 526.7, a_tp = 0.5670;
  double k_np_Nmm = 79.64, a_np = 0.2577;
  double k_ac_Nmm = 0.0, a_ac = 1.0;
  double k_ap_Nmm = 0.0, a_ap = 1.0;
};

/// Linear shear + edge law, [002] eq 18 / [001] eqs 18-21:
///   dF_t = (K_tc·h + K_te)·dz,  dF_n = (K_nc·h + K_ne)·dz,  dF_a = (K_ac·h + K_ae)·dz.
/// With ploughing = "area" the edge term is [001]'s K_p·A_p (eqs 14-17) instead of K_e: the
/// ploughed area A_p (mm²) accumulated while h < h_min, times K_tp/K_np/K_ap in N/mm³.
/// Below h_min (min_chip on) the [002] eq 17 power law A·h^B applies when ploughing = "edge".
struct LinearEdge {
  double k_tc_N_per_mm2 = 1100.0, k_nc_N_per_mm2 = 450.0, k_ac_N_per_mm2 = 0.0;
  double k_te_N_per_mm = 8.0, k_ne_N_per_mm = 12.0, k_ae_N_per_mm = 0.0;
  bool ploughing_area = false;
  double k_tp_N_per_mm3 = 0.0, k_np_N_per_mm3 = 0.0, k_ap_N_per_mm3 = 0.0;
  /// [002] eq 17 ploughing-regime power law (N/mm^(1+B)); used below h_min when not zero.
  double a_t_Nmm = 0.0, b_t = 1.0, a_n_Nmm = 0.0, b_n = 1.0, a_a_Nmm = 0.0, b_a = 1.0;
};

/// Kronenberg law, [003] eqs 7-8: F_t = S·K_s with K_s = K_s0·S^(−1/m), S = h·a_p (mm²) the
/// chip section. Applied per axial disc as dF_t = K_s·h·dz (K_s from the full-depth section),
/// with F_n = radial_ratio·F_t and F_a = axial_ratio·F_t ([003] gives only F_t).
struct Kronenberg {
  double k_s0_N_per_mm2 = 1000.0;
  double m = 4.0;
  double radial_ratio = 0.5;
  double axial_ratio = 0.0;
};

struct Material {
  std::string name = "cp-Ti grade 2 [000] Table 2";
  ForceLawKind law = ForceLawKind::kPowerLaw;
  PowerLaw power_law;
  LinearEdge linear_edge;
  Kronenberg kronenberg;
};

/// How runout meets the helix (effects.runout.helix).
enum class RunoutHelix {
  /// A rigid, parallel offset of the tool axis: the centre is ρ towards φ + γ at every height,
  /// while the edge of flute j at height z sits at φ − ψ_j − lag(z). So the edge at height z
  /// sees the runout angle γ + ψ_j + lag(z): disc i (lag_i, milling_model.hpp) has its own
  /// cutting radii r_{j,i} = |ρ·e(γ + lag_i) + R·e(−ψ_j)| = √(R² + ρ² + 2Rρ·cos(γ + ψ_j + lag_i))
  /// and edge shifts (flute_positions.hpp with γ + lag_i). γ is the runout angle at the tool tip.
  kRigidAxis,
  /// [000] eqs 1-2 as printed: every disc replays the tip's chip pattern lag_i later, so every
  /// disc sees the tip's runout angle γ + ψ_j (the runout turns with the helix, which a rigid
  /// tool does not do). Then ρ·sin γ reaches the force only through the trochoid's pitch term.
  kTipPattern,
};

/// Each physical effect: a switch and its parameters. Off costs nothing at run time.
struct Effects {
  struct Runout {
    bool enabled = true;
    double offset_um = 1.82;  ///< ρ, tool-centre offset from the spindle axis
    /// γ, offset direction relative to flute 0 at the tool tip ([000] "α"); see RunoutHelix
    /// for the other heights.
    double angle_rad = 0.58;
    /// JSON "tip_pattern" (default) or "rigid_axis"; no effect without helix_lag. The default
    /// is the model the monitor and the identification (core/identify) were built and tested on;
    /// rigid_axis is the physical reading but the window fit does not handle it yet (README).
    RunoutHelix helix = RunoutHelix::kTipPattern;
  } runout;
  /// Exact trochoidal flute path by Newton-Raphson ([002] eqs 2-10, [000] eqs 9-18); off: the
  /// circular path h = f_t·sin θ + (r_j − r_{j−1}).
  struct Trochoidal {
    bool enabled = true;
  } trochoidal;
  /// Chip against the nearest of the previous passes ([000] eqs 19-20); off: previous flute only.
  struct MultiPass {
    bool enabled = true;
    int passes = 0;  ///< passes looked back; 0 = automatic (flutes, more with accumulation)
  } multi_pass;
  /// Minimum chip thickness: ploughing coefficients below h_min ([000] eq 5, [002] eq 17-18).
  struct MinChip {
    bool enabled = true;
    double h_min_um = 0.2;
  } min_chip;
  /// Chip accumulation: a pass below h_min removes nothing; its chip adds to the next pass
  /// ([002] eqs 11-12, [000] eq 25). Needs min_chip.
  struct Accumulation {
    bool enabled = true;
  } accumulation;
  /// Static tool deflection under the normal force, material-conserving reading of [000]
  /// eqs 21-24: the leftover δh is carried into the next pass.
  struct Deflection {
    bool enabled = true;
    double stiffness_N_per_um = 0.47;  ///< k_n, [000] Sect. 2.2.1
  } deflection;
  /// Helix lag by axial discs ([000] eqs 1-4, 6, 8); off: one disc without lag.
  struct HelixLag {
    bool enabled = true;
    int discs = 10;
  } helix_lag;
  /// Flank wear land VB per flute adding a rubbing force dF_t = K_wt·VB·dz, dF_n = K_wn·VB·dz
  /// while the flute is engaged (a standard flank-contact term; not in the four papers).
  struct FlankWear {
    bool enabled = false;
    std::vector<double> wear_um = {0.0};  ///< one value for all flutes, or one per flute
    double k_wt_N_per_mm2 = 300.0;
    double k_wn_N_per_mm2 = 600.0;
  } flank_wear;
  /// Dynamometer dynamics applied to the model's output: one second-order resonance per axis
  /// with unit static gain ([001]/[003]: 2145 Hz x, 2192 Hz y).
  struct Dynamometer {
    bool enabled = false;
    std::array<double, 3> natural_hz = {2145.0, 2192.0, 3000.0};
    std::array<double, 3> damping_ratio = {0.05, 0.05, 0.05};
  } dynamometer;
};

/// Numerical resolution of the model.
struct Resolution {
  int steps_per_rev = 720;  ///< spindle-angle steps per revolution (0.5°)
};

struct ModelConfig {
  Tool tool;
  Process process;
  Material material;
  Effects effects;
  Resolution resolution;
};

/// Names of the switchable effects, in the order the diagnosis adds them.
inline constexpr std::array<const char*, 10> kEffectNames = {
    "runout",     "trochoidal", "multi_pass", "min_chip",    "accumulation",
    "deflection", "helix_lag",  "flank_wear", "dynamometer", "ploughing_area"};

/// Turns the named effect on or off. @throws std::invalid_argument for an unknown name.
void set_effect(ModelConfig& config, const std::string& name, bool enabled);
/// Whether the named effect is on. @throws std::invalid_argument for an unknown name.
bool effect_enabled(const ModelConfig& config, const std::string& name);
/// All effects off: the plain circular-path, single-disc, rigid, sharp-tool model.
ModelConfig without_effects(ModelConfig config);

/// Passes a chip looks back (MillingModel and the steady-state evaluator alike): one without
/// multi-pass; with it N_z (or as configured), plus enough for accumulation to find a
/// surface-defining pass near the entry where the nominal chip is smallest (at most 32).
int passes_to_look_back(const ModelConfig& config);

std::string to_string(Operation op);
std::string to_string(ForceLawKind law);
std::string to_string(RunoutHelix helix);

/// Reads a configuration; every field optional (defaults above), unknown keys and values out of
/// range rejected with a config::ConfigError naming the field. Cross-field checks included.
ModelConfig model_config_from_json(const nlohmann::json& j, const std::string& path = "");
nlohmann::json to_json(const ModelConfig& config);

/// Cross-field validation (also run by model_config_from_json).
/// @throws config::ConfigError naming the field.
void validate(const ModelConfig& config, const std::string& path = "");

/// Tool radius in µm.
inline double tool_radius_um(const ModelConfig& c) {
  return c.tool.diameter_mm * 500.0;
}
/// The tooth-passing frequency at the commanded speed (Hz).
inline double tooth_passing_hz(const ModelConfig& c) {
  return c.process.spindle_rpm / 60.0 * c.tool.flutes;
}
/// The immersion angles a flute's tip engages, [from, to] (rad): [000] eq 28 for side milling
/// (up: [0, φ_s], down: [π − φ_s, π], cos φ_s = (R − a_e)/R); a slot engages [0, π] (its walls
/// come from the earlier passes themselves). The helix lag (helix_lag_total_rad) extends it.
struct EngagedArc {
  double from_rad = 0.0;
  double to_rad = 0.0;
};
EngagedArc engaged_arc(const ModelConfig& c);
/// Cumulative pitch angle ψ_j (rad) of each flute, ψ_0 = 0.
std::vector<double> flute_pitch_angles_rad(const Tool& tool);
/// The same into `out` (resized to the flute count; no allocation when it already fits).
void flute_pitch_angles_rad(const Tool& tool, std::vector<double>& out);

/// Total helix lag β over the axial depth, [000] eq 4 (0 with helix_lag off):
///   β = arccos((2R² − a_p²·tan²λ)/(2R²))  (≈ a_p·tan λ/R; the chord of the edge's arc).
/// Disc i of K (dz = a_p/K) is centred at height (i + ½)·dz and trails the tip by
/// lag_i = (i + ½)·β/K (both models take each disc's midpoint).
double helix_lag_total_rad(const ModelConfig& config);
/// Per disc, the angle added to γ for that disc's runout geometry: lag_i with runout on, helix
/// "rigid_axis" and helix_lag on (RunoutHelix::kRigidAxis); empty otherwise (every disc sees the
/// tip's runout angle). `out` keeps its capacity.
void runout_disc_angles_rad(const ModelConfig& config, std::vector<double>& out);

}  // namespace millwatch::model
