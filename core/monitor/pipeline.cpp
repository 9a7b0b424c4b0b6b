#include "core/monitor/pipeline.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/monitor/valley_template.hpp"

namespace millwatch::monitor {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kTareTime_s = 0.05;    // time constant of the re-zeroing while not cutting
constexpr double kIdleFraction = 0.2;   // a revolution below this of the usual peak: not cutting
constexpr double kSettledSpeed = 2e-4;  // relative speed change between hops when settled
constexpr int kRingChannels = 8;        // measured fx, fy, fz, detection; the same for the model

InputCheckConfig input_config(const MonitorConfig& c) {
  InputCheckConfig i;
  i.sample_rate_hz = c.sample_rate_hz;
  i.saturation_N = c.saturation_N;
  return i;
}

}  // namespace

std::string_view to_string(PipelineEventKind kind) {
  switch (kind) {
    case PipelineEventKind::kBlockRejected:
      return "block rejected";
    case PipelineEventKind::kGap:
      return "gap in the samples";
    case PipelineEventKind::kNonFinite:
      return "non-finite samples";
    case PipelineEventKind::kSaturated:
      return "saturated samples";
    case PipelineEventKind::kLockAcquired:
      return "spindle locked";
    case PipelineEventKind::kLockLost:
      return "spindle lock lost";
    case PipelineEventKind::kModelAligned:
      return "model aligned";
    case PipelineEventKind::kModelBuilt:
      return "model rebuilt";
    case PipelineEventKind::kCuttingStopped:
      return "cutting stopped";
    case PipelineEventKind::kCuttingResumed:
      return "cutting resumed";
  }
  return "event";
}

Pipeline::Pipeline(const MonitorConfig& config, PipelineSink& sink)
    : config_(config), sink_(sink), input_(input_config(config)) {
  validate(config_);
  // Forward and backward, the response is |H|²: the zero-phase design moves its cut-off up so
  // that the pair is still 3 dB down at the configured cut-off, like the causal filter
  // (1 + (f_c/f_c')^(2n) = √2), and both modes pass the tooth harmonics alike.
  const double cutoff_hz =
      config_.filter_zero_phase
          ? config_.filter_cutoff_hz *
                std::pow(std::sqrt(2.0) - 1.0, -1.0 / (2.0 * config_.filter_order))
          : config_.filter_cutoff_hz;
  filter_ =
      signal::ButterworthDesign::lowpass(config_.sample_rate_hz, cutoff_hz, config_.filter_order);
  for (auto& f : lowpass_) {
    f = signal::LowPassFilter(filter_);
  }
  if (config_.filter_zero_phase) {
    zero_phase_ = signal::ZeroPhaseFilter(filter_, 3);
  }
  // The tracker works on the filtered resultant, decimated to ~2.5× the cut-off.
  decimation_ =
      std::max(1, static_cast<int>(config_.sample_rate_hz / (2.5 * config_.filter_cutoff_hz)));
  signal::SpindleTrackerConfig tc = config_.spindle;
  tc.sample_rate_hz = config_.sample_rate_hz / decimation_;
  tc.flutes = config_.model.tool.flutes;
  tc.commanded_rpm = config_.model.process.spindle_rpm;
  tracker_.setup(tc);

  sync_ = SyncAverage(config_.sync_bins, config_.sync_window_revolutions);
  const double slowest_hz = tc.commanded_rpm / 60.0 * (1.0 - tc.search_fraction);
  ring_ = SampleRing(kRingChannels,
                     static_cast<std::size_t>(8.0 * config_.sample_rate_hz / slowest_hz) + 8192);
  if (config_.lockstep) {
    lockstep_ = Lockstep(config_.model, filter_, config_.filter_zero_phase);
  }
  RevolutionMeterConfig mc;
  mc.flutes = config_.model.tool.flutes;
  mc.sample_rate_hz = config_.sample_rate_hz;
  mc.search_fraction_of_pitch = config_.search_fraction_of_pitch;
  measured_meter_ = RevolutionMeter(mc, 0);
  model_meter_ = RevolutionMeter(mc, 4);
  alerts_ = AlertEngine(config_.alerts);
  tooth_delay_s_ =
      config_.filter_zero_phase ? 0.0 : filter_.group_delay_s(tc.commanded_rpm / 60.0 * mc.flutes);
  tare_gain_ = 1.0 / (kTareTime_s * config_.sample_rate_hz);
  // The envelope forgets over about two revolutions at the commanded speed.
  envelope_decay_ = std::exp(-2.0 / (2.0 * config_.sample_rate_hz / (tc.commanded_rpm / 60.0)));
  // Gaps up to a tracker hop are bridged; longer ones restart the stream.
  max_bridged_gap_ = static_cast<std::int64_t>(config_.spindle.hop_s * config_.sample_rate_hz);
  alpha_window_.assign(static_cast<std::size_t>(config_.alpha_window_revolutions), 0.0);
  dfy_window_.assign(static_cast<std::size_t>(config_.alpha_window_revolutions), 0.0);
}

