#pragma once
// Configuration of the monitoring pipeline, shared by the live daemon and the replay.
//
// JSON (every field optional except where the source cannot tell, e.g. the sample rate of a
// live DAQ):
//   { "name": "...", "description": "..." (free text, for the reader),
//     "model": { ModelConfig: the cut as commanded — tool, process, material, effects },
//     "sample_rate_hz": 50000,
//     "axis_map": {"x": "-fx", "y": "-fy", "z": "-fz"},
//     "saturation_N": [x, y, z],
//     "filter": {"cutoff_hz": 3300, "order": 4, "mode": "causal" | "zero_phase"},
//     "spindle": { SpindleTrackerConfig: window_s, hop_s, search_fraction, ... },
//     "tooth_periods": {"window_revolutions": 30, "search_fraction_of_pitch": 0.3},
//     "sync_average": {"bins": 256, "window_revolutions": 30, "template_revolutions": 10},
//     "lockstep": {"enabled": true, "sectors": 12},
//     "identification": {"enabled": true, "extra_parameters": ["h_min_um"],
//                        "max_unexplained": 0.2, "runout_prior_um": 5, "cpu_budget": 0.005},
//     "alerts": { AlertConfig } }

#include <array>
#include <initializer_list>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "core/model/model_config.hpp"
#include "core/monitor/alert_engine.hpp"
#include "core/signal/axis_map.hpp"
#include "core/signal/spindle_tracker.hpp"

namespace millwatch::monitor {

/// The sample rates the monitor takes (MonitorConfig::sample_rate_hz), Hz.
inline constexpr double kMinSampleRateHz = 1000.0;
inline constexpr double kMaxSampleRateHz = 2e6;

/// The cut-off a zero-phase (forward-backward) filter is designed at so that the pair is still
/// 3 dB down at `cutoff_hz` (1 + (f_c/f_c')^(2n) = √2): above it, by 1.12× at order 4.
double zero_phase_design_cutoff_hz(double cutoff_hz, int order);

/// The cut-off for a cut whose configuration gives none, where `default_hz` does not suit it
/// (below 1.5× the tooth-passing frequency, or not below 0.45× the sample rate): moved into the
/// band from four times the tooth-passing frequency (the default's four harmonics at [000]'s
/// speed) up to 0.4× the sample rate — lowered so that a zero-phase design at `order` stays
/// below 0.45× the rate too —, or the band's top where four times does not fit but 1.5× does;
/// `default_hz` itself where it suits the cut or nothing can (validate() then says why).
double cutoff_for_cut_hz(double default_hz, double sample_rate_hz, double tooth_hz, int order);

struct MonitorConfig {
  model::ModelConfig model;
  double sample_rate_hz = 50000.0;
  signal::AxisMap axis_map;
  std::array<double, 3> saturation_N = {std::numeric_limits<double>::infinity(),
                                        std::numeric_limits<double>::infinity(),
                                        std::numeric_limits<double>::infinity()};
  /// [000] Sect. 5 (four harmonics of its 833 Hz tooth-passing frequency). Where the
  /// configuration gives none and this default would not suit the cut,
  /// choose_cutoff_for_cut() takes one that does (cutoff_for_cut_hz) and says so in
  /// filter_cutoff_note.
  double filter_cutoff_hz = 3300.0;
  /// Whether the configuration gave the cut-off (false: monitor_config_from_json found none,
  /// and choose_cutoff_for_cut() may choose it for the cut).
  bool filter_cutoff_given = true;
  /// Why the cut-off is not the default one the configuration left it at ("": it is, or the
  /// configuration gave it).
  std::string filter_cutoff_note;
  int filter_order = 4;
  /// Zero-phase (forward-backward) filtering: offline work only, the results come out up to
  /// signal::ZeroPhaseFilter's chunk + margin samples late; no delay to correct, the model is
  /// filtered with |H|².
  bool filter_zero_phase = false;
  signal::SpindleTrackerConfig spindle;  ///< rate, flutes, commanded speed come from the above
  int alpha_window_revolutions = 30;     ///< [001]: α from 30 revolutions
  double search_fraction_of_pitch = 0.3;
  int sync_bins = 256;
  int sync_window_revolutions = 30;
  int template_revolutions = 10;  ///< revolutions averaged before the valleys are located (at
                                  ///< most sync_window_revolutions: the last ones)
  bool lockstep = true;
  int residual_sectors = 12;
  /// Identification of runout and coefficients on every sync-average window (core/identify).
  struct Identification {
    bool enabled = true;
    /// Further nonlinear parameters fitted (model::parameter_map names, e.g. "h_min_um",
    /// "stiffness_N_per_um"); each must exist for the configured model's effects and law.
    std::vector<std::string> extra_parameters;
    /// The model in lockstep takes a fit that leaves at most this fraction of the window's
    /// variance unexplained.
    double max_unexplained = 0.2;
    double runout_prior_um = 5.0;  ///< identify::FitOptions::runout_prior_um
    /// Live: the fraction of one core the fits may use on average, in (0, 1] (identify::CpuBudget;
    /// the replay waits for every fit and ignores it). 0.005: a fit of the default model takes
    /// ~0.15–0.4 s of CPU (with the systematic variants, up to ~0.6 s: a run's first window, every
    /// tenth, after a move), so one window in 30–80 s is fitted, and the daemon at 333.3 kHz (~4 %
    /// of a core without its fits) stays under 5 % in total.
    double cpu_budget = 0.005;
  } identification;
  AlertConfig alerts;
};

/// @throws config::ConfigError naming the field, its value and the allowed range.
/// `caller_keys`: top-level keys the caller reads itself (the offline shell's "columns", the
/// recording's column map), allowed here and named among the allowed keys when one is unknown.
MonitorConfig monitor_config_from_json(const nlohmann::json& j, const std::string& path = "",
                                       std::initializer_list<std::string_view> caller_keys = {});
nlohmann::json to_json(const MonitorConfig& c);

/// Where the configuration gave no cut-off (filter_cutoff_given false): the default, or where it
/// does not suit this cut's speed, flutes and sample rate the one cutoff_for_cut_hz() takes,
/// with filter_cutoff_note saying why. Again after the rate or the speed changed (the daemon
/// takes a Comedi board's running rate on reload).
void choose_cutoff_for_cut(MonitorConfig& c);
/// Cross-field checks (sample rate against filter and spindle). @throws config::ConfigError.
void validate(const MonitorConfig& c, const std::string& path = "");

/// The monitor configuration JSON a recorded cut's sidecar implies: the cut's model (the full
/// "model" of a simulated cut, else its "tool", "process" and "material"), "sample_rate_hz" and
/// the axis map of "force_sign_convention". `overrides` (a monitor configuration JSON, e.g. from
/// --config) is merged over it (RFC 7386 merge patch). Read the result with
/// monitor_config_from_json. @throws config::ConfigError naming a missing or bad sidecar field.
nlohmann::json monitor_json_from_sidecar(
    const nlohmann::json& sidecar, const nlohmann::json& overrides = nlohmann::json::object());

}  // namespace millwatch::monitor
