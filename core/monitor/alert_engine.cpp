#include "core/monitor/alert_engine.hpp"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numbers>
#include <span>

#include "core/config/json_reader.hpp"
#include "core/identify/identifier.hpp"
#include "core/monitor/input_check.hpp"
#include "core/monitor/revolution_record.hpp"

namespace millwatch::monitor {
namespace {

constexpr auto kFlutes = static_cast<std::size_t>(kMaxFlutes);
constexpr int kStepRevolutionsMax = 32;  // AlertEngine::kStepRevolutions
constexpr int kBaselineWindowsMax = 64;  // AlertEngine::kRecentWindows

std::size_t at(int i) {
  return static_cast<std::size_t>(i);
}

/// "≥ " before a value that is a lower bound (ρ of a fit on a flute's contact edge), else "".
const char* at_least(bool lower_bound) {
  return lower_bound ? "≥ " : "";
}

/// Writes an alert's operator line (printf format; truncated to the message's size).
__attribute__((format(printf, 2, 3))) void write_message(Alert* alert, const char* format, ...) {
  if (alert == nullptr) {
    return;
  }
  std::va_list args;
  va_start(args, format);
  const int length = std::vsnprintf(alert->message.data(), alert->message.size(), format, args);
  va_end(args);
  if (length >= static_cast<int>(alert->message.size())) {
    // Truncated: drop a multi-byte character cut in half (UTF-8 continuation bytes 10xxxxxx).
    std::size_t end = alert->message.size() - 1;
    while (end > 0 && (static_cast<unsigned char>(alert->message[end - 1]) & 0xC0) == 0x80) {
      --end;
    }
    if (end > 0 && (static_cast<unsigned char>(alert->message[end - 1]) & 0x80) != 0) {
      --end;  // the lead byte of the cut character
    }
    alert->message[end] = '\0';
  }
}

double percent(double fraction) {
  return 100.0 * fraction;
}

double degrees(double rad) {
  return rad * 180.0 / std::numbers::pi;
}

/// A parameter name with its unit for the operator: "k_tc_N_per_mm2" → "k_tc" and "N/mm²",
/// "k_tc_Nmm" (power law) → "k_tc" and "N/mm^(1+a)".
void split_unit(const char* name, char (&symbol)[32], char (&unit)[32]) {
  const char* u = std::strstr(name, "_N");
  const std::size_t length = u != nullptr ? static_cast<std::size_t>(u - name) : std::strlen(name);
  std::snprintf(symbol, sizeof symbol, "%.*s", static_cast<int>(length), name);
  unit[0] = '\0';
  if (u == nullptr) {
    return;
  }
  const char* rest = u + 1;
  struct Known {
    const char* name;
    const char* text;
  };
  for (const Known& k : {Known{"N_per_mm3", "N/mm³"}, Known{"N_per_mm2", "N/mm²"},
                         Known{"N_per_mm", "N/mm"}, Known{"Nmm", "N/mm^(1+a)"}}) {
    if (std::strcmp(rest, k.name) == 0) {
      std::snprintf(unit, sizeof unit, "%s", k.text);
      return;
    }
  }
  std::snprintf(unit, sizeof unit, "%s", rest);
}

/// z with P(|Z| > z) = p for both sides together (p clamped to a meaningful range).
double two_sided_quantile(double p) {
  return normal_upper_quantile(std::clamp(0.5 * p, 1e-300, 0.25));
}

/// A revolution's speed, or 0 when it has none (not measured, not finite).
double known_rpm(double rpm) {
  return rpm > 0.0 && std::isfinite(rpm) ? rpm : 0.0;
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
  c.block_revolutions = r.integer("block_revolutions", c.block_revolutions, 1, 250);
  c.baseline_blocks = r.integer("baseline_blocks", c.baseline_blocks, 10, 400);
  c.false_alarm_revolutions = r.number("false_alarm_revolutions", c.false_alarm_revolutions,
                                       config::closed(1e3, 1e15, "revolutions"));
  c.cusum_k = r.number("cusum_k", c.cusum_k, config::positive(5.0));
  c.baseline_margin = r.number("baseline_margin", c.baseline_margin, config::non_negative(10.0));
  c.sigma_floor = r.number("sigma_floor", c.sigma_floor, config::positive(1.0));
  c.runout_change_min =
      r.number("runout_change_min", c.runout_change_min, config::non_negative(2.0));
  c.runout_step_min = r.number("runout_step_min", c.runout_step_min, config::positive(2.0));
  c.runout_step_revolutions =
      r.integer("runout_step_revolutions", c.runout_step_revolutions, 1, kStepRevolutionsMax);
  c.wear_increase = r.number("wear_increase", c.wear_increase, config::positive(10.0));
  c.breakage_fraction =
      r.number("breakage_fraction", c.breakage_fraction, {0.0, 1.0, true, true, ""});
  c.sensor_bad_fraction =
      r.number("sensor_bad_fraction", c.sensor_bad_fraction, config::positive(1.0));
  c.runout_feed_fraction =
      r.number("runout_feed_fraction", c.runout_feed_fraction, config::positive(2.0));
  c.estimate_sigmas = r.number("estimate_sigmas", c.estimate_sigmas, config::non_negative(10.0));
  c.estimate_windows = r.integer("estimate_windows", c.estimate_windows, 1, 100);
  c.estimate_baseline_windows =
      r.integer("estimate_baseline_windows", c.estimate_baseline_windows, 3, kBaselineWindowsMax);
  c.runout_change_min_um =
      r.number("runout_change_min_um", c.runout_change_min_um, config::non_negative(100.0, "um"));
  c.coefficient_increase =
      r.number("coefficient_increase", c.coefficient_increase, config::positive(10.0));
  c.conditions_tolerance =
      r.number("conditions_tolerance", c.conditions_tolerance, config::positive(1.0));
  r.finish();
  return c;
}

nlohmann::json to_json(const AlertConfig& c) {
  return {{"runout_imbalance", c.runout_imbalance},
          {"persist_revolutions", c.persist_revolutions},
          {"hysteresis", c.hysteresis},
          {"block_revolutions", c.block_revolutions},
          {"baseline_blocks", c.baseline_blocks},
          {"false_alarm_revolutions", c.false_alarm_revolutions},
          {"cusum_k", c.cusum_k},
          {"baseline_margin", c.baseline_margin},
          {"sigma_floor", c.sigma_floor},
          {"runout_change_min", c.runout_change_min},
          {"runout_step_min", c.runout_step_min},
          {"runout_step_revolutions", c.runout_step_revolutions},
          {"wear_increase", c.wear_increase},
          {"breakage_fraction", c.breakage_fraction},
          {"sensor_bad_fraction", c.sensor_bad_fraction},
          {"runout_feed_fraction", c.runout_feed_fraction},
          {"estimate_sigmas", c.estimate_sigmas},
          {"estimate_windows", c.estimate_windows},
          {"estimate_baseline_windows", c.estimate_baseline_windows},
          {"runout_change_min_um", c.runout_change_min_um},
          {"coefficient_increase", c.coefficient_increase},
          {"conditions_tolerance", c.conditions_tolerance}};
}

AlertEngine::AlertEngine(const AlertConfig& config) : config_(config) {
  const auto block = static_cast<std::size_t>(std::max(config_.block_revolutions, 1));
  const auto revolutions = block * static_cast<std::size_t>(std::max(config_.baseline_blocks, 1));
  baseline_force_N_.assign(revolutions * kFlutes, 0.0);
  baseline_rpm_.assign(revolutions, 0.0);
  series_.assign(revolutions, 0.0);
  scratch_.assign(revolutions, 0.0);
  block_medians_.assign(static_cast<std::size_t>(std::max(config_.baseline_blocks, 1)), 0.0);
  block_values_.assign((kFlutes + 1) * block, 0.0);
  static_assert(kStepRevolutionsMax == kStepRevolutions && kBaselineWindowsMax == kRecentWindows);
  recent_rpm_revolution_.fill(-1);
}

void AlertEngine::rebaseline() {
  baseline_ = Baseline{};
  flutes_ = 0;
  baseline_count_ = 0;
  reforming_ = false;
  block_count_ = 0;
  recent_count_ = 0;
  recent_next_ = 0;
  for (int j = 0; j < kMaxFlutes; ++j) {
    change_up_[at(j)].reset();
    change_down_[at(j)].reset();
  }
  change_clear_.reset();
  wear_raise_.reset();
  wear_clear_.reset();
  breakage_.streak = 0;
  imbalance_high_ = false;
  imbalance_above_run_ = imbalance_below_run_ = 0;
  step_streak_.fill(0);
  change_identify_ = false;
  restart_estimate_baseline();
  rebaselined_ = true;
}

Alert* AlertEngine::emit(AlertKind kind, AlertSeverity severity, bool active,
                         std::int64_t revolution, std::int64_t utime_us, double value,
                         double threshold, std::string_view quantity) {
  if (pending_count_ >= static_cast<int>(pending_.size())) {
    return nullptr;
  }
  Alert& alert = pending_[at(pending_count_++)];
  alert.kind = kind;
  alert.severity = severity;
  alert.active = active;
  alert.revolution = revolution;
  alert.utime_us = utime_us;
  alert.value = value;
  alert.threshold = threshold;
  alert.quantity = quantity;
  alert.message[0] = '\0';
  if (active) {
    raised_[static_cast<std::size_t>(kind)] = Raised{value, threshold, quantity};
  }
  return &alert;
}

void AlertEngine::examine(const RevolutionRecord& r) {
  const RevolutionMeasurement& m = r.measured;
  last_revolution_ = std::max(last_revolution_, r.revolution);
  last_utime_us_ = std::max(last_utime_us_, r.utime_us);
  if (r.spindle_rpm > 0.0 && std::isfinite(r.spindle_rpm) && r.revolution >= 0) {
    const auto slot = static_cast<std::size_t>(r.revolution % kRecentRevolutions);
    recent_rpm_[slot] = r.spindle_rpm;
    recent_rpm_revolution_[slot] = r.revolution;
  }
  // A bounded revolution has each flute's force even when a flute left no event (a broken one).
  if (!m.bounded || m.flutes < 2 || m.flutes > kMaxFlutes) {
    return;
  }
  Flutes f;
  f.count = m.flutes;
  double lo = 0.0, hi = 0.0, sum = 0.0;
  for (int j = 0; j < f.count; ++j) {
    const auto& range = m.range_N[at(j)];
    const double force = std::sqrt(range[0] * range[0] + range[1] * range[1] + range[2] * range[2]);
    f.force_N[at(j)] = force;
    lo = j == 0 ? force : std::min(lo, force);
    hi = j == 0 ? force : std::max(hi, force);
    sum += force;
  }
  f.mean_N = sum / f.count;
  if (!std::isfinite(f.mean_N) || f.mean_N <= 0.0) {
    return;
  }
  f.imbalance = (hi - lo) / f.mean_N;
  for (int j = 0; j < f.count; ++j) {
    f.share[at(j)] = f.force_N[at(j)] / f.mean_N - 1.0;
  }
  const std::int64_t rev = r.revolution;
  const std::int64_t t = r.utime_us;

  if (rebaselined_) {
    clear_after_rebaseline(rev, t, "new baseline");
  }
  if (flutes_ != 0 && f.count != flutes_) {
    rebaseline();  // another tool
    clear_after_rebaseline(rev, t, "new baseline");
  }
  track_imbalance(f);
  if (!follow_estimates()) {
    check_runout(f, rev, t);
  }
  if (!baseline_.ready) {
    add_to_baseline(f, r.spindle_rpm);
    return;
  }
  if (!same_speed(r.spindle_rpm, baseline_.spindle_rpm)) {
    // Another feed per tooth: the shares and the mean force are not comparable with the
    // baseline's. Held, and the revolution counts towards a baseline at its speed.
    if (!reforming_) {
      reforming_ = true;
      baseline_count_ = 0;
    }
    ++held_revolutions_;
    check_breakage(f, rev, t);
    add_to_baseline(f, r.spindle_rpm);
    return;
  }
  reforming_ = false;  // back at the baseline's speed before a new one was complete
  const bool collapsing = check_breakage(f, rev, t);
  check_runout_step(f, collapsing, rev, t);
  add_to_block(f, rev, t);
}

void AlertEngine::expect_estimates(bool expected) {
  estimates_expected_ = expected;
  if (!expected && estimates_) {
    estimates_ = false;  // back to the flute forces until the next window
    runout_.streak = 0;  // counted in revolutions again
  }
}

void AlertEngine::check_runout(const Flutes& f, std::int64_t rev, std::int64_t t) {
  const double limit = config_.runout_imbalance;
  const int persist = config_.persist_revolutions;
  if (!runout_.active) {
    runout_.streak = f.imbalance > limit ? runout_.streak + 1 : 0;
    if (runout_.streak >= persist) {
      runout_.active = true;
      runout_.streak = 0;
      write_message(emit(AlertKind::kRunout, AlertSeverity::kWarning, true, rev, t, f.imbalance,
                         limit, "flute_imbalance"),
                    "runout: flute forces differ by %.2f %% of their mean (limit %.2f %%, %d "
                    "revolutions)",
                    percent(f.imbalance), percent(limit), persist);
    }
    return;
  }
  const double clear_below = config_.hysteresis * limit;
  runout_.streak = f.imbalance < clear_below ? runout_.streak + 1 : 0;
  if (runout_.streak >= persist) {
    runout_.active = false;
    runout_.streak = 0;
    write_message(emit(AlertKind::kRunout, AlertSeverity::kInfo, false, rev, t, f.imbalance, limit,
                       "flute_imbalance"),
                  "runout cleared: flute imbalance %.2f %% (below %.2f %% for %d revolutions)",
                  percent(f.imbalance), percent(clear_below), persist);
  }
}

void AlertEngine::track_imbalance(const Flutes& f) {
  const double limit = config_.runout_imbalance;
  const int persist = config_.persist_revolutions;
  imbalance_above_run_ = f.imbalance > limit ? std::min(imbalance_above_run_ + 1, persist) : 0;
  imbalance_below_run_ =
      f.imbalance < config_.hysteresis * limit ? std::min(imbalance_below_run_ + 1, persist) : 0;
  if (imbalance_above_run_ == persist) {
    imbalance_high_ = true;
    imbalance_above_ = f.imbalance;
  }
  if (imbalance_below_run_ == persist) {
    imbalance_high_ = false;
    imbalance_below_ = f.imbalance;
  }
}

bool AlertEngine::same_speed(double rpm, double reference_rpm) const {
  const bool known = known_rpm(rpm) > 0.0 && reference_rpm > 0.0;
  return !known || std::fabs(rpm / reference_rpm - 1.0) <= config_.conditions_tolerance;
}

void AlertEngine::add_to_baseline(const Flutes& f, double rpm) {
  if (baseline_count_ > 0 && !same_speed(rpm, baseline_rpm_[0])) {
    baseline_count_ = 0;  // the speed moved on: start again at this one
  }
  baseline_rpm_[at(baseline_count_)] = known_rpm(rpm);
  flutes_ = f.count;
  std::copy(f.force_N.begin(), f.force_N.end(),
            baseline_force_N_.begin() + static_cast<std::ptrdiff_t>(at(baseline_count_) * kFlutes));
  ++baseline_count_;
  if (baseline_count_ == config_.block_revolutions * config_.baseline_blocks) {
    finish_baseline();
  }
}

void AlertEngine::finish_baseline() {
  const int n = baseline_count_;
  const int block = config_.block_revolutions;
  const int blocks = config_.baseline_blocks;
  const int flutes = flutes_;
  const std::span<double> series = std::span(series_).first(at(n));
  const std::span<double> scratch(scratch_);
  auto force = [&](int i, int j) { return baseline_force_N_[at(i) * kFlutes + at(j)]; };
  auto mean_force = [&](int i) {
    double sum = 0.0;
    for (int j = 0; j < flutes; ++j) {
      sum += force(i, j);
    }
    return sum / flutes;
  };
  auto max_force = [&](int i) {
    double hi = 0.0;
    for (int j = 0; j < flutes; ++j) {
      hi = std::max(hi, force(i, j));
    }
    return hi;
  };
  // σ of a block median of `series`: the AR(1) figure from the single revolutions, or the
  // spread of the baseline's own block medians, whichever is larger.
  auto block_sigma = [&](const RobustSummary& s) {
    for (int b = 0; b < blocks; ++b) {
      const auto first = series.begin() + static_cast<std::ptrdiff_t>(at(b) * at(block));
      std::copy(first, first + block, scratch.begin());
      block_medians_[at(b)] = median_in_place(scratch.first(at(block)));
    }
    const RobustSummary spread = robust_summary(block_medians_, scratch);
    return std::max(ar1_block_median_sigma(s.sigma, s.rho1, block), spread.sigma);
  };

  Baseline& base = baseline_;
  base = Baseline{};
  base.flutes = flutes;
  // The speed: the median of the revolutions' that have one.
  int known = 0;
  for (int i = 0; i < n; ++i) {
    if (baseline_rpm_[at(i)] > 0.0) {
      series[at(known++)] = baseline_rpm_[at(i)];
    }
  }
  base.spindle_rpm = known > 0 ? median_in_place(series.first(at(known))) : 0.0;
  reforming_ = false;
  // Mean flute force and its relative rise.
  for (int i = 0; i < n; ++i) {
    series[at(i)] = mean_force(i);
  }
  base.mean_force_N = robust_summary(series, scratch).median;
  for (int i = 0; i < n; ++i) {
    series[at(i)] = series[at(i)] / base.mean_force_N - 1.0;
  }
  base.rise_sigma = std::max(block_sigma(robust_summary(series, scratch)), config_.sigma_floor);
  // Shares, and strengths relative to the strongest flute.
  const double arl_blocks = config_.false_alarm_revolutions / block;
  const double margin = config_.baseline_margin / std::sqrt(static_cast<double>(blocks));
  const int detectors = flutes == 2 ? 1 : flutes;
  breakage_z_ = normal_upper_quantile(1.0 / (config_.false_alarm_revolutions * flutes));
  step_z_ = two_sided_quantile(1.0 / (config_.false_alarm_revolutions * detectors));
  for (int j = 0; j < flutes; ++j) {
    for (int i = 0; i < n; ++i) {
      series[at(i)] = force(i, j) / mean_force(i) - 1.0;
    }
    const RobustSummary share = robust_summary(series, scratch);
    base.share[at(j)] = share.median;
    base.share_sigma[at(j)] = std::max(block_sigma(share), config_.sigma_floor);
    const double k_relevant =
        std::max(config_.cusum_k, 0.5 * config_.runout_change_min / base.share_sigma[at(j)]);
    base.change_allowance[at(j)] = k_relevant + margin;
    base.change_threshold[at(j)] = cusum_threshold_for(k_relevant, 2.0 * arl_blocks * detectors);
    base.step_limit[at(j)] =
        std::max(step_z_ * std::max(share.sigma, config_.sigma_floor), config_.runout_step_min);
    change_up_[at(j)] = Cusum(base.change_allowance[at(j)], base.change_threshold[at(j)]);
    change_down_[at(j)] = change_up_[at(j)];

    for (int i = 0; i < n; ++i) {
      series[at(i)] = force(i, j) / max_force(i);
    }
    const RobustSummary strength = robust_summary(series, scratch);
    base.strength[at(j)] = strength.median;
    const double sigma_q = strength.median > 0.0 ? strength.sigma / strength.median : 1.0;
    base.breakage_limit[at(j)] = std::min(config_.breakage_fraction, 1.0 - breakage_z_ * sigma_q);
  }
  base.wear_allowance = config_.cusum_k + margin;
  base.wear_threshold = cusum_threshold_for(config_.cusum_k, arl_blocks);
  wear_raise_ = Cusum(base.wear_allowance, base.wear_threshold);
  wear_clear_ = Cusum(config_.cusum_k, base.wear_threshold);
  block_count_ = 0;
  recent_count_ = 0;
  recent_next_ = 0;
  step_streak_.fill(0);
  base.ready = true;
}

void AlertEngine::add_to_block(const Flutes& f, std::int64_t rev, std::int64_t t) {
  const auto block = at(config_.block_revolutions);
  const auto i = at(block_count_);
  for (int j = 0; j < f.count; ++j) {
    block_values_[at(j) * block + i] = f.share[at(j)];
  }
  block_values_[kFlutes * block + i] = f.mean_N;
  if (++block_count_ < config_.block_revolutions) {
    return;
  }
  block_count_ = 0;
  Block b;
  const std::span<double> values(block_values_);
  for (int j = 0; j < f.count; ++j) {
    b.share[at(j)] = median_in_place(values.subspan(at(j) * block, block));
  }
  b.mean_N = median_in_place(values.subspan(kFlutes * block, block));
  recent_[at(recent_next_)] = b;
  recent_next_ = (recent_next_ + 1) % kRecentBlocks;
  recent_count_ = std::min(recent_count_ + 1, kRecentBlocks);
  check_runout_change(b, rev, t);
  // With estimates the coefficients tell wear; the flute forces only clear what they raised.
  if (!follow_estimates() || (wear_active_ && !wear_from_estimates_)) {
    check_wear(b, rev, t);
  }
}

AlertEngine::Block AlertEngine::recent_mean(int blocks) const {
  const int n = std::clamp(blocks, 1, std::max(recent_count_, 1));
  Block mean;
  for (int q = 0; q < n; ++q) {
    const Block& b = recent_[at((recent_next_ - 1 - q + 2 * kRecentBlocks) % kRecentBlocks)];
    for (int j = 0; j < flutes_; ++j) {
      mean.share[at(j)] += b.share[at(j)] / n;
    }
    mean.mean_N += b.mean_N / n;
  }
  return mean;
}

void AlertEngine::check_runout_change(const Block& b, std::int64_t rev, std::int64_t t) {
  const Baseline& base = baseline_;
  auto imbalance = [&](const std::array<double, kMaxFlutes>& share) {
    const auto first = share.begin();
    const auto last = first + flutes_;
    return *std::max_element(first, last) - *std::min_element(first, last);
  };
  const double before = imbalance(base.share);
  const int block = config_.block_revolutions;

  if (change_active_) {
    if (change_source_ == ChangeSource::kEstimate) {
      return;  // cleared by the estimates
    }
    if (rev - block + 1 <= change_onset_) {
      return;  // a block that began before the change (raised per revolution) is not "after"
    }
    const auto j = at(change_flute_);
    const double sigma = base.share_sigma[j];
    const double deviation = change_side_ * (b.share[j] - base.share[j]);
    const double inside = config_.hysteresis * base.change_allowance[j] * sigma;
    if (change_clear_.update((inside - deviation) / sigma)) {
      change_active_ = false;
      change_identify_ = false;
      for (int q = 0; q < kMaxFlutes; ++q) {
        change_up_[at(q)].reset();
        change_down_[at(q)].reset();
      }
      step_streak_.fill(0);
      const Block now = recent_mean(change_clear_.run());
      write_message(
          emit(AlertKind::kRunoutChange, AlertSeverity::kInfo, false, rev, t, imbalance(now.share),
               before, "flute_imbalance"),
          "runout change cleared: flute imbalance %.2f %% (baseline %.2f %%, over %d revolutions)",
          percent(imbalance(now.share)), percent(before), change_clear_.run() * block);
    }
    return;
  }
  if (breakage_.active) {
    return;  // a broken flute changes the shares: breakage says it
  }
  const int detectors = flutes_ == 2 ? 1 : flutes_;
  for (int q = 0; q < detectors; ++q) {
    const auto j = at(q);
    const double z = (b.share[j] - base.share[j]) / base.share_sigma[j];
    const bool up = change_up_[j].update(z);
    const bool down = change_down_[j].update(-z);
    if (change_active_ || !(up || down)) {
      continue;
    }
    // Confirmed on the excursion's blocks after its first, which may straddle the change.
    const int side = up ? 1 : -1;
    const int run = up ? change_up_[j].run() : change_down_[j].run();
    if (run < 2) {
      continue;
    }
    const int blocks_after = std::min(run - 1, kRecentBlocks);
    const Block now = recent_mean(blocks_after);
    if (side * (now.share[j] - base.share[j]) <= base.change_allowance[j] * base.share_sigma[j]) {
      continue;
    }
    start_change(ChangeSource::kBlock, q, side, rev - static_cast<std::int64_t>(run) * block + 1);
    const double after = imbalance(now.share);
    write_message(emit(AlertKind::kRunoutChange, AlertSeverity::kWarning, true, rev, t, after,
                       before, "flute_imbalance"),
                  "runout change: flute imbalance %.2f %% → %.2f %% (baseline %.2f ± %.2f %%; "
                  "flute %d %+.2f %% → %+.2f %% of the mean flute force; over %d revolutions)",
                  percent(before), percent(after), percent(before),
                  percent(2.0 * base.share_sigma[j]), q + 1, percent(base.share[j]),
                  percent(now.share[j]), blocks_after * block);
  }
}

void AlertEngine::start_change(ChangeSource source, int flute, int side, std::int64_t onset) {
  change_active_ = true;
  change_source_ = source;
  change_flute_ = flute;
  change_side_ = side;
  change_onset_ = onset;
  change_clear_ = Cusum(config_.cusum_k, baseline_.change_threshold[at(flute)]);
  for (int q = 0; q < kMaxFlutes; ++q) {
    change_up_[at(q)].reset();
    change_down_[at(q)].reset();
  }
  step_streak_.fill(0);
  window_streak_.fill(0);
  // The estimates say what changed once a window wholly after the onset is fitted. A baseline of
  // them still gathering would mix both states: it starts again.
  change_identify_ = true;
  if (!estimate_base_.ready) {
    restart_estimate_baseline();
  }
}

void AlertEngine::check_runout_step(const Flutes& f, bool collapsing, std::int64_t rev,
                                    std::int64_t t) {
  step_shares_[at(step_next_)] = f.share;
  step_next_ = (step_next_ + 1) % kStepRevolutions;
  if (change_active_) {
    return;
  }
  const Baseline& base = baseline_;
  const int detectors = flutes_ == 2 ? 1 : flutes_;
  const int persist = config_.runout_step_revolutions;
  for (int q = 0; q < detectors; ++q) {
    const auto j = at(q);
    const double deviation = f.share[j] - base.share[j];
    const int side = deviation > base.step_limit[j] ? 1 : deviation < -base.step_limit[j] ? -1 : 0;
    if (side == 0 || side != step_side_[j]) {
      step_side_[j] = side;
      step_streak_[j] = side != 0 ? 1 : 0;
    } else {
      ++step_streak_[j];
    }
    // A flute collapsing is breakage, not runout: it waits for the breakage detector.
    if (step_streak_[j] < persist || collapsing || breakage_.active) {
      continue;
    }
    // The revolutions of the run: their mean shares are the "after".
    std::array<double, kMaxFlutes> after{};
    for (int b = 0; b < persist; ++b) {
      const auto& shares =
          step_shares_[at((step_next_ - 1 - b + 2 * kStepRevolutions) % kStepRevolutions)];
      for (int k = 0; k < flutes_; ++k) {
        after[at(k)] += shares[at(k)] / persist;
      }
    }
    auto imbalance = [&](const std::array<double, kMaxFlutes>& share) {
      const auto first = share.begin();
      const auto last = first + flutes_;
      return *std::max_element(first, last) - *std::min_element(first, last);
    };
    const double before = imbalance(base.share);
    const double now = imbalance(after);
    start_change(ChangeSource::kRevolution, q, side, rev - persist + 1);
    Alert* a = emit(AlertKind::kRunoutChange, AlertSeverity::kWarning, true, rev, t, now, before,
                    "flute_imbalance");
    if (estimate_base_.ready) {
      write_message(a,
                    "runout change: flute imbalance %.2f %% → %.2f %% (flute %d %+.2f %% → %+.2f "
                    "%% of the mean flute force, limit ± %.2f %%; %d revolutions); identified "
                    "before: r_CE1 − r_CE2 %.3f ± %.3f µm",
                    percent(before), percent(now), q + 1, percent(base.share[j]), percent(after[j]),
                    percent(base.step_limit[j]), persist, -estimate_base_.radius_difference_um[1],
                    estimate_base_.radius_total_sigma_um[1]);
    } else {
      write_message(a,
                    "runout change: flute imbalance %.2f %% → %.2f %% (flute %d %+.2f %% → %+.2f "
                    "%% of the mean flute force, limit ± %.2f %%; %d revolutions)",
                    percent(before), percent(now), q + 1, percent(base.share[j]), percent(after[j]),
                    percent(base.step_limit[j]), persist);
    }
    return;
  }
}

void AlertEngine::check_wear(const Block& b, std::int64_t rev, std::int64_t t) {
  const Baseline& base = baseline_;
  const double limit = config_.wear_increase;
  const double rise = b.mean_N / base.mean_force_N - 1.0;
  const int block = config_.block_revolutions;
  if (!wear_active_) {
    // Confirmed, as a runout change, on the excursion's blocks after its first.
    if (!wear_raise_.update((rise - limit) / base.rise_sigma) || wear_raise_.run() < 2) {
      return;
    }
    const int blocks_after = std::min(wear_raise_.run() - 1, kRecentBlocks);
    const double now_N = recent_mean(blocks_after).mean_N;
    const double now_rise = now_N / base.mean_force_N - 1.0;
    if (now_rise <= limit) {
      return;
    }
    wear_active_ = true;
    wear_from_estimates_ = false;
    wear_clear_.reset();
    write_message(emit(AlertKind::kWearDrift, AlertSeverity::kWarning, true, rev, t, now_rise,
                       limit, "flute_force_rise"),
                  "wear drift: mean flute force %.3f N → %.3f N (%+.1f %%, limit %+.1f %%; "
                  "baseline ± %.2f %%, over %d revolutions)",
                  base.mean_force_N, now_N, percent(now_rise), percent(limit),
                  percent(base.rise_sigma), blocks_after * block);
    return;
  }
  const double clear_below = config_.hysteresis * limit;
  if (wear_clear_.update((clear_below - rise) / base.rise_sigma)) {
    wear_active_ = false;
    wear_raise_.reset();
    const int run = std::min(wear_clear_.run(), kRecentBlocks);
    const double now_N = recent_mean(run).mean_N;
    write_message(emit(AlertKind::kWearDrift, AlertSeverity::kInfo, false, rev, t,
                       now_N / base.mean_force_N - 1.0, limit, "flute_force_rise"),
                  "wear drift cleared: mean flute force %.3f N (%+.1f %% over the baseline "
                  "%.3f N, below %+.1f %%)",
                  now_N, percent(now_N / base.mean_force_N - 1.0), base.mean_force_N,
                  percent(clear_below));
  }
}

bool AlertEngine::check_breakage(const Flutes& f, std::int64_t rev, std::int64_t t) {
  const Baseline& base = baseline_;
  double strongest = 0.0;
  for (int j = 0; j < f.count; ++j) {
    strongest = std::max(strongest, f.force_N[at(j)]);
  }
  // The flute furthest below its limit, and whether every flute is back above limit/hysteresis.
  int weakest = 0;
  double weakest_margin = 0.0;
  bool healed = true;
  std::array<double, kMaxFlutes> q{};
  for (int j = 0; j < f.count; ++j) {
    const auto i = at(j);
    q[i] = base.strength[i] > 0.0 ? f.force_N[i] / strongest / base.strength[i] : 1.0;
    const double margin = q[i] - base.breakage_limit[i];
    if (j == 0 || margin < weakest_margin) {
      weakest = j;
      weakest_margin = margin;
    }
    healed = healed && q[i] >= base.breakage_limit[i] / config_.hysteresis;
  }
  const int persist = config_.persist_revolutions;
  const auto w = at(weakest);
  if (!breakage_.active) {
    breakage_.streak = weakest_margin < 0.0 ? breakage_.streak + 1 : 0;
    if (breakage_.streak >= persist) {
      breakage_.active = true;
      breakage_.streak = 0;
      breakage_flute_ = weakest;
      write_message(
          emit(AlertKind::kBreakage, AlertSeverity::kAlarm, true, rev, t, q[w],
               base.breakage_limit[w], "flute_strength_fraction_of_baseline"),
          "breakage: flute %d cuts %.1f %% of the strongest flute's force (baseline %.1f %%), "
          "%.1f %% of its baseline strength (limit %.1f %%, %d revolutions)",
          weakest + 1, percent(f.force_N[w] / strongest), percent(base.strength[w]), percent(q[w]),
          percent(base.breakage_limit[w]), persist);
    }
    return weakest_margin < 0.0;
  }
  breakage_.streak = healed ? breakage_.streak + 1 : 0;
  if (breakage_.streak >= persist) {
    breakage_.active = false;
    breakage_.streak = 0;
    const auto b = at(breakage_flute_);
    write_message(emit(AlertKind::kBreakage, AlertSeverity::kInfo, false, rev, t, q[b],
                       base.breakage_limit[b], "flute_strength_fraction_of_baseline"),
                  "breakage cleared: flute %d back at %.1f %% of its baseline strength (above "
                  "%.1f %% for %d revolutions)",
                  breakage_flute_ + 1, percent(q[b]),
                  percent(base.breakage_limit[b] / config_.hysteresis), persist);
  }
  return weakest_margin < 0.0;
}

void AlertEngine::clear_as_raised(AlertKind kind, const char* what, std::string_view why,
                                  std::int64_t rev, std::int64_t t) {
  const Raised& r = raised_[static_cast<std::size_t>(kind)];
  write_message(emit(kind, AlertSeverity::kInfo, false, rev, t, r.value, r.threshold, r.quantity),
                "%s cleared: %.*s (raised on %.*s %.4g against %.4g)", what,
                static_cast<int>(why.size()), why.data(), static_cast<int>(r.quantity.size()),
                r.quantity.data(), r.value, r.threshold);
}

void AlertEngine::clear_after_rebaseline(std::int64_t rev, std::int64_t t, std::string_view why) {
  rebaselined_ = false;
  // Neither a new baseline nor a successor has a value to compare yet: the clear repeats what
  // the alert was raised on.
  if (change_active_) {
    change_active_ = false;
    change_identify_ = false;
    clear_as_raised(AlertKind::kRunoutChange, "runout change", why, rev, t);
  }
  if (wear_active_) {
    wear_active_ = false;
    clear_as_raised(AlertKind::kWearDrift, "wear drift", why, rev, t);
  }
  if (breakage_.active) {
    breakage_.active = false;
    breakage_.streak = 0;
    clear_as_raised(AlertKind::kBreakage, "breakage", why, rev, t);
  }
}

void AlertEngine::clear_all(std::string_view why) {
  if (runout_.active) {
    runout_.active = false;
    clear_as_raised(AlertKind::kRunout, "runout", why, last_revolution_, last_utime_us_);
  }
  if (sensor_.active) {
    sensor_.active = false;
    clear_as_raised(AlertKind::kSensor, "sensor trouble", why, last_revolution_, last_utime_us_);
  }
  clear_after_rebaseline(last_revolution_, last_utime_us_, why);
}

// ---- Estimates -------------------------------------------------------------------------------

bool AlertEngine::read_window(const identify::IdentifiedWindow& w, WindowEstimate& e) const {
  const identify::FitResult& fit = w.fit;
  const int flutes = fit.config.tool.flutes;
  if (!fit.ok || flutes < 2 || flutes > kMaxFlutes ||
      static_cast<int>(fit.radius_from_ce1_um.size()) != flutes || fit.coefficients.empty()) {
    return false;
  }
  e = WindowEstimate{};
  e.flutes = flutes;
  e.last_revolution = w.revolution;
  e.first_revolution = w.revolution - std::max(w.window_revolutions, 1) + 1;
  // The window's mean actual speed from its revolutions (the fit keeps the commanded one).
  double sum = 0.0;
  int n = 0;
  const std::int64_t from =
      std::max({e.first_revolution, e.last_revolution - kRecentRevolutions + 1, std::int64_t{0}});
  for (std::int64_t r = from; r <= e.last_revolution; ++r) {
    const auto slot = static_cast<std::size_t>(r % kRecentRevolutions);
    if (recent_rpm_revolution_[slot] == r) {
      sum += recent_rpm_[slot];
      ++n;
    }
  }
  const double commanded_rpm = fit.config.process.spindle_rpm;
  e.spindle_rpm = n > 0 ? sum / n : commanded_rpm;
  if (!(e.spindle_rpm > 0.0) || !(commanded_rpm > 0.0)) {
    return false;
  }
  e.feed_per_tooth_um = fit.config.process.feed_per_tooth_um * commanded_rpm / e.spindle_rpm;
  for (int j = 0; j < flutes; ++j) {
    const identify::Estimate& d = fit.radius_from_ce1_um[at(j)];
    e.radius_difference_um[at(j)] = d.value;
    e.radius_sigma_um[at(j)] = d.sigma;
    e.radius_sigma_stat_um[at(j)] = d.sigma_stat;
  }
  e.rho_um = fit.rho_um.value;
  e.rho_sigma_um = fit.rho_um.sigma;
  e.rho_lower_bound = fit.runout_at_contact_edge;
  e.edge_flute = fit.edge_flute;  // −1 off an edge
  e.gamma_rad = fit.gamma_rad.value;
  e.gamma_sigma_rad = fit.gamma_rad.sigma;
  e.coefficients = std::min(static_cast<int>(fit.coefficients.size()), kMaxCoefficients);
  for (int c = 0; c < e.coefficients; ++c) {
    e.coefficient[at(c)] = fit.coefficients[at(c)].value;
    e.coefficient_sigma_stat[at(c)] = fit.coefficients[at(c)].sigma_stat;
  }
  for (double v : {e.feed_per_tooth_um, e.rho_um, e.rho_sigma_um, e.gamma_rad, e.gamma_sigma_rad}) {
    if (!std::isfinite(v)) {
      return false;
    }
  }
  for (int j = 0; j < flutes; ++j) {
    if (!std::isfinite(e.radius_difference_um[at(j)]) || !std::isfinite(e.radius_sigma_um[at(j)])) {
      return false;
    }
  }
  for (int c = 0; c < e.coefficients; ++c) {
    if (!std::isfinite(e.coefficient[at(c)]) || !std::isfinite(e.coefficient_sigma_stat[at(c)])) {
      return false;
    }
  }
  return true;
}

const AlertEngine::WindowEstimate& AlertEngine::recent_window(int back) const {
  return windows_[at((windows_next_ - 1 - back + 2 * kRecentWindows) % kRecentWindows)];
}

void AlertEngine::examine(const identify::IdentifiedWindow& w) {
  if (w.revolution <= last_window_) {
    return;  // out of order
  }
  WindowEstimate e;
  if (!read_window(w, e)) {
    return;
  }
  last_window_ = w.revolution;
  const int flutes = w.fit.config.tool.flutes;
  const std::int64_t rev = std::max(last_revolution_, w.revolution);
  const std::int64_t t = std::max(last_utime_us_, w.utime_us);
  if (!estimates_) {
    estimates_ = true;
    runout_.streak = 0;  // counted in windows from now on
  }
  windows_[at(windows_next_)] = e;
  windows_next_ = (windows_next_ + 1) % kRecentWindows;
  windows_count_ = std::min(windows_count_ + 1, kRecentWindows);

  check_runout_high(e, rev, t);

  // The estimates' baseline holds at one speed and feed, one tool, one set of coefficients.
  EstimateBaseline& base = estimate_base_;
  if (estimate_base_count_ > 0) {
    const double tolerance = config_.conditions_tolerance;
    bool same = base.flutes == flutes && base.coefficients == e.coefficients &&
                std::fabs(e.spindle_rpm / base.spindle_rpm - 1.0) <= tolerance &&
                std::fabs(e.feed_per_tooth_um / base.feed_per_tooth_um - 1.0) <= tolerance;
    for (int c = 0; same && c < e.coefficients; ++c) {
      same = w.fit.coefficients[at(c)].name == base.coefficient_name[at(c)].data();
    }
    if (!same) {
      restart_estimate_baseline();
    }
  }
  if (estimate_base_count_ == 0) {
    base = EstimateBaseline{};
    base.flutes = flutes;
    base.spindle_rpm = e.spindle_rpm;
    base.feed_per_tooth_um = e.feed_per_tooth_um;
    base.coefficients = e.coefficients;
    for (int c = 0; c < e.coefficients; ++c) {
      const std::string& name = w.fit.coefficients[at(c)].name;
      auto& out = base.coefficient_name[at(c)];
      const std::size_t n = std::min(name.size(), out.size() - 1);
      std::memcpy(out.data(), name.data(), n);
      out[n] = '\0';
    }
  }
  if (!base.ready) {
    // A window straddling a change the flute forces raised belongs to neither state.
    if (change_active_ && e.first_revolution <= change_onset_) {
      return;
    }
    add_to_estimate_baseline();
  }
  if (change_active_ && change_identify_ && e.first_revolution > change_onset_) {
    state_change_identified(e, rev, t);
  }
  if (!base.ready) {
    return;
  }
  check_estimate_change(e, rev, t);
  check_coefficient_wear(e, rev, t);
}

void AlertEngine::check_runout_high(const WindowEstimate& e, std::int64_t rev, std::int64_t t) {
  // u = max over flutes j and passes back n of (r_{j−n} − r_j)/n over f_t (header comment).
  const int n_z = e.flutes;
  auto d = [&](int j) { return j == 0 ? 0.0 : e.radius_difference_um[at(j)]; };
  auto sd = [&](int j) { return j == 0 ? 0.0 : e.radius_sigma_um[at(j)]; };
  double deficit = -std::numeric_limits<double>::infinity(), sigma = 0.0;
  int longer = 0, shorter = 1, passes = 1;
  for (int j = 0; j < n_z; ++j) {
    for (int n = 1; n < n_z; ++n) {
      const int a = (j - n + n_z) % n_z;
      const double value = (d(a) - d(j)) / n;
      if (value > deficit) {
        deficit = value;
        sigma = (sd(a) + sd(j)) / n;  // through CE1 one of the two is 0
        longer = a;
        shorter = j;
        passes = n;
      }
    }
  }
  const double ft = e.feed_per_tooth_um;
  const double u = deficit / ft;
  const double sigma_u = sigma / ft;
  if (!runout_first_known_) {
    runout_first_known_ = true;
    runout_first_ratio_ = u;
  }
  const double limit = config_.runout_feed_fraction;
  const double z = config_.estimate_sigmas;
  const int persist = config_.estimate_windows;
  char pair[64];
  if (passes == 1) {
    std::snprintf(pair, sizeof pair, "r_CE%d − r_CE%d", longer + 1, shorter + 1);
  } else {
    std::snprintf(pair, sizeof pair, "(r_CE%d − r_CE%d)/%d", longer + 1, shorter + 1, passes);
  }
  const double clear_below = config_.hysteresis * limit;
  const bool high = u - z * sigma_u > limit;
  const bool low = u + z * sigma_u < clear_below;
  // Cannot tell: the estimate's band reaches from below the clearing level to above the limit
  // (one within the hysteresis band holds the alert as it is). The flute forces' level decides,
  // where revolutions have been measured.
  const bool undecided = u - z * sigma_u < clear_below && u + z * sigma_u > limit;
  const double imbalance_limit = config_.runout_imbalance;
  if (!runout_.active) {
    runout_.streak = high || (undecided && imbalance_high_) ? runout_.streak + 1 : 0;
    if (runout_.streak >= persist && !high) {
      runout_.active = true;
      runout_.streak = 0;
      write_message(emit(AlertKind::kRunout, AlertSeverity::kWarning, true, rev, t,
                         imbalance_above_, imbalance_limit, "flute_imbalance"),
                    "runout: flute forces differ by %.2f %% of their mean (above %.2f %% for %d "
                    "revolutions); the estimate cannot tell: %s %.3f ± %.3f µm = %.0f ± %.0f %% "
                    "of f_t %.3g µm",
                    percent(imbalance_above_), percent(imbalance_limit),
                    config_.persist_revolutions, pair, deficit, sigma, percent(u), percent(sigma_u),
                    ft);
    } else if (runout_.streak >= persist) {
      runout_.active = true;
      runout_.streak = 0;
      write_message(emit(AlertKind::kRunout, AlertSeverity::kWarning, true, rev, t, u, limit,
                         "radius_deficit_per_feed"),
                    "runout high: %s %s%.3f ± %.3f µm = %.1f ± %.1f %% of f_t %.2f µm (first "
                    "window %.1f %% → %.1f %%; limit %.0f %%, at 100 %% flute %d stops cutting); "
                    "ρ %s%.2f ± %.2f µm at γ %.1f ± %.1f°",
                    pair, at_least(shorter == e.edge_flute), deficit, sigma, percent(u),
                    percent(sigma_u), ft, percent(runout_first_ratio_), percent(u), percent(limit),
                    shorter + 1, at_least(e.rho_lower_bound), e.rho_um, e.rho_sigma_um,
                    degrees(e.gamma_rad), degrees(e.gamma_sigma_rad));
    }
    return;
  }
  const bool forces_low = imbalance_below_run_ == config_.persist_revolutions;
  runout_.streak = low || (undecided && forces_low) ? runout_.streak + 1 : 0;
  if (runout_.streak >= persist && !low) {
    runout_.active = false;
    runout_.streak = 0;
    write_message(emit(AlertKind::kRunout, AlertSeverity::kInfo, false, rev, t, imbalance_below_,
                       imbalance_limit, "flute_imbalance"),
                  "runout cleared: flute imbalance %.2f %% (below %.2f %% for %d revolutions); "
                  "the estimate cannot tell: %s %.3f ± %.3f µm = %.0f ± %.0f %% of f_t %.3g µm",
                  percent(imbalance_below_), percent(config_.hysteresis * imbalance_limit),
                  config_.persist_revolutions, pair, deficit, sigma, percent(u), percent(sigma_u),
                  ft);
  } else if (runout_.streak >= persist) {
    runout_.active = false;
    runout_.streak = 0;
    write_message(emit(AlertKind::kRunout, AlertSeverity::kInfo, false, rev, t, u, limit,
                       "radius_deficit_per_feed"),
                  "runout cleared: %s %.3f ± %.3f µm = %.1f ± %.1f %% of f_t %.2f µm (below "
                  "%.0f %% for %d windows)",
                  pair, deficit, sigma, percent(u), percent(sigma_u), ft, percent(clear_below),
                  persist);
  }
}

void AlertEngine::restart_estimate_baseline() {
  estimate_base_.ready = false;
  estimate_base_count_ = 0;
  window_streak_.fill(0);
  window_clear_streak_ = 0;
  for (auto& c : coefficient_raise_) {
    c.reset();
  }
  coefficient_clear_.reset();
}

void AlertEngine::add_to_estimate_baseline() {
  ++estimate_base_count_;
  if (estimate_base_count_ >= config_.estimate_baseline_windows) {
    finish_estimate_baseline();
  }
}

void AlertEngine::finish_estimate_baseline() {
  EstimateBaseline& base = estimate_base_;
  const int n = estimate_base_count_;  // the newest n recent windows
  const std::span<double> series = std::span(estimate_series_).first(at(n));
  const std::span<double> scratch(estimate_scratch_);
  const double inflate = std::sqrt(1.0 + 1.0 / n);
  // σ of one window about the baseline: the spread of successive windows' differences / √2
  // (blind to a slow trend within the baseline), or their median statistical σ, whichever is
  // larger, and a floor.
  auto spread = [&](auto value, auto sigma_stat, double floor, double& median_out) {
    for (int i = 0; i < n; ++i) {
      series[at(i)] = value(recent_window(i));
    }
    median_out = median_in_place(series);
    for (int i = 0; i < n; ++i) {  // the median reordered them
      series[at(i)] = value(recent_window(i));
    }
    const double scatter = successive_scatter(series.first(at(n)), scratch);
    for (int i = 0; i < n; ++i) {
      series[at(i)] = sigma_stat(recent_window(i));
    }
    const double stat = median_in_place(series);
    return inflate * std::max({scatter, stat, floor});
  };
  auto median_of = [&](auto value) {
    for (int i = 0; i < n; ++i) {
      series[at(i)] = value(recent_window(i));
    }
    return median_in_place(series);
  };
  const double ft = base.feed_per_tooth_um;
  const double arl_windows =
      config_.false_alarm_revolutions /
      std::max<double>(1.0, static_cast<double>(recent_window(0).last_revolution -
                                                recent_window(0).first_revolution + 1));
  window_z_ = two_sided_quantile(1.0 / (arl_windows * (base.flutes - 1)));
  for (int j = 1; j < base.flutes; ++j) {
    base.radius_sigma_um[at(j)] =
        spread([j](const WindowEstimate& w) { return w.radius_difference_um[at(j)]; },
               [j](const WindowEstimate& w) { return w.radius_sigma_stat_um[at(j)]; },
               config_.sigma_floor * ft, base.radius_difference_um[at(j)]);
    base.radius_limit_um[at(j)] =
        std::max(window_z_ * base.radius_sigma_um[at(j)], config_.runout_change_min_um);
    base.radius_total_sigma_um[at(j)] =
        median_of([j](const WindowEstimate& w) { return w.radius_sigma_um[at(j)]; });
  }
  base.rho_um = median_of([](const WindowEstimate& w) { return w.rho_um; });
  base.rho_sigma_um = median_of([](const WindowEstimate& w) { return w.rho_sigma_um; });
  base.rho_lower_bound = false;  // any window's ρ a lower bound: the median's may be one
  double c = 0.0, s = 0.0;
  for (int i = 0; i < n; ++i) {
    c += std::cos(recent_window(i).gamma_rad);
    s += std::sin(recent_window(i).gamma_rad);
    base.rho_lower_bound = base.rho_lower_bound || recent_window(i).rho_lower_bound;
  }
  base.gamma_rad = std::atan2(s, c);
  base.gamma_sigma_rad = median_of([](const WindowEstimate& w) { return w.gamma_sigma_rad; });
  for (int k = 0; k < base.coefficients; ++k) {
    const double median = median_of([k](const WindowEstimate& w) { return w.coefficient[at(k)]; });
    base.coefficient[at(k)] = median;
    double ignored = 0.0;
    const double scale = median != 0.0 ? 1.0 / std::fabs(median) : 1.0;
    base.coefficient_sigma[at(k)] = spread(
        [k, scale](const WindowEstimate& w) { return w.coefficient[at(k)] * scale; },
        [k, scale](const WindowEstimate& w) { return w.coefficient_sigma_stat[at(k)] * scale; },
        config_.sigma_floor, ignored);
    const double stat =
        median_of([k](const WindowEstimate& w) { return w.coefficient_sigma_stat[at(k)]; });
    if (!(stat > 0.0)) {
      // No statistical σ: the windows did not fit it (held as configured), so its value says
      // nothing about wear, however steady it looks.
      base.coefficient_sigma[at(k)] = std::numeric_limits<double>::infinity();
    }
  }
  base.wear_allowance =
      config_.cusum_k + config_.baseline_margin / std::sqrt(static_cast<double>(n));
  base.wear_threshold = cusum_threshold_for(config_.cusum_k, arl_windows * base.coefficients);
  for (int k = 0; k < kMaxCoefficients; ++k) {
    coefficient_raise_[at(k)] = Cusum(base.wear_allowance, base.wear_threshold);
  }
  coefficient_clear_ = Cusum(config_.cusum_k, base.wear_threshold);
  base.windows = n;
  base.ready = true;
}

void AlertEngine::state_change_identified(const WindowEstimate& e, std::int64_t rev,
                                          std::int64_t t) {
  change_identify_ = false;
  const EstimateBaseline& base = estimate_base_;
  // Before: the baseline if it holds the state before the change, else the newest window that
  // ended before the onset.
  const WindowEstimate* before_window = nullptr;
  for (int i = 1; i < windows_count_; ++i) {
    if (recent_window(i).last_revolution < change_onset_) {
      before_window = &recent_window(i);
      break;
    }
  }
  const bool from_baseline = base.ready;
  if (!from_baseline && before_window == nullptr) {
    return;  // nothing fitted before the change
  }
  auto before_d = [&](int j) {
    return from_baseline ? base.radius_difference_um[at(j)]
                         : before_window->radius_difference_um[at(j)];
  };
  auto before_sd = [&](int j) {
    return from_baseline ? base.radius_total_sigma_um[at(j)]
                         : before_window->radius_sigma_um[at(j)];
  };
  const int flutes = base.flutes;
  int flute = 1;
  double largest = -1.0;
  for (int j = 1; j < flutes; ++j) {
    const double step = std::fabs(e.radius_difference_um[at(j)] - before_d(j));
    if (step > largest) {
      largest = step;
      flute = j;
    }
  }
  const double rho = from_baseline ? base.rho_um : before_window->rho_um;
  const double rho_sd = from_baseline ? base.rho_sigma_um : before_window->rho_sigma_um;
  const bool rho_bound = from_baseline ? base.rho_lower_bound : before_window->rho_lower_bound;
  const double gamma = from_baseline ? base.gamma_rad : before_window->gamma_rad;
  const double gamma_sd = from_baseline ? base.gamma_sigma_rad : before_window->gamma_sigma_rad;
  const double was = -before_d(flute), now = -e.radius_difference_um[at(flute)];
  write_message(
      emit(AlertKind::kRunoutChange, AlertSeverity::kInfo, true, rev, t, now, was,
           "radius_difference_um"),
      "runout change identified: r_CE1 − r_CE%d %.3f ± %.3f µm → %.3f ± %.3f µm; ρ %s%.2f "
      "± %.2f µm at γ %.1f ± %.1f° → %s%.2f ± %.2f µm at %.1f ± %.1f° (revolutions "
      "%lld–%lld)",
      flute + 1, was, before_sd(flute), now, e.radius_sigma_um[at(flute)], at_least(rho_bound), rho,
      rho_sd, degrees(gamma), degrees(gamma_sd), at_least(e.rho_lower_bound), e.rho_um,
      e.rho_sigma_um, degrees(e.gamma_rad), degrees(e.gamma_sigma_rad),
      static_cast<long long>(e.first_revolution), static_cast<long long>(e.last_revolution));
}

void AlertEngine::check_estimate_change(const WindowEstimate& e, std::int64_t rev, std::int64_t t) {
  const EstimateBaseline& base = estimate_base_;
  const int persist = config_.estimate_windows;
  if (change_active_) {
    if (change_source_ != ChangeSource::kEstimate) {
      return;  // the flute forces clear what they raised
    }
    bool inside = true;
    for (int j = 1; j < base.flutes; ++j) {
      inside =
          inside && std::fabs(e.radius_difference_um[at(j)] - base.radius_difference_um[at(j)]) <
                        config_.hysteresis * base.radius_limit_um[at(j)];
    }
    window_clear_streak_ = inside ? window_clear_streak_ + 1 : 0;
    if (window_clear_streak_ >= persist) {
      change_active_ = false;
      window_clear_streak_ = 0;
      window_streak_.fill(0);
      const auto j = at(change_flute_);
      write_message(
          emit(AlertKind::kRunoutChange, AlertSeverity::kInfo, false, rev, t,
               -e.radius_difference_um[j], -base.radius_difference_um[j], "radius_difference_um"),
          "runout change cleared: r_CE1 − r_CE%d %.3f ± %.3f µm (baseline %.3f µm, "
          "within %.3f µm for %d windows)",
          change_flute_ + 1, -e.radius_difference_um[j], e.radius_sigma_um[j],
          -base.radius_difference_um[j], config_.hysteresis * base.radius_limit_um[j], persist);
    }
    return;
  }
  for (int j = 1; j < base.flutes; ++j) {
    const auto q = at(j);
    const double deviation = e.radius_difference_um[q] - base.radius_difference_um[q];
    const double limit = base.radius_limit_um[q];
    const int side = deviation > limit ? 1 : deviation < -limit ? -1 : 0;
    if (side == 0 || side != window_side_[q]) {
      window_side_[q] = side;
      window_streak_[q] = side != 0 ? 1 : 0;
      continue;
    }
    if (++window_streak_[q] < persist) {
      continue;
    }
    change_active_ = true;
    change_source_ = ChangeSource::kEstimate;
    change_flute_ = j;
    change_side_ = side;
    change_onset_ = recent_window(persist - 1).first_revolution;
    change_identify_ = false;
    window_clear_streak_ = 0;
    step_streak_.fill(0);
    write_message(
        emit(AlertKind::kRunoutChange, AlertSeverity::kWarning, true, rev, t,
             -e.radius_difference_um[q], -base.radius_difference_um[q], "radius_difference_um"),
        "runout change: r_CE1 − r_CE%d %.3f ± %.3f µm → %.3f ± %.3f µm (limit ± %.3f "
        "µm, %d windows); ρ %s%.2f ± %.2f µm at γ %.1f ± %.1f° → %s%.2f ± %.2f µm at %.1f "
        "± %.1f°",
        j + 1, -base.radius_difference_um[q], base.radius_total_sigma_um[q],
        -e.radius_difference_um[q], e.radius_sigma_um[q], limit, persist,
        at_least(base.rho_lower_bound), base.rho_um, base.rho_sigma_um, degrees(base.gamma_rad),
        degrees(base.gamma_sigma_rad), at_least(e.rho_lower_bound), e.rho_um, e.rho_sigma_um,
        degrees(e.gamma_rad), degrees(e.gamma_sigma_rad));
    return;
  }
}

void AlertEngine::check_coefficient_wear(const WindowEstimate& e, std::int64_t rev,
                                         std::int64_t t) {
  const EstimateBaseline& base = estimate_base_;
  const double limit = config_.coefficient_increase;
  auto rise = [&](const WindowEstimate& w, int k) {
    return w.coefficient[at(k)] / base.coefficient[at(k)] - 1.0;
  };
  const int window_revolutions = static_cast<int>(e.last_revolution - e.first_revolution + 1);
  if (!wear_active_) {
    for (int k = 0; k < base.coefficients; ++k) {
      const double sigma = base.coefficient_sigma[at(k)];
      Cusum& raise = coefficient_raise_[at(k)];
      // A coefficient the windows do not pin (a relative σ above a third of the limit: e.g.
      // K_ac with no axial force measured) tells nothing about wear.
      if (base.coefficient[at(k)] == 0.0 || sigma > limit / 3.0 ||
          !raise.update((rise(e, k) - limit) / sigma) || raise.run() < 2 || wear_active_) {
        continue;
      }
      // Confirmed on the excursion's windows after its first.
      const int after = std::min({raise.run() - 1, windows_count_, kRecentWindows});
      double mean = 0.0;
      for (int i = 0; i < after; ++i) {
        mean += recent_window(i).coefficient[at(k)] / after;
      }
      const double now_rise = mean / base.coefficient[at(k)] - 1.0;
      if (now_rise <= limit) {
        continue;
      }
      wear_active_ = true;
      wear_from_estimates_ = true;
      wear_coefficient_ = k;
      coefficient_clear_.reset();
      char symbol[32], unit[32];
      split_unit(base.coefficient_name[at(k)].data(), symbol, unit);
      write_message(emit(AlertKind::kWearDrift, AlertSeverity::kWarning, true, rev, t, now_rise,
                         limit, "coefficient_rise"),
                    "wear drift: %s %.4g %s → %.4g %s (%+.1f %%, limit %+.1f %%; baseline ± %.2f "
                    "%%, over %d windows, %d revolutions)",
                    symbol, base.coefficient[at(k)], unit, mean, unit, percent(now_rise),
                    percent(limit), percent(sigma), after, after * window_revolutions);
    }
    return;
  }
  if (!wear_from_estimates_) {
    return;  // the flute forces clear what they raised
  }
  const int k = wear_coefficient_;
  const double sigma = base.coefficient_sigma[at(k)];
  const double clear_below = config_.hysteresis * limit;
  if (coefficient_clear_.update((clear_below - rise(e, k)) / sigma)) {
    wear_active_ = false;
    for (auto& c : coefficient_raise_) {
      c.reset();
    }
    const int run = std::min({coefficient_clear_.run(), windows_count_, kRecentWindows});
    double mean = 0.0;
    for (int i = 0; i < run; ++i) {
      mean += recent_window(i).coefficient[at(k)] / run;
    }
    const double now_rise = mean / base.coefficient[at(k)] - 1.0;
    char symbol[32], unit[32];
    split_unit(base.coefficient_name[at(k)].data(), symbol, unit);
    write_message(emit(AlertKind::kWearDrift, AlertSeverity::kInfo, false, rev, t, now_rise, limit,
                       "coefficient_rise"),
                  "wear drift cleared: %s %.4g %s (%+.1f %% over the baseline %.4g %s, below "
                  "%+.1f %%)",
                  symbol, mean, unit, percent(now_rise), base.coefficient[at(k)], unit,
                  percent(clear_below));
  }
}

AlertEngine::Raised AlertEngine::sensor_figure(SensorCause cause, double bad_fraction,
                                               std::int64_t new_gaps) const {
  switch (cause) {
    case SensorCause::kDeadChannel:
      return {dead_range_ratio_, dead_range_limit_, "sync_range_ratio"};
    case SensorCause::kBadSamples:
      return {bad_fraction, config_.sensor_bad_fraction, "bad_sample_fraction"};
    case SensorCause::kGaps:
      break;
  }
  return {static_cast<double>(new_gaps), 0.0, "new_gaps"};
}

void AlertEngine::examine(const InputCounters& c, std::int64_t utime_us) {
  last_utime_us_ = std::max(last_utime_us_, utime_us);  // a clear says when, revolutions or not
  const std::int64_t bad = c.samples_flagged;
  const std::int64_t samples = c.samples_in;
  const std::int64_t new_samples = samples - last_samples_;
  const double fraction =
      new_samples > 0 ? static_cast<double>(bad - last_bad_) / static_cast<double>(new_samples)
                      : 0.0;
  const std::int64_t new_gaps = c.gaps - last_gaps_;
  last_bad_ = bad;
  last_samples_ = samples;
  last_gaps_ = c.gaps;
  const bool trouble = fraction > config_.sensor_bad_fraction || new_gaps > 0 || dead_channel_ >= 0;
  // Raised, or raised already for bad samples or gaps when a dead channel is found: said again,
  // naming the channel.
  const bool newly_dead =
      sensor_.active && dead_channel_ >= 0 && dead_channel_ != dead_channel_said_;
  if ((trouble && !sensor_.active) || newly_dead) {
    sensor_.active = true;
    dead_channel_said_ = dead_channel_;
    // The revolution the alert comes at: the last one reported (−1: none yet); its value the
    // quantity that raised it (a dead channel's, else the bad samples' if above their limit,
    // else the gaps').
    sensor_cause_ = dead_channel_ >= 0                       ? SensorCause::kDeadChannel
                    : fraction > config_.sensor_bad_fraction ? SensorCause::kBadSamples
                                                             : SensorCause::kGaps;
    const Raised why = sensor_figure(sensor_cause_, fraction, new_gaps);
    Alert* a = emit(AlertKind::kSensor, AlertSeverity::kWarning, true, last_revolution_, utime_us,
                    why.value, why.threshold, why.quantity);
    const char* gap_s = new_gaps == 1 ? "" : "s";
    if (sensor_cause_ == SensorCause::kDeadChannel) {
      write_message(a,
                    "sensor trouble: %s carries no cutting force while %s does (a dead amplifier "
                    "or cable?); %.3f %% of recent samples saturated or not finite, %lld new "
                    "gap%s",
                    dead_channel_ == 0 ? "fx" : "fy", dead_channel_ == 0 ? "fy" : "fx",
                    percent(fraction), static_cast<long long>(new_gaps), gap_s);
    } else if (sensor_cause_ == SensorCause::kBadSamples) {
      write_message(a,
                    "sensor trouble: %.3f %% of recent samples saturated or not finite (limit "
                    "%.3f %%), %lld new gap%s",
                    percent(fraction), percent(config_.sensor_bad_fraction),
                    static_cast<long long>(new_gaps), gap_s);
    } else {  // raised for the gaps: said first, the bad samples (below their limit) after
      write_message(a,
                    "sensor trouble: %lld new gap%s in the stream (samples lost); %.3f %% of "
                    "recent samples saturated or not finite (limit %.3f %%)",
                    static_cast<long long>(new_gaps), gap_s, percent(fraction),
                    percent(config_.sensor_bad_fraction));
    }
  } else if (!trouble && sensor_.active && new_samples > 0) {
    sensor_.active = false;
    dead_channel_said_ = -1;
    // The clear states the quantity the raise did, as it stands now.
    const Raised now = sensor_figure(sensor_cause_, fraction, new_gaps);
    write_message(emit(AlertKind::kSensor, AlertSeverity::kInfo, false, last_revolution_, utime_us,
                       now.value, now.threshold, now.quantity),
                  "sensor trouble cleared: %.3f %% bad samples, no new gaps", percent(fraction));
  }
}

}  // namespace millwatch::monitor