void Pipeline::event(PipelineEventKind kind, std::int64_t sample, std::int64_t count, double value,
                     std::string_view detail, std::int64_t block_seq) {
  PipelineEvent e;
  e.kind = kind;
  e.sample = sample;
  e.utime_us = input_.utime_of(sample);
  e.count = count;
  e.value = value;
  e.detail = detail;
  e.block_seq = block_seq;
  sink_.on_event(e);
}

void Pipeline::restart_stream(std::int64_t first_sample) {
  if (phase_.valid) {
    event(PipelineEventKind::kLockLost, first_sample, 0, 0.0, "stream restarted");
  }
  stream_start_ = first_sample;
  stream_fresh_ = true;
  tracker_.restart(0);
  phase_.valid = false;
  sync_.clear();
  ring_.clear();
  measuring_ = false;
  measured_meter_.restart();
  model_meter_.restart();
  pending_measured_.clear();
  pending_model_.clear();
}

void Pipeline::bridge_gap(std::int64_t first_sample) {
  // A short gap: the spindle kept turning, so the tracker keeps its lock and sample time; it
  // sees the last value held over the gap. The filters restart at the next sample and the
  // meters measure only revolutions after it.
  const double held = last_detect_ >= 0.0 ? std::sqrt(last_detect_) : 0.0;
  while (stream_start_ + tracker_.next_sample() * decimation_ < first_sample) {
    if (tracker_.process({&held, 1}) > 0) {
      on_tracker_update();
    }
  }
  stream_fresh_ = true;
  const std::int64_t from =
      first_sample + static_cast<std::int64_t>(0.002 * config_.sample_rate_hz);
  measured_meter_.restart(from);
  model_meter_.restart(from);
  pending_measured_.clear();
  pending_model_.clear();
}

