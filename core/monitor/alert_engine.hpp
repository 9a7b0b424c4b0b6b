#pragma once
// Tool-state alerts from the per-revolution records and the input counters.
//
//  runout         the flutes' peak forces differ by more than `runout_imbalance` of their mean
//                 (averaged over the α window), raised after `persist_revolutions`, cleared below
//                 `hysteresis`·threshold
//  runout change  two-sided CUSUM of the flute imbalance against the baseline of the first
//                 `baseline_revolutions` valid revolutions, in units of its standard deviation
//  wear drift     the exponentially weighted mean peak force rises `wear_increase` above the
//                 baseline
//  breakage       one flute's peak falls below `breakage_fraction` of the strongest for
//                 `persist_revolutions` while the baseline had all flutes cutting
//  sensor         saturated or non-finite samples above `sensor_bad_fraction` of the samples
//                 of a status interval, or gaps in the stream
// Each alert is raised once and cleared once (hysteresis); nothing is allocated.

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

namespace millwatch::monitor {

struct RevolutionRecord;
struct InputCounters;

enum class AlertKind : std::int8_t {
  kRunout = 1,
  kRunoutChange = 2,
  kWearDrift = 3,
  kBreakage = 4,
  kSensor = 5
};
enum class AlertSeverity : std::int8_t { kInfo = 0, kWarning = 1, kAlarm = 2 };

std::string_view to_string(AlertKind kind);

struct Alert {
  AlertKind kind = AlertKind::kSensor;
  AlertSeverity severity = AlertSeverity::kWarning;
  bool active = true;  ///< raised (true) or cleared (false)
  std::int64_t revolution = 0;
  std::int64_t utime_us = 0;
  double value = 0.0;
  double threshold = 0.0;
  std::string_view quantity;        ///< name with unit of value/threshold
  std::array<char, 160> message{};  ///< one line for the operator
};

struct AlertConfig {
  double runout_imbalance = 0.25;  ///< (max − min)/mean of the flutes' peak resultant
  int persist_revolutions = 10;
  double hysteresis = 0.8;
  int baseline_revolutions = 100;
  double cusum_drift_sigma = 0.5;      ///< k of the CUSUM
  double cusum_threshold_sigma = 8.0;  ///< h of the CUSUM
  double wear_increase = 0.15;         ///< relative rise of the mean peak force
  double wear_ewma_gain = 0.02;
  double breakage_fraction = 0.3;
  double sensor_bad_fraction = 0.001;
};

/// @throws config::ConfigError naming the field.
AlertConfig alert_config_from_json(const nlohmann::json& j, const std::string& path);
nlohmann::json to_json(const AlertConfig& c);

class AlertEngine {
 public:
  AlertEngine() = default;
  explicit AlertEngine(const AlertConfig& config) : config_(config) {}

  /// Examines one revolution; calls sink(const Alert&) for each change of state.
  template <typename Sink>
  void on_revolution(const RevolutionRecord& r, Sink&& sink) {
    examine(r);
    flush(sink);
  }
  /// Examines the input counters since the previous call.
  template <typename Sink>
  void on_input(const InputCounters& c, std::int64_t utime_us, Sink&& sink) {
    examine(c, utime_us);
    flush(sink);
  }
  /// Forget the baseline (a new tool, a reconfiguration).
  void rebaseline();

 private:
  struct State {
    bool active = false;
    int streak = 0;
  };
  void examine(const RevolutionRecord& r);
  void examine(const InputCounters& c, std::int64_t utime_us);
  void emit(AlertKind kind, AlertSeverity severity, bool active, std::int64_t revolution,
            std::int64_t utime_us, double value, double threshold, std::string_view quantity,
            const char* format, double a, double b);
  template <typename Sink>
  void flush(Sink&& sink) {
    for (int i = 0; i < pending_count_; ++i) {
      sink(static_cast<const Alert&>(pending_[static_cast<std::size_t>(i)]));
    }
    pending_count_ = 0;
  }

  AlertConfig config_;
  State runout_, change_, wear_, breakage_, sensor_;
  // Baseline of the first valid revolutions: imbalance mean and spread, mean peak, all cutting.
  int baseline_n_ = 0;
  double baseline_sum_ = 0.0, baseline_sum_sq_ = 0.0, baseline_peak_sum_ = 0.0;
  double baseline_min_ratio_ = 1.0;
  double cusum_high_ = 0.0, cusum_low_ = 0.0;
  double peak_ewma_ = 0.0;
  std::int64_t last_bad_ = 0, last_samples_ = 0, last_gaps_ = 0;
  std::array<Alert, 8> pending_{};
  int pending_count_ = 0;
};

}  // namespace millwatch::monitor
