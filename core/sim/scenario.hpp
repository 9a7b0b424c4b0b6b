#pragma once
// A simulated recording: the true cut (a ModelConfig) plus the measurement chain that turns its
// force into what a dynamometer recording looks like. Every part of the chain is a switch.
//
// JSON (every field optional; defaults below):
//   { "name": "...", "description": "...",
//     "model": { ModelConfig: tool, process, material, effects, resolution },
//     "recording": { "sample_rate_hz", "duration_s", "seed" },
//     "spindle": { "profile": "steady"|"ramp"|"stop_start", "actual_rpm",
//                  "ramp_end_rpm", "ramp_start_s", "ramp_end_s",
//                  "stop_s", "stop_ramp_s", "stop_hold_s" },
//     "noise": { "enabled", "sigma_N": [x, y, z] },
//     "quantisation": { "enabled", "bits", "range_N": [x, y, z] },
//     "drift": { "enabled", "rate_N_per_s": [x, y, z] },
//     "hum": { "enabled", "frequency_hz", "amplitude_N": [x, y, z] },
//     "wear": { "enabled", "start_um": [...], "end_um": [...] },
//     "runout_change": { "enabled", "time_s", "offset_um", "angle_rad" },
//     "coefficient_drift": { "enabled", "end_factor" },
//     "axis_map": { "x": "-fx", "y": "-fy", "z": "-fz" } }
// The model's own dynamometer effect is the dynamometer resonance of the chain.

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/model/model_config.hpp"
#include "core/signal/axis_map.hpp"

namespace millwatch::sim {

enum class SpindleProfileKind { kSteady, kRamp, kStopStart };

struct SpindleSettings {
  SpindleProfileKind profile = SpindleProfileKind::kSteady;
  /// Actual speed; 0 means "the commanded speed" (model.process.spindle_rpm).
  double actual_rpm = 0.0;
  double ramp_end_rpm = 0.0;  ///< ramp: speed reached at ramp_end_s
  double ramp_start_s = 0.0;
  double ramp_end_s = 0.0;
  double stop_s = 0.0;        ///< stop/start: deceleration starts here (feed hold: no cutting)
  double stop_ramp_s = 0.05;  ///< deceleration and acceleration time
  double stop_hold_s = 0.1;   ///< time at standstill
};

struct Scenario {
  std::string name = "unnamed";
  std::string description;
  model::ModelConfig model;

  double sample_rate_hz = 50000.0;
  double duration_s = 0.5;
  std::uint64_t seed = 1;

  SpindleSettings spindle;

  struct Noise {
    bool enabled = false;
    std::array<double, 3> sigma_N = {0.01, 0.01, 0.01};
  } noise;
  /// ADC: clipping at ±range_N (saturation) and rounding to 2·range/2^bits.
  struct Quantisation {
    bool enabled = false;
    int bits = 16;
    std::array<double, 3> range_N = {20.0, 20.0, 20.0};
  } quantisation;
  /// Charge-amplifier drift: a linear offset growing at rate_N_per_s.
  struct Drift {
    bool enabled = false;
    std::array<double, 3> rate_N_per_s = {0.02, -0.015, 0.01};
  } drift;
  /// Mains hum.
  struct Hum {
    bool enabled = false;
    double frequency_hz = 50.0;
    std::array<double, 3> amplitude_N = {0.005, 0.005, 0.005};
  } hum;
  /// Flank wear growing linearly over the record (per flute, or one value for all).
  struct Wear {
    bool enabled = false;
    std::vector<double> start_um = {0.0};
    std::vector<double> end_um = {10.0};
  } wear;
  /// The runout becomes (offset_um, angle_rad) at time_s (e.g. a tool re-clamped or chipped).
  struct RunoutChange {
    bool enabled = false;
    double time_s = 0.25;
    double offset_um = 3.0;
    double angle_rad = 1.0;
  } runout_change;
  /// Every force coefficient — the force law's K's (cutting, edge, ploughing; not the exponents)
  /// and the flank-wear rubbing ones — scaled by a factor growing linearly over the record from 1
  /// at the start to end_factor at the end (an edge wearing, a harder material).
  struct CoefficientDrift {
    bool enabled = false;
    double end_factor = 1.2;
  } coefficient_drift;

  signal::AxisMap axis_map;  ///< how the simulated dynamometer is mounted
};

/// Actual spindle speed of the scenario when steady (actual_rpm or the commanded speed).
double actual_rpm(const Scenario& s);

/// @throws config::ConfigError naming the field, its value and the allowed range.
Scenario scenario_from_json(const nlohmann::json& j);
nlohmann::json to_json(const Scenario& s);

}  // namespace millwatch::sim