void Pipeline::process(const SampleBlock& block) {
  const CheckedBlock c = input_.check(block);
  if (c.verdict == BlockVerdict::kRejected) {
    event(PipelineEventKind::kBlockRejected, input_.next_sample(),
          static_cast<std::int64_t>(block.fx_N.size()), 0.0, c.problem, block.seq);
    return;
  }
  if (config_.filter_zero_phase && (c.gap_samples > 0 || c.first_sample == 0)) {
    drain_zero_phase(zero_phase_.flush());  // the stretch before the gap ends here
  }
  if (c.gap_samples > 0) {
    event(PipelineEventKind::kGap, c.first_sample, c.gap_samples, 0.0, c.problem, block.seq);
    if (c.gap_samples <= max_bridged_gap_ && !stream_fresh_) {
      bridge_gap(c.first_sample);
    } else {
      restart_stream(c.first_sample);
    }
  } else if (c.first_sample == 0) {
    restart_stream(0);
  }
  std::int64_t nonfinite = 0, saturated = 0;
  for (const std::uint8_t f : c.flags) {
    nonfinite += (f & kFlagNonFinite) != 0 ? 1 : 0;
    saturated += (f & kFlagSaturated) != 0 ? 1 : 0;
  }
  if (nonfinite > 0) {
    event(PipelineEventKind::kNonFinite, c.first_sample, nonfinite, 0.0,
          "replaced by the channel's last good value", block.seq);
  }
  if (saturated > 0) {
    event(PipelineEventKind::kSaturated, c.first_sample, saturated, 0.0,
          "at or beyond the charge amplifier's range", block.seq);
  }

  const std::size_t count = c.fx_N.size();
  for (std::size_t i = 0; i < count; ++i) {
    const std::int64_t n = c.first_sample + static_cast<std::int64_t>(i);
    const auto f = config_.axis_map.to_model({c.fx_N[i], c.fy_N[i], c.fz_N[i]});
    if (config_.filter_zero_phase) {
      if (stream_fresh_) {
        zero_phase_next_sample_ = n;
        stream_fresh_ = false;
      }
      drain_zero_phase(zero_phase_.push(f));
      continue;
    }
    if (stream_fresh_) {
      for (std::size_t a = 0; a < 3; ++a) {
        lowpass_[a].reset();
        lowpass_[a].settle(f[a]);
      }
      stream_fresh_ = false;
    }
    downstream(n, lowpass_[0].step(f[0]), lowpass_[1].step(f[1]), lowpass_[2].step(f[2]));
  }

  if (measuring_) {
    if (sync_revolutions_since_report_ >= config_.sync_window_revolutions) {
      sync_revolutions_since_report_ = 0;
      sink_.on_sync_average(sync_, lockstep_.aligned() ? &lockstep_ : nullptr, revolutions_,
                            input_.utime_of(ring_.newest()));
    }
  }
}

void Pipeline::finish() {
  if (config_.filter_zero_phase) {
    drain_zero_phase(zero_phase_.flush());
  }
}

void Pipeline::drain_zero_phase(std::size_t ready) {
  for (std::size_t k = 0; k < ready; ++k) {
    downstream(zero_phase_next_sample_ + static_cast<std::int64_t>(k), zero_phase_.output(0, k),
               zero_phase_.output(1, k), zero_phase_.output(2, k));
  }
  zero_phase_next_sample_ += static_cast<std::int64_t>(ready);
}

void Pipeline::downstream(std::int64_t n, double fx, double fy, double fz) {
  // Re-zero while the tracker says the tool is not cutting: the force is then zero, and what
  // the channels read is the charge amplifiers' offset and drift.
  // Only quiet stretches count: the force envelope of the last revolutions well below the
  // usual peak (the tracker's verdict lags by half a window when the cut resumes).
  const double ex = fx - tare_N_[0];
  const double ey = fy - tare_N_[1];
  envelope_sq_ = std::max(ex * ex + ey * ey, envelope_sq_ * envelope_decay_);
  const auto& tracked = tracker_.estimate();
  if (tracked.updates > 0 && !tracked.cutting && typical_peak_N_ > 0.0 &&
      envelope_sq_ < kIdleFraction * kIdleFraction * typical_peak_N_ * typical_peak_N_) {
    tare_N_[0] += tare_gain_ * (fx - tare_N_[0]);
    tare_N_[1] += tare_gain_ * (fy - tare_N_[1]);
    tare_N_[2] += tare_gain_ * (fz - tare_N_[2]);
  }
  fx -= tare_N_[0];
  fy -= tare_N_[1];
  fz -= tare_N_[2];
  // Valleys are sought on the squared in-plane force: near a valley the force is nearly
  // linear in time, so its square is a smooth parabola.
  const double detect = fx * fx + fy * fy;
  last_detect_ = detect;
  if ((n - stream_start_) % decimation_ == 0) {
    const double magnitude = std::sqrt(detect);
    if (tracker_.process({&magnitude, 1}) > 0) {
      on_tracker_update();
    }
  }
  std::array<double, kRingChannels> v = {fx, fy, fz, detect, 0.0, 0.0, 0.0, 0.0};
  if (phase_.valid) {
    const double angle = phase_.angle_at(static_cast<double>(n));
    const double turn = std::floor(angle / kTwoPi);
    if (turn > last_turn_) {
      sync_.end_revolution();
      ++sync_revolutions_since_report_;
      if (!measuring_ && settled_ && sync_.revolutions() >= config_.template_revolutions) {
        start_measuring(n);
      }
    }
    last_turn_ = turn;
    sync_.add(angle - turn * kTwoPi, {fx, fy, fz, detect});
    if (measuring_ && lockstep_.aligned()) {
      const auto m = lockstep_.next_sample(angle);
      v[4] = m[0];
      v[5] = m[1];
      v[6] = m[2];
      v[7] = m[0] * m[0] + m[1] * m[1];
    }
  }
  ring_.push(n, v.data());
  if (measuring_ && n >= measured_meter_.needed_sample() &&
      (!lockstep_.aligned() || n >= model_meter_.needed_sample())) {
    measure_revolutions();
  }
  if (n >= next_health_check_) {
    alerts_.on_input(input_.counters(), input_.utime_of(n),
                     [this](const Alert& a) { sink_.on_alert(a); });
    next_health_check_ = n + static_cast<std::int64_t>(0.5 * config_.sample_rate_hz);
  }
}

