#include "core/monitor/alert_engine.hpp"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <span>

#include "core/config/json_reader.hpp"
#include "core/monitor/input_check.hpp"
#include "core/monitor/revolution_record.hpp"

namespace millwatch::monitor {
namespace {

constexpr auto kFlutes = static_cast<std::size_t>(kMaxFlutes);

std::size_t at(int i) {
  return static_cast<std::size_t>(i);
}

/// Writes an alert's operator line (printf format; truncated to the message's size).
__attribute__((format(printf, 2, 3))) void write_message(Alert* alert, const char* format, ...) {
  if (alert == nullptr) {
    return;
  }
  std::va_list args;
  va_start(args, format);
  std::vsnprintf(alert->message.data(), alert->message.size(), format, args);
  va_end(args);
}

double percent(double fraction) {
  return 100.0 * fraction;
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
  c.wear_increase = r.number("wear_increase", c.wear_increase, config::positive(10.0));
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
          {"block_revolutions", c.block_revolutions},
          {"baseline_blocks", c.baseline_blocks},
          {"false_alarm_revolutions", c.false_alarm_revolutions},
          {"cusum_k", c.cusum_k},
          {"baseline_margin", c.baseline_margin},
          {"sigma_floor", c.sigma_floor},
          {"runout_change_min", c.runout_change_min},
          {"wear_increase", c.wear_increase},
          {"breakage_fraction", c.breakage_fraction},
          {"sensor_bad_fraction", c.sensor_bad_fraction}};
}

AlertEngine::AlertEngine(const AlertConfig& config) : config_(config) {
  const auto block = static_cast<std::size_t>(std::max(config_.block_revolutions, 1));
  const auto revolutions = block * static_cast<std::size_t>(std::max(config_.baseline_blocks, 1));
  baseline_force_N_.assign(revolutions * kFlutes, 0.0);
  series_.assign(revolutions, 0.0);
  scratch_.assign(revolutions, 0.0);
  block_medians_.assign(static_cast<std::size_t>(std::max(config_.baseline_blocks, 1)), 0.0);
  block_values_.assign((kFlutes + 1) * block, 0.0);
}

void AlertEngine::rebaseline() {
  baseline_ = Baseline{};
  flutes_ = 0;
  baseline_count_ = 0;
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
  return &alert;
}

void AlertEngine::examine(const RevolutionRecord& r) {
  const RevolutionMeasurement& m = r.measured;
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
  const std::int64_t rev = r.revolution;
  const std::int64_t t = r.utime_us;

  if (rebaselined_) {
    clear_after_rebaseline(rev, t);
  }
  if (flutes_ != 0 && f.count != flutes_) {
    rebaseline();  // another tool
    clear_after_rebaseline(rev, t);
  }
  check_runout(f, rev, t);
  if (!baseline_.ready) {
    add_to_baseline(f);
    return;
  }
  check_breakage(f, rev, t);
  add_to_block(f, rev, t);
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

void AlertEngine::add_to_baseline(const Flutes& f) {
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
  base.ready = true;
}

void AlertEngine::add_to_block(const Flutes& f, std::int64_t rev, std::int64_t t) {
  const auto block = at(config_.block_revolutions);
  const auto i = at(block_count_);
  for (int j = 0; j < f.count; ++j) {
    block_values_[at(j) * block + i] = f.force_N[at(j)] / f.mean_N - 1.0;
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
  check_wear(b, rev, t);
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
    const auto j = at(change_flute_);
    const double sigma = base.share_sigma[j];
    const double deviation = change_side_ * (b.share[j] - base.share[j]);
    const double inside = config_.hysteresis * base.change_allowance[j] * sigma;
    if (change_clear_.update((inside - deviation) / sigma)) {
      change_active_ = false;
      for (int q = 0; q < kMaxFlutes; ++q) {
        change_up_[at(q)].reset();
        change_down_[at(q)].reset();
      }
      const Block now = recent_mean(change_clear_.run());
      write_message(
          emit(AlertKind::kRunoutChange, AlertSeverity::kInfo, false, rev, t, imbalance(now.share),
               before, "flute_imbalance"),
          "runout change cleared: flute imbalance %.2f %% (baseline %.2f %%, over %d revolutions)",
          percent(imbalance(now.share)), percent(before), change_clear_.run() * block);
    }
    return;
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
    change_active_ = true;
    change_flute_ = q;
    change_side_ = side;
    const double after = imbalance(now.share);
    write_message(emit(AlertKind::kRunoutChange, AlertSeverity::kWarning, true, rev, t, after,
                       before, "flute_imbalance"),
                  "runout change: flute imbalance %.2f %% → %.2f %% (baseline %.2f ± %.2f %%; "
                  "flute %d %+.2f %% → %+.2f %% of the mean flute force; over %d revolutions)",
                  percent(before), percent(after), percent(before),
                  percent(2.0 * base.share_sigma[j]), q, percent(base.share[j]),
                  percent(now.share[j]), blocks_after * block);
  }
  if (change_active_) {
    change_clear_ = Cusum(config_.cusum_k, base.change_threshold[at(change_flute_)]);
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

void AlertEngine::check_breakage(const Flutes& f, std::int64_t rev, std::int64_t t) {
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
          weakest, percent(f.force_N[w] / strongest), percent(base.strength[w]), percent(q[w]),
          percent(base.breakage_limit[w]), persist);
    }
    return;
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
                  breakage_flute_, percent(q[b]),
                  percent(base.breakage_limit[b] / config_.hysteresis), persist);
  }
}

void AlertEngine::clear_after_rebaseline(std::int64_t rev, std::int64_t t) {
  rebaselined_ = false;
  if (change_active_) {
    change_active_ = false;
    write_message(emit(AlertKind::kRunoutChange, AlertSeverity::kInfo, false, rev, t, 0.0, 0.0,
                       "flute_imbalance"),
                  "runout change cleared: new baseline");
  }
  if (wear_active_) {
    wear_active_ = false;
    write_message(emit(AlertKind::kWearDrift, AlertSeverity::kInfo, false, rev, t, 0.0,
                       config_.wear_increase, "flute_force_rise"),
                  "wear drift cleared: new baseline");
  }
  if (breakage_.active) {
    breakage_.active = false;
    breakage_.streak = 0;
    write_message(emit(AlertKind::kBreakage, AlertSeverity::kInfo, false, rev, t, 0.0, 0.0,
                       "flute_strength_fraction_of_baseline"),
                  "breakage cleared: new baseline");
  }
}

void AlertEngine::examine(const InputCounters& c, std::int64_t utime_us) {
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
  const bool trouble = fraction > config_.sensor_bad_fraction || new_gaps > 0;
  if (trouble && !sensor_.active) {
    sensor_.active = true;
    write_message(emit(AlertKind::kSensor, AlertSeverity::kWarning, true, 0, utime_us, fraction,
                       config_.sensor_bad_fraction, "bad_sample_fraction"),
                  "sensor trouble: %.3f %% of recent samples saturated or not finite (limit "
                  "%.3f %%), %lld new gaps",
                  percent(fraction), percent(config_.sensor_bad_fraction),
                  static_cast<long long>(new_gaps));
  } else if (!trouble && sensor_.active && new_samples > 0) {
    sensor_.active = false;
    write_message(emit(AlertKind::kSensor, AlertSeverity::kInfo, false, 0, utime_us, fraction,
                       config_.sensor_bad_fraction, "bad_sample_fraction"),
                  "sensor trouble cleared: %.3f %% bad samples, no new gaps", percent(fraction));
  }
}

}  // namespace millwatch::monitor
