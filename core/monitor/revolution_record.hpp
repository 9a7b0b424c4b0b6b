#pragma once
// Everything the pipeline measures about one revolution: the measured features, the same
// features of the model in lockstep, and the residual between them.

#include <array>
#include <cstdint>

#include "core/monitor/revolution_features.hpp"

namespace millwatch::monitor {

inline constexpr int kMaxSectors = 36;

struct RevolutionRecord {
  std::int64_t revolution = 0;  ///< revolutions reported since the pipeline started
  std::int64_t utime_us = 0;    ///< time of the revolution's first event (filter delay removed)
  /// This revolution's own speed from its tooth events: 60/T with T filtered over the last
  /// revolutions (measured.period_s is the raw T); 0 when not measured (its closing CE1 event
  /// was not found, and the period would be the filter's prediction).
  double spindle_rpm = 0.0;
  ToothEventKind event_kind = ToothEventKind::kValley;
  RevolutionMeasurement measured;
  /// Window statistics of the valid measured revolutions (the last alpha_window).
  double alpha_mean_deg = 0.0;
  double alpha_std_deg = 0.0;
  double delta_fy_mean_N = 0.0;
  int window_revolutions = 0;

  bool model_valid = false;  ///< lockstep aligned and its revolution measured
  RevolutionMeasurement model;
  double model_offset_rad = 0.0;
  /// Measured minus modelled filtered force over the revolution (valid with model_valid).
  std::array<double, 3> residual_rms_N{};
  double measured_rms_N = 0.0;  ///< RMS of the measured in-plane resultant √(Fx² + Fy²), N
  std::array<double, kMaxFlutes> residual_flute_rms_N{};
  int sectors = 0;
  std::array<double, kMaxSectors> residual_sector_rms_N{};
};

}  // namespace millwatch::monitor