void Pipeline::on_tracker_update() {
  const signal::SpindleEstimate& e = tracker_.estimate();
  const std::int64_t center = stream_start_ + e.center_sample * decimation_;
  SpindleUpdate u;
  u.utime_us = input_.utime_of(center);
  u.seq = ++spindle_seq_;
  u.estimate = e;
  u.commanded_rpm = config_.model.process.spindle_rpm;
  if (!e.valid) {
    if (phase_.valid) {
      event(PipelineEventKind::kLockLost, center, 0, 0.0, "no periodic cutting force");
      phase_.valid = false;
      measuring_ = false;
    }
    sink_.on_spindle(u);
    return;
  }
  const signal::PhaseModel& p = tracker_.phase();
  phase_ = p;
  phase_.reference_sample = static_cast<double>(stream_start_) + p.reference_sample * decimation_;
  phase_.sample_rate_hz = config_.sample_rate_hz;
  last_rpm_ = e.spindle_rpm;
  u.revolution =
      static_cast<std::int64_t>(std::floor(phase_.angle_at(static_cast<double>(center)) / kTwoPi));
  if (e.relocked) {
    event(PipelineEventKind::kLockAcquired, center, 0, e.spindle_rpm, "spindle speed locked");
    settled_ = false;
    sync_.clear();
    sync_revolutions_since_report_ = 0;
    measuring_ = false;
    measured_meter_.restart();
    model_meter_.restart();
    last_turn_ = std::floor(phase_.angle_at(static_cast<double>(ring_.newest() + 1)) / kTwoPi);
  } else if (!measuring_ && std::fabs(e.spindle_hz - last_hop_hz_) > kSettledSpeed * e.spindle_hz) {
    // Still settling after the lock: the average so far was taken with a poor phase model.
    sync_.clear();
    sync_revolutions_since_report_ = 0;
    settled_ = false;
  } else if (!measuring_) {
    settled_ = true;
  } else if (config_.lockstep && measuring_ && lockstep_.set_spindle_hz(e.spindle_hz)) {
    event(PipelineEventKind::kModelBuilt, center, 0, e.spindle_rpm, "spindle speed changed");
  }
  last_hop_hz_ = e.spindle_hz;
  sink_.on_spindle(u);
}

void Pipeline::start_measuring(std::int64_t sample) {
  std::vector<double> detect;
  sync_.average(3, detect);
  const ValleyTemplate t = find_valley_template(detect, config_.model.tool.flutes);
  if (!t.valid) {
    return;
  }
  measured_meter_.set_template(t);
  model_meter_.set_template(t);
  // Measure only revolutions that start after the model stream has settled.
  const std::int64_t from = sample + static_cast<std::int64_t>(0.002 * config_.sample_rate_hz);
  if (config_.lockstep) {
    lockstep_.set_spindle_hz(phase_.spindle_hz);
    if (lockstep_.align(sync_)) {
      event(PipelineEventKind::kModelAligned, sample, 0, lockstep_.alignment_correlation(),
            "model aligned to the measured revolution");
    }
  }
  measured_meter_.restart(from);
  model_meter_.restart(from);
  pending_measured_.clear();
  pending_model_.clear();
  measuring_ = true;
}

