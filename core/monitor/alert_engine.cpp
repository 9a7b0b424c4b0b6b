#include "core/monitor/alert_engine.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/config/json_reader.hpp"
#include "core/monitor/input_check.hpp"
#include "core/monitor/revolution_record.hpp"

namespace millwatch::monitor {
namespace {

/// (max − min)/mean of the flutes' peak resultant force, and min/max.
struct Imbalance {
  double ratio = 0.0;
  double min_over_max = 1.0;
  double mean_N = 0.0;
};

Imbalance imbalance(const RevolutionMeasurement& m) {
  Imbalance out;
  if (m.flutes < 2) {
    return out;
  }
  double lo = m.peak_resultant_N[0], hi = lo, sum = 0.0;
  for (int j = 0; j < m.flutes; ++j) {
    const double p = m.peak_resultant_N[static_cast<std::size_t>(j)];
    lo = std::min(lo, p);
    hi = std::max(hi, p);
    sum += p;
  }
  out.mean_N = sum / m.flutes;
  out.ratio = out.mean_N > 0.0 ? (hi - lo) / out.mean_N : 0.0;
  out.min_over_max = hi > 0.0 ? lo / hi : 1.0;
  return out;
}

}  // namespace

std::string_view to_string(AlertKind kind) {
  switch (kind) {
    case AlertKind::kRunout:
      return "runout";
    case AlertKind::kRunoutChange:
      return "runout_change";
    case AlertKind::kWearDrift:
      return "wear_drift";
    case AlertKind::kBreakage:
      return "breakage";
    case AlertKind::kSensor:
      break;
  }
  return "sensor";
}

AlertConfig alert_config_from_json(const nlohmann::json& j, const std::string& path) {
  config::ObjectReader r(j, path);
  AlertConfig c;
  c.runout_imbalance = r.number("runout_imbalance", c.runout_imbalance, config::positive(10.0));
  c.persist_revolutions = r.integer("persist_revolutions", c.persist_revolutions, 1, 100000);
  c.hysteresis = r.number("hysteresis", c.hysteresis, {0.0, 1.0, true, false, ""});
  c.baseline_revolutions = r.integer("baseline_revolutions", c.baseline_revolutions, 10, 1000000);
  c.cusum_drift_sigma =
      r.number("cusum_drift_sigma", c.cusum_drift_sigma, config::non_negative(100.0));
  c.cusum_threshold_sigma =
      r.number("cusum_threshold_sigma", c.cusum_threshold_sigma, config::positive(1000.0));
  c.wear_increase = r.number("wear_increase", c.wear_increase, config::positive(10.0));
  c.wear_ewma_gain = r.number("wear_ewma_gain", c.wear_ewma_gain, {0.0, 1.0, true, false, ""});
  c.breakage_fraction =
      r.number("breakage_fraction", c.breakage_fraction, {0.0, 1.0, true, true, ""});
  c.sensor_bad_fraction =
      r.number("sensor_bad_fraction", c.sensor_bad_fraction, config::positive(1.0));
  r.finish();
  return c;
}

nlohmann::json to_json(const AlertConfig& c) {
  return {{"runout_imbalance", c.runout_imbalance},
          {"persist_revolutions", c.persist_revolutions},
          {"hysteresis", c.hysteresis},
          {"baseline_revolutions", c.baseline_revolutions},
          {"cusum_drift_sigma", c.cusum_drift_sigma},
          {"cusum_threshold_sigma", c.cusum_threshold_sigma},
          {"wear_increase", c.wear_increase},
          {"wear_ewma_gain", c.wear_ewma_gain},
          {"breakage_fraction", c.breakage_fraction},
          {"sensor_bad_fraction", c.sensor_bad_fraction}};
}

void AlertEngine::rebaseline() {
  baseline_n_ = 0;
  baseline_sum_ = baseline_sum_sq_ = baseline_peak_sum_ = 0.0;
  baseline_min_ratio_ = 1.0;
  cusum_high_ = cusum_low_ = 0.0;
  peak_ewma_ = 0.0;
}

void AlertEngine::emit(AlertKind kind, AlertSeverity severity, bool active, std::int64_t revolution,
                       std::int64_t utime_us, double value, double threshold,
                       std::string_view quantity, const char* format, double a, double b) {
  if (pending_count_ >= static_cast<int>(pending_.size())) {
    return;
  }
  Alert& alert = pending_[static_cast<std::size_t>(pending_count_++)];
  alert.kind = kind;
  alert.severity = severity;
  alert.active = active;
  alert.revolution = revolution;
  alert.utime_us = utime_us;
  alert.value = value;
  alert.threshold = threshold;
  alert.quantity = quantity;
  std::snprintf(alert.message.data(), alert.message.size(), format, a, b);
}

void AlertEngine::examine(const RevolutionRecord& r) {
  const RevolutionMeasurement& m = r.measured;
  if (!m.valid || m.flutes < 2) {
    return;
  }
  const Imbalance now = imbalance(m);
  const std::int64_t rev = r.revolution;
  const std::int64_t t = r.utime_us;

  // Runout: imbalance persists above threshold.
  const double limit = config_.runout_imbalance;
  if (!runout_.active) {
    runout_.streak = now.ratio > limit ? runout_.streak + 1 : 0;
    if (runout_.streak >= config_.persist_revolutions) {
      runout_.active = true;
      emit(AlertKind::kRunout, AlertSeverity::kWarning, true, rev, t, now.ratio, limit,
           "flute_imbalance",
           "runout: flute peak forces differ by %.0f %% of their mean (limit %.0f %%)",
           100.0 * now.ratio, 100.0 * limit);
    }
  } else {
    runout_.streak = now.ratio < config_.hysteresis * limit ? runout_.streak + 1 : 0;
    if (runout_.streak >= config_.persist_revolutions) {
      runout_.active = false;
      runout_.streak = 0;
      emit(AlertKind::kRunout, AlertSeverity::kInfo, false, rev, t, now.ratio, limit,
           "flute_imbalance", "runout cleared: flute imbalance %.0f %% (limit %.0f %%)",
           100.0 * now.ratio, 100.0 * limit);
    }
  }

  // Baseline of the first valid revolutions.
  if (baseline_n_ < config_.baseline_revolutions) {
    ++baseline_n_;
    baseline_sum_ += now.ratio;
    baseline_sum_sq_ += now.ratio * now.ratio;
    baseline_peak_sum_ += now.mean_N;
    baseline_min_ratio_ = std::min(baseline_min_ratio_, now.min_over_max);
    peak_ewma_ = baseline_peak_sum_ / baseline_n_;
    return;
  }
  const double mean = baseline_sum_ / baseline_n_;
  const double sigma = std::max(
      std::sqrt(std::max(0.0, baseline_sum_sq_ / baseline_n_ - mean * mean)), 0.01 * mean + 1e-6);
  const double peak_baseline = baseline_peak_sum_ / baseline_n_;

  // Runout change: two-sided CUSUM of the standardised imbalance.
  const double z = (now.ratio - mean) / sigma;
  cusum_high_ = std::max(0.0, cusum_high_ + z - config_.cusum_drift_sigma);
  cusum_low_ = std::max(0.0, cusum_low_ - z - config_.cusum_drift_sigma);
  const double cusum = std::max(cusum_high_, cusum_low_);
  if (!change_.active && cusum > config_.cusum_threshold_sigma) {
    change_.active = true;
    emit(AlertKind::kRunoutChange, AlertSeverity::kWarning, true, rev, t, now.ratio, mean,
         "flute_imbalance", "runout change: flute imbalance now %.0f %%, was %.0f %%",
         100.0 * now.ratio, 100.0 * mean);
  } else if (change_.active && cusum < 0.5 * config_.cusum_drift_sigma) {
    change_.active = false;
    emit(AlertKind::kRunoutChange, AlertSeverity::kInfo, false, rev, t, now.ratio, mean,
         "flute_imbalance", "runout change cleared: imbalance %.0f %% (baseline %.0f %%)",
         100.0 * now.ratio, 100.0 * mean);
  }

  // Wear drift: the mean peak force creeps up.
  peak_ewma_ += config_.wear_ewma_gain * (now.mean_N - peak_ewma_);
  const double rise = peak_ewma_ / peak_baseline - 1.0;
  if (!wear_.active && rise > config_.wear_increase) {
    wear_.active = true;
    emit(AlertKind::kWearDrift, AlertSeverity::kWarning, true, rev, t, rise, config_.wear_increase,
         "peak_force_rise",
         "wear drift: mean peak force %.0f %% above its baseline (limit %.0f %%)", 100.0 * rise,
         100.0 * config_.wear_increase);
  } else if (wear_.active && rise < config_.hysteresis * config_.wear_increase) {
    wear_.active = false;
    emit(AlertKind::kWearDrift, AlertSeverity::kInfo, false, rev, t, rise, config_.wear_increase,
         "peak_force_rise",
         "wear drift cleared: mean peak force %.0f %% above baseline (limit %.0f %%)", 100.0 * rise,
         100.0 * config_.wear_increase);
  }

  // Breakage: a flute that cut in the baseline stops cutting.
  if (baseline_min_ratio_ > 2.0 * config_.breakage_fraction) {
    const bool broken = now.min_over_max < config_.breakage_fraction;
    if (!breakage_.active) {
      breakage_.streak = broken ? breakage_.streak + 1 : 0;
      if (breakage_.streak >= config_.persist_revolutions) {
        breakage_.active = true;
        emit(AlertKind::kBreakage, AlertSeverity::kAlarm, true, rev, t, now.min_over_max,
             config_.breakage_fraction, "weakest_flute_ratio",
             "breakage: weakest flute cuts %.0f %% of the strongest (limit %.0f %%)",
             100.0 * now.min_over_max, 100.0 * config_.breakage_fraction);
      }
    }
  }
}

void AlertEngine::examine(const InputCounters& c, std::int64_t utime_us) {
  const std::int64_t bad = c.samples_flagged;
  const std::int64_t samples = c.samples_in;
  const std::int64_t new_samples = samples - last_samples_;
  const double fraction =
      new_samples > 0 ? static_cast<double>(bad - last_bad_) / static_cast<double>(new_samples)
                      : 0.0;
  const bool gaps = c.gaps > last_gaps_;
  last_bad_ = bad;
  last_samples_ = samples;
  last_gaps_ = c.gaps;
  const bool trouble = fraction > config_.sensor_bad_fraction || gaps;
  if (trouble && !sensor_.active) {
    sensor_.active = true;
    emit(AlertKind::kSensor, AlertSeverity::kWarning, true, 0, utime_us, fraction,
         config_.sensor_bad_fraction, "bad_sample_fraction",
         "sensor trouble: %.2f %% of recent samples saturated or not finite, gaps %.0f",
         100.0 * fraction, static_cast<double>(c.gaps));
  } else if (!trouble && sensor_.active && new_samples > 0) {
    sensor_.active = false;
    emit(AlertKind::kSensor, AlertSeverity::kInfo, false, 0, utime_us, fraction,
         config_.sensor_bad_fraction, "bad_sample_fraction",
         "sensor trouble cleared: %.2f %% bad samples, gaps %.0f", 100.0 * fraction,
         static_cast<double>(c.gaps));
  }
}

}  // namespace millwatch::monitor