void Pipeline::measure_revolutions() {
  // Both meters measure the same revolutions (same template, phase and start): pair them by
  // their sequence numbers.
  const bool with_model = config_.lockstep && lockstep_.aligned();
  measured_meter_.advance(ring_, phase_, [&](const RevolutionMeasurement& m) {
    if (!with_model) {
      emit_record(m, nullptr);
      return;
    }
    pending_measured_.push(m);
  });
  if (!with_model) {
    return;
  }
  model_meter_.advance(ring_, phase_,
                       [&](const RevolutionMeasurement& m) { pending_model_.push(m); });
  while (!pending_measured_.empty() && !pending_model_.empty()) {
    const RevolutionMeasurement& meas = pending_measured_.front();
    const RevolutionMeasurement& mod = pending_model_.front();
    if (meas.sequence == mod.sequence) {
      emit_record(meas, &mod);
      pending_measured_.pop();
      pending_model_.pop();
    } else if (meas.sequence < mod.sequence) {
      emit_record(meas, nullptr);
      pending_measured_.pop();
    } else {
      pending_model_.pop();
    }
  }
  // A model meter that lags too far behind is not waited for.
  while (pending_measured_.size() > PendingRevolutions::kCapacity / 2) {
    emit_record(pending_measured_.front(), nullptr);
    pending_measured_.pop();
  }
}

void Pipeline::emit_record(const RevolutionMeasurement& measured,
                           const RevolutionMeasurement* model) {
  // A revolution without cutting force (the spindle stopping: the tracker's window still holds
  // the cut for a while) is counted, not reported.
  double peak = 0.0;
  for (int j = 0; j < measured.flutes; ++j) {
    peak = std::max(peak, measured.peak_resultant_N[static_cast<std::size_t>(j)]);
  }
  const auto at = static_cast<std::int64_t>(std::llround(measured.valley_sample[0]));
  if (typical_peak_N_ > 0.0 && peak < kIdleFraction * typical_peak_N_) {
    ++idle_revolutions_;
    if (!idle_) {
      idle_ = true;
      event(PipelineEventKind::kCuttingStopped, at, 0, peak, "no cutting force in the revolution");
    }
    return;
  }
  if (idle_) {
    idle_ = false;
    event(PipelineEventKind::kCuttingResumed, at, 0, peak, "cutting force again");
  }
  typical_peak_N_ =
      typical_peak_N_ == 0.0 ? peak : typical_peak_N_ + 0.05 * (peak - typical_peak_N_);
  RevolutionRecord r;
  r.revolution = revolutions_++;
  const double first_valley = measured.valley_sample[0];
  r.utime_us = input_.utime_of(static_cast<std::int64_t>(std::llround(first_valley))) -
               static_cast<std::int64_t>(std::llround(tooth_delay_s_ * 1e6));
  r.spindle_rpm = last_rpm_;
  r.measured = measured;
  if (measured.valid) {
    ++valid_revolutions_;
    const auto w = static_cast<int>(alpha_window_.size());
    alpha_window_[static_cast<std::size_t>(window_next_)] = measured.alpha_deg;
    dfy_window_[static_cast<std::size_t>(window_next_)] = measured.delta_fy_N;
    window_next_ = (window_next_ + 1) % w;
    window_count_ = std::min(window_count_ + 1, w);
  }
  if (window_count_ > 0) {
    double sa = 0.0, saa = 0.0, sd = 0.0;
    for (int i = 0; i < window_count_; ++i) {
      sa += alpha_window_[static_cast<std::size_t>(i)];
      saa +=
          alpha_window_[static_cast<std::size_t>(i)] * alpha_window_[static_cast<std::size_t>(i)];
      sd += dfy_window_[static_cast<std::size_t>(i)];
    }
    r.alpha_mean_deg = sa / window_count_;
    r.alpha_std_deg =
        window_count_ > 1
            ? std::sqrt(std::max(0.0, (saa - sa * sa / window_count_) / (window_count_ - 1)))
            : 0.0;
    r.delta_fy_mean_N = sd / window_count_;
    r.window_revolutions = window_count_;
  }
  if (model != nullptr) {
    r.model_valid = model->valid;
    r.model = *model;
    r.model_offset_rad = lockstep_.offset_rad();
    fill_residuals(r);
  }
  sink_.on_revolution(r);
  alerts_.on_revolution(r, [this](const Alert& a) { sink_.on_alert(a); });
}

void Pipeline::fill_residuals(RevolutionRecord& r) const {
  const RevolutionMeasurement& m = r.measured;
  const auto from = static_cast<std::int64_t>(std::ceil(m.valley_sample[0]));
  const auto to =
      static_cast<std::int64_t>(std::floor(m.valley_sample[static_cast<std::size_t>(m.flutes)]));
  if (from < ring_.oldest() || to > ring_.newest() || to <= from) {
    return;
  }
  const int sectors = config_.residual_sectors;
  r.sectors = sectors;
  std::array<double, 3> sum{};
  double measured_sum = 0.0;
  std::array<double, kMaxFlutes> flute_sum{};
  std::array<int, kMaxFlutes> flute_n{};
  std::array<double, kMaxSectors> sector_sum{};
  std::array<int, kMaxSectors> sector_n{};
  const double sector_per_sample =
      sectors / (m.valley_sample[static_cast<std::size_t>(m.flutes)] - m.valley_sample[0]);
  int flute = 0;
  for (std::int64_t n = from; n <= to; ++n) {
    std::array<double, 3> d{};
    for (int a = 0; a < 3; ++a) {
      d[static_cast<std::size_t>(a)] = ring_.at(a, n) - ring_.at(a + 4, n);
      sum[static_cast<std::size_t>(a)] +=
          d[static_cast<std::size_t>(a)] * d[static_cast<std::size_t>(a)];
    }
    measured_sum += ring_.at(3, n) * ring_.at(3, n);
    const double d_xy2 = d[0] * d[0] + d[1] * d[1];
    while (flute + 1 < m.flutes &&
           static_cast<double>(n) >= m.valley_sample[static_cast<std::size_t>(flute + 1)]) {
      ++flute;
    }
    flute_sum[static_cast<std::size_t>(flute)] += d_xy2;
    ++flute_n[static_cast<std::size_t>(flute)];
    // Sector by position within the revolution (the speed is steady over one revolution).
    const double rel = (static_cast<double>(n) - m.valley_sample[0]) * sector_per_sample;
    const int s = std::clamp(static_cast<int>(rel), 0, sectors - 1);
    sector_sum[static_cast<std::size_t>(s)] += d_xy2;
    ++sector_n[static_cast<std::size_t>(s)];
  }
  const auto count = static_cast<double>(to - from + 1);
  for (std::size_t a = 0; a < 3; ++a) {
    r.residual_rms_N[a] = std::sqrt(sum[a] / count);
  }
  r.measured_rms_N = std::sqrt(measured_sum / count);
  for (int j = 0; j < m.flutes; ++j) {
    const auto uj = static_cast<std::size_t>(j);
    r.residual_flute_rms_N[uj] = flute_n[uj] > 0 ? std::sqrt(flute_sum[uj] / flute_n[uj]) : 0.0;
  }
  for (int s = 0; s < sectors; ++s) {
    const auto us = static_cast<std::size_t>(s);
    r.residual_sector_rms_N[us] = sector_n[us] > 0 ? std::sqrt(sector_sum[us] / sector_n[us]) : 0.0;
  }
}

PipelineStatus Pipeline::status() const {
  PipelineStatus s;
  s.input = input_.counters();
  s.revolutions = revolutions_;
  s.valid_revolutions = valid_revolutions_;
  s.idle_revolutions = idle_revolutions_;
  s.utime_us = input_.utime_of(std::max<std::int64_t>(0, input_.next_sample() - 1));
  const auto& e = tracker_.estimate();
  s.spindle_rpm = e.valid ? e.spindle_rpm : 0.0;
  s.cutting = e.cutting;
  s.state = !phase_.valid ? (e.updates > 0 && !e.cutting ? "no cutting" : "acquiring")
            : measuring_  ? "measuring"
                          : "tracking";
  return s;
}

}  // namespace millwatch::monitor
