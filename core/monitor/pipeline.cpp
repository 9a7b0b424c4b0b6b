#include "core/monitor/pipeline.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <utility>

#include "core/monitor/extremum.hpp"
#include "core/monitor/force_rows.hpp"
#include "core/monitor/nearest_integer.hpp"

namespace millwatch::monitor {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr int kRingChannels = 4;  // fx, fy, fz, Fx² + Fy²
constexpr int kDetectChannel = 3;
constexpr double kMaxBridgedGap_s = 0.05;  // shorter gaps keep the lock
// Gaps of at most a quarter of the low-pass's cut-off period (at least a sample) are filled on
// the line between their neighbours: a tooth harmonic at the cut-off moves by under 15 % of its
// amplitude there, the tooth-passing frequency by under 1 %.
constexpr double kFilledGapCutoffs = 0.25;
constexpr const char* kFilledGap =
    "filled on the line between its neighbours (shorter than a quarter of the low-pass's period)";
constexpr double kSlowestFraction = 0.4;     // of the commanded speed: longest revolution analysed
constexpr double kModelSpeedChange = 0.002;  // relative: the lockstep model follows the speed
// A rebuild at a new speed applies this long (at the commanded speed, in revolutions) after it
// was asked for: [000]'s full model takes 4.3 ms to build on the Zen 5, ~7 ms on the Intel Xeon
// (bench/model_benchmark), done meanwhile on the builder's thread. Through a ramp the model
// lags the speed by this much more than the 0.2 % (100 rpm at 5,000 rpm/s, 0.4 % at 25,000
// rpm), up to twice that when the speed's build waits for a fit's (a fit's build takes the
// newest speed, so fits do not hold the speed back).
constexpr double kModelBuildDelay_s = 0.02;
// A lock's first alignments refused (a quarter pitch from the template's) that start the
// synchronous average again: a knock of a few revolutions; more, the template may be wrong.
constexpr int kFirstAlignmentRestarts = 4;
// Relative: the tooth events' revolution speed against a consistent tracker window's, beyond
// which the events follow minima that are not the flutes' (a 6-flute cut after a speed ramp:
// the events' filter ran on to 16,500 rpm for 13,000, counting 8 turns the spindle did not make).
constexpr double kEventSpeedDisagreement = 0.03;
// Unlocked windows in a row that must agree on a line outside the search before it is
// reported: noise peaks wander from window to window, a spindle's line stays.
constexpr int kLineWindows = 4;
constexpr int kIdleToStop = 3;  // idle revolutions in a row: cutting has stopped
// An in-plane channel whose synchronous range over the lock's windows is below this fraction of
// the other's carries no cutting force (in a cut the two are within a factor of a few).
constexpr double kFlatChannel = 0.02;
constexpr const char* kNoDistinctEvents = "the synchronous average shows no distinct tooth events";
constexpr const char* kDeadFx =
    "fx carries no cutting force (its synchronous range is below 2 % of fy's): the tooth events "
    "need both in-plane channels";
constexpr const char* kDeadFy =
    "fy carries no cutting force (its synchronous range is below 2 % of fx's): the tooth events "
    "need both in-plane channels";
// Past the low-pass, the stages after it take every stride-th sample, at no less than this rate
// and no fewer samples per revolution (at the commanded speed) than the synchronous average has
// bins: the filter leaves nothing above a few cut-offs (order 4 at 3.3 kHz: −74 dB at 27.8 kHz),
// the valley fits span a fixed fraction of the tooth pitch, and the average (what identification
// fits) stays as well filled. A 333.3 kHz cut at 25,000 rpm measures at 111.1 kHz.
constexpr double kMeasuringRate_hz = 50000.0;

/// The first sample of a checked block with `flag` (its first sample if none has).
std::int64_t first_flagged(const CheckedBlock& c, SampleFlag flag) {
  const auto at = std::find_if(c.flags.begin(), c.flags.end(),
                               [flag](std::uint8_t f) { return (f & flag) != 0; });
  return c.first_sample + (at == c.flags.end() ? 0 : at - c.flags.begin());
}

InputCheckConfig input_config(const MonitorConfig& c) {
  InputCheckConfig i;
  i.sample_rate_hz = c.sample_rate_hz;
  i.saturation_N = c.saturation_N;
  return i;
}

signal::ButterworthDesign design(const MonitorConfig& c) {
  // Forward and backward, the response is |H|²: the zero-phase design moves its cut-off up so
  // that the pair is still 3 dB down at the configured cut-off, like the causal filter
  // (1 + (f_c/f_c')^(2n) = √2), and both modes pass the tooth harmonics alike.
  const double cutoff_hz = c.filter_zero_phase
                               ? zero_phase_design_cutoff_hz(c.filter_cutoff_hz, c.filter_order)
                               : c.filter_cutoff_hz;
  return signal::ButterworthDesign::lowpass(c.sample_rate_hz, cutoff_hz, c.filter_order);
}

/// Every how many filtered samples the measuring stages take one.
int stride_for(const MonitorConfig& c) {
  const double lowest_hz =
      std::max(kMeasuringRate_hz, c.sync_bins * c.model.process.spindle_rpm / 60.0);
  return std::max(1, static_cast<int>(c.sample_rate_hz / lowest_hz));
}

/// The configuration the measuring stages see: the sample rate they run at.
MonitorConfig measuring_config(const MonitorConfig& c) {
  MonitorConfig m = c;
  m.sample_rate_hz = c.sample_rate_hz / stride_for(c);
  return m;
}

/// The tracker works on the filtered resultant, decimated to ~2.5× the cut-off.
int decimation_for(const MonitorConfig& c) {
  return std::max(1, static_cast<int>(c.sample_rate_hz / (2.5 * c.filter_cutoff_hz)));
}

signal::SpindleTrackerConfig tracker_config(const MonitorConfig& c) {
  signal::SpindleTrackerConfig t = c.spindle;
  t.sample_rate_hz = c.sample_rate_hz / decimation_for(c);
  t.flutes = c.model.tool.flutes;
  t.commanded_rpm = c.model.process.spindle_rpm;
  return t;
}

}  // namespace

std::string_view to_string(PipelineEventKind kind) {
  switch (kind) {
    case PipelineEventKind::kBlockRejected:
      return "block rejected";
    case PipelineEventKind::kGap:
      return "gap in the samples";
    case PipelineEventKind::kNonFinite:
      return "non-finite or implausible samples";
    case PipelineEventKind::kSaturated:
      return "saturated samples";
    case PipelineEventKind::kLockAcquired:
      return "spindle locked";
    case PipelineEventKind::kLockLost:
      return "spindle lock lost";
    case PipelineEventKind::kModelAligned:
      return "model aligned";
    case PipelineEventKind::kModelUpdated:
      return "model updated";
    case PipelineEventKind::kCuttingStopped:
      return "cutting stopped";
    case PipelineEventKind::kCuttingResumed:
      return "cutting resumed";
    case PipelineEventKind::kAlertsHeld:
      return "alerts held";
    case PipelineEventKind::kAlertsArmed:
      return "alerts armed";
    case PipelineEventKind::kRecordTooShort:
      return "record too short";
    case PipelineEventKind::kNoSteadySignal:
      return "no steady tooth-passing signal";
    case PipelineEventKind::kNoTemplate:
      return "tooth events not found";
    case PipelineEventKind::kSpeedOutOfRange:
      return "spindle speed outside the search";
    case PipelineEventKind::kFlutesRelabelled:
      return "flutes relabelled";
  }
  return "event";
}

const char* const kLineWithSpindleLine =
    "unlocked tracker windows agreed on a strongest spectral line outside the search, with a "
    "line at its spindle frequency as a tooth-passing line";

std::string describe_line_outside_search(const PipelineEvent& e, const MonitorConfig& config) {
  const int flutes = config.model.tool.flutes;
  const double commanded_rpm = config.model.process.spindle_rpm;
  const double line_hz = e.value;
  // The line is the spindle frequency (runout can make it the strongest) or the tooth-passing
  // one: without runout a cut at f with z flutes is periodic at z·f, and forces alone cannot
  // tell. A line at line/z as well makes it the tooth-passing one, likely.
  const bool tooth_passing = e.detail == kLineWithSpindleLine;
  std::array<double, 2> rpm = {60.0 * line_hz / flutes, 60.0 * line_hz};
  std::array<const char*, 2> as = {"the tooth-passing frequency", "the spindle frequency"};
  if (!tooth_passing &&
      std::fabs(std::log(rpm[1] / commanded_rpm)) < std::fabs(std::log(rpm[0] / commanded_rpm))) {
    std::swap(rpm[0], rpm[1]);
    std::swap(as[0], as[1]);
  }
  const auto percent = [&](double r) { return 100.0 * (r / commanded_rpm - 1.0); };
  char text[320];
  std::snprintf(text, sizeof text,
                "the strongest spectral line, %.0f Hz, lies outside the spindle tracker's search "
                "(%.0f rpm commanded, ± %.0f %%), so no speed is stated",
                line_hz, commanded_rpm, 100.0 * config.spindle.search_fraction);
  std::string out = text;
  if (flutes == 1) {
    std::snprintf(text, sizeof text, ": the spindle ran at %.0f rpm (%+.0f %%)", rpm[0],
                  percent(rpm[0]));
    out += text;
  } else {
    std::snprintf(text, sizeof text, ": the spindle ran at %.0f rpm (%+.0f %%) if it is %s%s",
                  rpm[0], percent(rpm[0]), as[0],
                  tooth_passing ? " of its flutes (a line stands at that speed's spindle "
                                  "frequency too)"
                                : "");
    out += text;
    std::snprintf(text, sizeof text, ", at %.0f rpm (%+.0f %%) if it is %s (%d flutes)", rpm[1],
                  percent(rpm[1]), as[1], flutes);
    out += text;
  }
  return out +
         "; if it ran at one of them (an override?), set process.spindle_rpm to it, or widen "
         "spindle.search_fraction";
}

Pipeline::Pipeline(const MonitorConfig& config, PipelineSink& sink)
    : config_(config), sink_(sink), input_(input_config(config)) {
  validate(config_);
  filter_ = design(config_);
  conditioner_ = Conditioner(config_, filter_);
  stride_ = stride_for(config_);
  conditioner_.set_stride(stride_);
  const MonitorConfig measuring = measuring_config(config_);
  rate_hz_ = measuring.sample_rate_hz;
  decimation_ = decimation_for(measuring);
  const signal::SpindleTrackerConfig tc = tracker_config(measuring);
  tracker_.setup(tc);

  // From here on, samples are the measuring stages' (every stride_-th input sample).
  const double fs = rate_hz_;
  const int flutes = config_.model.tool.flutes;
  const double commanded_hz = tc.commanded_rpm / 60.0;
  const signal::TrackerTiming timing = signal::tracker_timing(tc);
  const double slowest_revolution = fs / (kSlowestFraction * commanded_hz);
  // The ring holds what a lock needs to look back on: the tracker's two windows before it and
  // some revolutions more, at least a quarter second.
  ring_ =
      SampleRing(kRingChannels,
                 static_cast<std::size_t>(std::max(
                     (3.0 * timing.window_s + 2.0 * timing.hop_s) * fs + 8.0 * slowest_revolution,
                     0.25 * fs)));
  ToothEventConfig ec;
  ec.flutes = flutes;
  ec.sample_rate_hz = fs;
  ec.search_fraction_of_pitch = config_.search_fraction_of_pitch;
  events_ = ToothEventTracker(ec);
  analyzer_ = RevolutionAnalyzer(
      measuring, static_cast<std::size_t>(slowest_revolution * (1.0 + 2.0 / flutes)) + 64);
  sync_ = SyncAverage(config_.sync_bins, config_.sync_window_revolutions);
  resultant_ = SyncAverageOf<1>(config_.sync_bins, config_.sync_window_revolutions);
  template_average_.reserve(static_cast<std::size_t>(config_.sync_bins));
  pauses_expected_ = pauses_between_flutes(config_.model);
  if (config_.lockstep) {
    lockstep_ = Lockstep(config_.model, filter_, config_.filter_zero_phase);
    build_delay_revolutions_ = std::max<std::int64_t>(
        2, static_cast<std::int64_t>(std::ceil(kModelBuildDelay_s * commanded_hz)));
  }
  stats_ = RevolutionStats(config_.alpha_window_revolutions);
  alerts_ = AlertEngine(config_.alerts);
  tooth_delay_s_ = config_.filter_zero_phase ? 0.0 : filter_.group_delay_s(commanded_hz * flutes);
  max_bridged_gap_ = static_cast<std::int64_t>(kMaxBridgedGap_s * config_.sample_rate_hz);
  max_filled_gap_ = std::max<std::int64_t>(
      1, static_cast<std::int64_t>(kFilledGapCutoffs / config_.filter_cutoff_hz *
                                   config_.sample_rate_hz));
  for (auto& channel : gap_fill_) {
    channel.assign(static_cast<std::size_t>(max_filled_gap_), 0.0);
  }
}

void Pipeline::event(PipelineEventKind kind, std::int64_t sample, std::int64_t count, double value,
                     std::string_view detail, std::int64_t block_seq,
                     std::optional<std::int64_t> block_utime_us) {
  PipelineEvent e;
  e.kind = kind;
  e.sample = sample;
  // A rejected block at the time it states, where plausible: the stream's clock has no time for
  // it before a first block is taken (a reload's pipeline refusing the stream's rate had said
  // t = 0 for every block), and an out-of-order block's own time is the one to look up.
  e.utime_us = block_utime_us && plausible_utime(*block_utime_us) ? *block_utime_us
                                                                  : input_.utime_of(sample);
  e.count = count;
  e.value = value;
  e.detail = detail;
  e.block_seq = block_seq;
  sink_.on_event(e);
}

void Pipeline::restart_stream(std::int64_t first_sample) {
  if (last_sample_ >= 0) {  // a break ends a stretch: the tracker starts afresh after it
    longest_stretch_ = std::max(longest_stretch_, last_sample_ - stretch_first_ + 1);
  }
  stretch_first_ = first_sample;
  line_run_ = 0;  // the tracker starts afresh
  line_reported_ = false;
  conditioner_.restart(
      [this](std::int64_t n, double fx, double fy, double fz) { downstream(n, fx, fy, fz); });
  if (events_.active()) {
    event(PipelineEventKind::kLockLost, first_sample, 0, 0.0, "stream restarted");
  }
  stream_start_ = measuring_sample(first_sample);
  if (last_sample_ < 0) {
    // The first health check after half a second, as every later one: over the first block
    // alone, a few bad samples would read as a large fraction.
    next_health_check_ = stream_start_ + static_cast<std::int64_t>(0.5 * rate_hz_);
  }
  decimation_phase_ = 0;
  cutting_revolutions_ += heard_since_update();  // the part-hop before the break
  finished_tail_revolutions_ = 0.0;
  tracker_.restart(0);
  phase_.valid = false;
  was_cutting_ = false;
  events_.stop();
  forget_labelling();  // the next lock is the tracker's own
  ring_.clear();
  sync_.clear();
  sync_revolutions_since_report_ = 0;
}

void Pipeline::bridge_gap(std::int64_t first_sample) {
  // A short gap: the spindle kept turning, so the tracker keeps its lock and sample time; it
  // sees the last value held over the gap. The filters restart at the next sample; tooth events
  // that fall into the gap have no samples and are skipped.
  conditioner_.restart(
      [this](std::int64_t n, double fx, double fy, double fz) { downstream(n, fx, fy, fz); });
  const double held = ring_.empty() ? 0.0 : std::sqrt(ring_.at(kDetectChannel, ring_.newest()));
  const std::int64_t first = measuring_sample(first_sample);
  while (stream_start_ + tracker_.next_sample() * decimation_ < first) {
    if (tracker_.process({&held, 1}) > 0) {
      on_tracker_update();
    }
  }
  decimation_phase_ =
      static_cast<int>((stream_start_ + tracker_.next_sample() * decimation_) - first);
}

bool Pipeline::process(const SampleBlock& block) {
  const std::int64_t expected_sample = input_.next_sample();  // the block's, were it on time
  const CheckedBlock timed = input_.check_time(block);
  if (timed.verdict == BlockVerdict::kRejected) {
    event(PipelineEventKind::kBlockRejected, expected_sample,
          static_cast<std::int64_t>(block.fx_N.size()), 0.0, timed.problem, block.seq,
          block.utime_us);
    return false;
  }
  // The stream's first block (or the first since a restart) starts it anew.
  const bool starts = timed.first_sample == 0 || last_sample_ < 0;
  // The usual block, the stream going on without a gap: its samples are tested as the filter
  // reads them (the block's first read, which a pass of its own would wait for); one that fails
  // goes the input check's way, every sample tested and replaced, and then through the filter.
  const bool filtered = timed.gap_samples == 0 && !starts && check_in_filter_ &&
                        conditioner_.filter_checked(timed.first_sample, block.fx_N, block.fy_N,
                                                    block.fz_N, input_.sample_limits());
  const CheckedBlock c = input_.check_samples(block, timed, filtered);
  if (c.gap_samples > 0) {
    const bool fill = c.gap_samples <= max_filled_gap_ && last_sample_ >= 0 && !c.fx_N.empty();
    event(PipelineEventKind::kGap, c.first_sample, c.gap_samples, 0.0,
          fill ? kFilledGap : c.problem, block.seq);
    if (fill) {
      fill_gap(c);
    } else if (c.gap_samples <= max_bridged_gap_ && last_sample_ >= 0) {
      bridge_gap(c.first_sample);
    } else {
      restart_stream(c.first_sample);
    }
  } else if (starts) {
    restart_stream(c.first_sample);
  }
  const std::int64_t nonfinite = c.nonfinite_samples;
  const std::int64_t saturated = c.saturated_samples;
  if (nonfinite > 0) {
    event(PipelineEventKind::kNonFinite, first_flagged(c, kFlagNonFinite), nonfinite, 0.0,
          "NaN, infinite or beyond ±1e6 N: replaced by the channel's last good value", block.seq);
  }
  if (saturated > 0) {
    event(PipelineEventKind::kSaturated, first_flagged(c, kFlagSaturated), saturated, 0.0,
          "at or beyond the charge amplifier's range", block.seq);
  }

  const std::size_t count = c.fx_N.size();
  if (filtered) {
    conditioner_.hand_on_checked(
        [this](std::int64_t n) { return run_limit(n); },
        [this](std::int64_t n, std::size_t run, const double* x, const double* y, const double* z) {
          downstream_run(n, run, x, y, z);
        });
  } else {
    condition(c.first_sample, c.fx_N, c.fy_N, c.fz_N);
  }
  last_sample_ = c.first_sample + static_cast<std::int64_t>(count) - 1;
  if (count > 0) {
    last_reading_ = {c.fx_N[count - 1], c.fy_N[count - 1], c.fz_N[count - 1]};
  }
  return true;
}

void Pipeline::fill_gap(const CheckedBlock& c) {
  // The few missing samples on the line from the last reading to the block's first, through
  // the filters as if read: far below the low-pass's reach, where restarting the filters (a
  // bridged gap) would leave milliseconds of their settling, and the tooth events with them.
  const auto gap = static_cast<std::size_t>(c.gap_samples);
  const std::array<double, 3> next = {c.fx_N[0], c.fy_N[0], c.fz_N[0]};
  for (std::size_t k = 0; k < gap; ++k) {
    const double w = static_cast<double>(k + 1) / static_cast<double>(gap + 1);
    for (std::size_t a = 0; a < 3; ++a) {
      gap_fill_[a][k] = last_reading_[a] + w * (next[a] - last_reading_[a]);
    }
  }
  condition(c.first_sample - c.gap_samples, std::span(gap_fill_[0]).first(gap),
            std::span(gap_fill_[1]).first(gap), std::span(gap_fill_[2]).first(gap));
}

void Pipeline::condition(std::int64_t first, std::span<const double> fx, std::span<const double> fy,
                         std::span<const double> fz) {
  conditioner_.push_block(
      first, fx, fy, fz, [this](std::int64_t n) { return run_limit(n); },
      [this](std::int64_t n, std::size_t run, const double* x, const double* y, const double* z) {
        downstream_run(n, run, x, y, z);
      });
}

void Pipeline::flush_tail() {
  conditioner_.flush(
      [this](std::int64_t n, double fx, double fy, double fz) { downstream(n, fx, fy, fz); });
  finished_tail_revolutions_ = heard_since_update();  // the record's last part-hop
  // Fits accepted for the model that no revolution will take now: counted, not lost.
  identifications_superseded_ += (waiting_fit_ ? 1 : 0) + (building_fit_ ? 1 : 0);
  waiting_fit_.reset();
  building_fit_.reset();
  // The input since the last health check (up to half a second: a gap there is a sensor
  // alert too).
  alerts_.on_input(input_.counters(),
                   input_.utime_of(std::max<std::int64_t>(0, input_.next_sample() - 1)),
                   [this](const Alert& a) { sink_.on_alert(a); });
}

void Pipeline::hand_over(std::string_view why) {
  flush_tail();
  alerts_.clear_active(why, [this](const Alert& a) { sink_.on_alert(a); });
}

void Pipeline::finish() {
  flush_tail();
  if (ever_locked_ || tracker_locked_ || line_ever_reported_) {
    return;  // measured, or a kNoTemplate or kSpeedOutOfRange said why not
  }
  // Say why nothing was measured.
  const signal::TrackerTiming t = signal::tracker_timing(tracker_config(config_));
  const double needed_s = 2.0 * t.window_s;  // two windows a window apart that agree
  const std::int64_t samples = input_.counters().samples_accepted;
  const std::int64_t at = std::max<std::int64_t>(0, last_sample_);
  if (samples == 0) {
    return;  // nothing came: nothing to say about it
  }
  // The tracker starts afresh after each break in the stream: what counts is the longest
  // stretch between breaks, not the record's samples.
  const std::int64_t longest = std::max(longest_stretch_, last_sample_ - stretch_first_ + 1);
  if (static_cast<double>(longest) < needed_s * config_.sample_rate_hz) {
    event(PipelineEventKind::kRecordTooShort, at, longest, needed_s,
          longest_stretch_ > 0  // a stretch ended at a break
              ? "the longest stretch between breaks in the stream; the spindle tracker locks on "
                "two windows (spindle.window_s) of steady cutting that agree"
              : "the spindle tracker locks on two windows (spindle.window_s) of steady cutting "
                "that agree");
  } else if (alias_windows_ > 0) {
    event(PipelineEventKind::kNoSteadySignal, at, alias_windows_, 0.0,
          "tracker windows agreed on a speed within the search whose lines are not the cut's: "
          "the harmonics of a spindle outside the search (spindle.search_fraction) falling on "
          "some of that speed's, an alias");
  } else if (inconsistent_windows_ > 0) {
    event(PipelineEventKind::kNoSteadySignal, at, inconsistent_windows_, 0.0,
          "weak or irregular cutting: tooth-passing lines came and went, but no two windows a "
          "window apart agreed on speed and phase");
  } else {
    char text[160];
    std::snprintf(text, sizeof text,
                  "weak or irregular cutting, or none: the spindle harmonics never stood "
                  "spindle.min_snr_db (%g dB) above the noise",
                  config_.spindle.min_snr_db);
    no_signal_detail_ = text;  // the event's detail is a view: kept while the pipeline lives
    event(PipelineEventKind::kNoSteadySignal, at, 0, 0.0, no_signal_detail_);
  }
}

void Pipeline::downstream(std::int64_t n, double fx, double fy, double fz) {
  downstream_run(n, 1, &fx, &fy, &fz);
}

std::size_t Pipeline::run_limit(std::int64_t n) const {
  // In measuring samples from m, the first at or after input sample n: the tracker's next
  // update comes with its k-th sample from now, which is m + decimation_phase_ + (k − 1)·
  // decimation_.
  const std::int64_t m = measuring_sample(n);
  const auto k = static_cast<std::int64_t>(tracker_.samples_to_update());
  std::int64_t last = m + decimation_phase_ + (k - 1) * decimation_;
  if (events_.active()) {
    last = std::min(last, events_.needed_sample());
  }
  last = std::min(last, next_health_check_);
  const std::int64_t last_input = last * stride_;
  return last_input > n ? static_cast<std::size_t>(last_input - n + 1) : 1;
}

void Pipeline::downstream_run(std::int64_t n, std::size_t count, const double* fx, const double* fy,
                              const double* fz) {
  // The run's samples on the measuring grid: input samples that are multiples of stride_.
  const std::int64_t m = measuring_sample(n);
  const auto skip = static_cast<std::size_t>(m * stride_ - n);
  if (skip >= count) {
    return;
  }
  const std::size_t taken = (count - 1 - skip) / static_cast<std::size_t>(stride_) + 1;
  measure_run(m, taken, fx + skip, fy + skip, fz + skip);
}

void Pipeline::measure_run(std::int64_t n, std::size_t count, const double* fx, const double* fy,
                           const double* fz) {
  // Valleys are sought on the squared in-plane force: near a valley the force is nearly
  // linear in time, so its square is a smooth parabola.
  const auto stride = static_cast<std::size_t>(stride_);
  static_assert(kRingChannels == 4);  // force_rows()'s rows
  ring_.push_rows(n, count, [&](std::size_t i, std::size_t rows, double* at) {
    const std::size_t j = i * stride;
    force_rows(fx + j, fy + j, fz + j, stride, rows, at);
  });
  // Every decimation_-th measuring sample's magnitude to the tracker, a batch per call
  // (run_limit(): only the run's last sample can start an update).
  bool updated = false;
  // Not zeroed (only what is written is read): zeroing its 512 bytes took a quarter of this
  // function at 50 kHz, one `rep stos` per block.
  std::array<double, 64> magnitudes;
  std::size_t batch = 0;
  for (auto i = static_cast<std::size_t>(decimation_phase_); i < count;
       i += static_cast<std::size_t>(decimation_)) {
    const std::size_t j = i * stride;
    magnitudes[batch++] = std::sqrt(fx[j] * fx[j] + fy[j] * fy[j]);
    if (batch == magnitudes.size()) {
      updated = tracker_.process({magnitudes.data(), batch}) > 0 || updated;
      batch = 0;
    }
  }
  updated = tracker_.process({magnitudes.data(), batch}) > 0 || updated;
  // Measuring samples until the tracker's next one, after the run.
  const auto phase =
      static_cast<std::int64_t>(decimation_phase_) - static_cast<std::int64_t>(count);
  decimation_phase_ =
      static_cast<int>(phase >= 0 ? phase : ((phase % decimation_) + decimation_) % decimation_);
  // What the last sample needs (run_limit(): none of the others needs anything).
  const std::int64_t last = n + static_cast<std::int64_t>(count) - 1;
  if (updated) {
    on_tracker_update();
  }
  if (events_.active() && last >= events_.needed_sample()) {
    advance_events();
  }
  if (last >= next_health_check_) {
    alerts_.on_input(input_.counters(), utime_at(last),
                     [this](const Alert& a) { sink_.on_alert(a); });
    next_health_check_ = last + static_cast<std::int64_t>(0.5 * rate_hz_);
  }
}

double Pipeline::heard_since_update() const {
  if (!was_cutting_) {
    return 0.0;
  }
  const double since_s =
      static_cast<double>(tracker_.samples_since_update() * static_cast<std::size_t>(decimation_)) /
      rate_hz_;
  return since_s * tracker_.estimate().spindle_hz;
}

void Pipeline::on_tracker_update() {
  const signal::SpindleEstimate& e = tracker_.estimate();
  const std::int64_t center = stream_start_ + e.center_sample * decimation_;
  SpindleUpdate u;
  u.utime_us = utime_at(center);
  u.seq = ++spindle_seq_;
  u.estimate = e;
  u.commanded_rpm = config_.model.process.spindle_rpm;

  // Turns heard while cutting: the time each cutting window covers that no earlier one did —
  // the whole first window of a cutting stretch, then a hop each. (A window after a spell
  // without cutting overlaps the last one counted: a gap bridged with the last value held
  // leaves such a spell, and counting that window whole had stated more turns than the record
  // holds.)
  if (e.cutting) {
    // The window's span in measuring samples: its centre is its first sample + w/2.
    const auto w = static_cast<std::int64_t>(tracker_.window_samples());
    const auto end =
        static_cast<double>(stream_start_ + (e.center_sample - w / 2 + w) * decimation_);
    const auto length = static_cast<double>(w * decimation_);
    const double added = std::clamp(end - cutting_counted_until_, 0.0, length);
    cutting_revolutions_ += added / rate_hz_ * e.spindle_hz;
    cutting_counted_until_ = end;
    if (!e.consistent && !e.valid) {
      ++inconsistent_windows_;
    }
  }
  was_cutting_ = e.cutting;
  note_line_outside_search(e, center);
  conditioner_.set_quiet(e.updates > 0 && !e.cutting, stats_.typical_peak_N());

  if (e.valid) {
    const signal::PhaseModel& p = tracker_.phase();
    phase_ = p;
    phase_.reference_sample = static_cast<double>(stream_start_) + p.reference_sample * decimation_;
    phase_.sample_rate_hz = rate_hz_;
    u.revolution = static_cast<std::int64_t>(
        std::floor(phase_.angle_at(static_cast<double>(center)) / kTwoPi));
  } else {
    phase_.valid = false;
  }
  sink_.on_spindle(u);
  // The tooth events' own speed checked against a consistent window's (the FFT's harmonics):
  // events that ran off are lost, and a fresh lock (below) finds them again at this speed.
  // Both at the window's centre: through a ramp the newest revolution runs ahead of it by half
  // a window (a 40,000 rpm/s jump: 700 rpm at 11,000 rpm).
  const double events_rpm = e.valid && e.consistent && events_.active()
                                ? events_rpm_at(static_cast<double>(center))
                                : 0.0;
  if (events_rpm > 0.0 &&
      std::fabs(events_rpm - e.spindle_rpm) > kEventSpeedDisagreement * e.spindle_rpm) {
    events_.stop();
    // The detail outlives the call (a sink may keep the view): the speeds go in value, count.
    event(PipelineEventKind::kLockLost, input_sample(center), std::llround(e.spindle_rpm),
          events_rpm, "the tooth events' speed left a consistent spindle tracker window's");
    last_rpm_ = 0.0;
  }
  // A lock starts the tooth events, unless they run already (they follow the cut on their own)
  // or the window's centre is still within what they measured before losing it.
  if (e.valid && !events_.active() &&
      static_cast<double>(center) >
          static_cast<double>(measured_until_) + phase_.samples_per_revolution()) {
    start_events();
  }
}

void Pipeline::note_line_outside_search(const signal::SpindleEstimate& e, std::int64_t center) {
  alias_windows_ += e.alias_refused ? 1 : 0;
  if (e.valid) {
    line_run_ = 0;
    line_reported_ = false;
    return;
  }
  if (!e.line_outside_search) {
    line_run_ = 0;
    return;
  }
  const double tolerance_hz = std::max(0.01 * e.line_hz, tracker_.bin_hz());
  if (line_run_ > 0 && std::fabs(e.line_hz - line_run_hz_) <= tolerance_hz) {
    ++line_run_;
    line_run_hz_ += (e.line_hz - line_run_hz_) / line_run_;
  } else {
    line_run_ = 1;
    line_run_hz_ = e.line_hz;
  }
  if (line_run_ >= kLineWindows && !line_reported_) {
    line_reported_ = true;
    line_ever_reported_ = true;
    event(PipelineEventKind::kSpeedOutOfRange, input_sample(center), line_run_, line_run_hz_,
          e.line_has_spindle_line
              ? kLineWithSpindleLine
              : "unlocked tracker windows agreed on a strongest spectral line outside the search");
  }
}

const char* Pipeline::build_template(std::int64_t anchor, ToothEventTemplate& out) {
  // The revolution-synchronous average, on the tracker's angle, over the two windows that
  // agreed on the lock (or template_revolutions around the lock's window centre, if more; at
  // most the synchronous average's window, the last turns), and the tooth events on it.
  const double window = static_cast<double>(tracker_.window_samples() * decimation_);
  const double half =
      std::max(0.5 * config_.template_revolutions * phase_.samples_per_revolution(), 0.5 * window);
  const std::int64_t lo = std::max(
      ring_.oldest(), anchor - static_cast<std::int64_t>(std::ceil(std::max(half, 1.5 * window))));
  const std::int64_t hi =
      std::min(ring_.newest(), anchor + static_cast<std::int64_t>(std::ceil(half)));
  if (hi - lo < static_cast<std::int64_t>(phase_.samples_per_revolution())) {
    return kNoDistinctEvents;
  }
  sync_.clear();
  resultant_.clear();
  // The window's last turns (more would start a new window: SyncAverageOf's windows tumble).
  const double first_turn =
      std::floor(phase_.angle_at(static_cast<double>(hi)) / kTwoPi) - (sync_.window() - 1);
  double previous_turn =
      std::max(first_turn, std::floor(phase_.angle_at(static_cast<double>(lo)) / kTwoPi));
  for (std::int64_t s = lo; s <= hi; ++s) {
    const double a = phase_.angle_at(static_cast<double>(s));
    const double turn = std::floor(a / kTwoPi);
    if (turn < first_turn) {
      continue;
    }
    if (turn > previous_turn) {
      sync_.end_revolution();
      resultant_.end_revolution();
      previous_turn = turn;
    }
    const double within_turn = a - kTwoPi * turn;
    sync_.add(within_turn, {ring_.at(0, s), ring_.at(1, s), ring_.at(2, s)});
    resultant_.add(within_turn, {std::sqrt(ring_.at(kDetectChannel, s))});
  }
  sync_.end_revolution();
  resultant_.end_revolution();
  // The tooth events are the in-plane resultant's: with one of its channels dead (an amplifier
  // off, a cable out) they would be the other channel's zero crossings, and every speed, period
  // and α from them wrong (a real cut with Fy zeroed: 12,400-17,800 rpm stated for 10,422).
  // The synchronous average's range: the cut's periodic force, the noise averaged down (a dead
  // channel's amplifier noise alone would be a sizeable share of a micro-cut's raw range).
  std::array<double, 2> range_N{};
  for (int c = 0; c < 2; ++c) {
    sync_.average(c, template_average_);
    const auto [lowest, highest] =
        std::minmax_element(template_average_.begin(), template_average_.end());
    range_N[static_cast<std::size_t>(c)] = *highest - *lowest;
  }
  // The smaller range over the larger (0 when neither channel moves).
  const double larger_N = std::max(range_N[0], range_N[1]);
  flat_range_ratio_ = larger_N > 0.0 ? std::min(range_N[0], range_N[1]) / larger_N : 0.0;
  if (range_N[1] < kFlatChannel * range_N[0]) {
    return kDeadFy;
  }
  if (range_N[0] < kFlatChannel * range_N[1]) {
    return kDeadFx;
  }
  resultant_.average(0, template_average_);
  out = find_tooth_event_template(template_average_, config_.model.tool.flutes, pauses_expected_);
  return out.valid ? nullptr : kNoDistinctEvents;
}

void Pipeline::start_events() {
  tracker_locked_ = true;
  const signal::SpindleEstimate& e = tracker_.estimate();
  const std::int64_t anchor = stream_start_ + e.center_sample * decimation_;
  ToothEventTemplate tmpl;
  const char* why = build_template(anchor, tmpl);
  if (why == nullptr || why == kDeadFx || why == kDeadFy) {  // the channels were looked at
    alerts_.set_dead_channel(why == kDeadFx   ? 0
                             : why == kDeadFy ? 1
                                              : -1,
                             flat_range_ratio_, kFlatChannel);
  }
  if (why != nullptr) {
    event(PipelineEventKind::kNoTemplate, input_sample(anchor), 0, e.spindle_rpm, why);
    return;
  }
  ++locks_;  // before the model: a fit taken here is no longer this lock's
  if (config_.lockstep) {
    follow_speed(phase_.spindle_hz_at(static_cast<double>(anchor)), true);
    // On the template average: a first offset, in the tracker's angle (no residuals on it).
    lockstep_.align(sync_);
    aligned_on_template_ = true;
    next_alignment_revolutions_ = 1;
    first_alignment_restarts_ = 0;
  }
  const std::int64_t earliest =
      std::max(stream_start_, measured_until_ == INT64_MIN ? stream_start_ : measured_until_ + 1);
  if (!events_.start(tmpl, phase_, static_cast<double>(anchor), earliest, ring_, kDetectChannel)) {
    event(PipelineEventKind::kNoTemplate, input_sample(anchor), 0, e.spindle_rpm,
          "no tooth event where the lock puts one");
    return;
  }
  restart_average();
  // The last lock's speed (events stopped for an idle spell keep it) is no speed of this one:
  // neither the status nor the events' speed check may read it before a revolution here.
  last_rpm_ = 0.0;
  recent_speeds_.fill({});
  lock_revolution_ = revolution_base_ + revolutions_;
  start_labelling(anchor);
  stats_.restart();
  alerts_.rebaseline();
  ever_locked_ = true;
  idle_ = false;
  event(PipelineEventKind::kLockAcquired, input_sample(anchor), 0, 60.0 * phase_.spindle_hz,
        "spindle locked");
  advance_events();
}

void Pipeline::restart_average() {
  sync_.clear();
  sync_revolutions_since_report_ = 0;
  window_rpm_sum_ = 0.0;
  window_rpm_count_ = 0;
}

void Pipeline::advance_events() {
  events_.advance(ring_, [this](const RevolutionEvents& r) { on_revolution(r); });
  // Events that stopped on their own (the pipeline's own stops say why where they happen): the
  // state falls back to tracking and the next lock measures the revolutions since.
  const ToothEventLoss loss = events_.take_loss();
  if (loss != ToothEventLoss::kNone) {
    event(PipelineEventKind::kLockLost, input_sample(events_.last_closed_sample()), 0, last_rpm_,
          to_string(loss));
    last_rpm_ = 0.0;
  }
}

double Pipeline::events_rpm_at(double n) const {
  for (const RevolutionSpeed& r : recent_speeds_) {
    if (r.rpm > 0.0 && r.from <= n && n <= r.to) {
      return r.rpm;
    }
  }
  return 0.0;
}

void Pipeline::follow_speed(double spindle_hz, bool now) {
  if (!config_.lockstep || !(spindle_hz > 0.0)) {
    return;
  }
  wanted_hz_ = spindle_hz;
  const auto moved = [&](double built_hz) {
    return !lockstep_.has_model() ||
           std::fabs(spindle_hz - built_hz) > kModelSpeedChange * built_hz;
  };
  if (now || !lockstep_.has_model()) {
    take_model_build(false, false);  // the build under way first, then this speed's
    if (moved(lockstep_.spindle_hz())) {
      lockstep_.set_spindle_hz(spindle_hz);
      count_model_build();
    }
    if (!builder_) {  // the later builds' (with the lock's burst, not in a revolution of its own)
      builder_ = std::make_unique<ModelBuilder>(config_.model, filter_, config_.filter_zero_phase);
    }
    start_fit_build();  // at this speed
    return;
  }
  const bool building = builder_ && builder_->busy();
  // Against the model to come, if one is being built.
  if (!moved(building ? builder_->spindle_hz() : lockstep_.spindle_hz())) {
    return;
  }
  if (building || waiting_fit_ || !builder_) {  // builder_ comes with the first model
    return;  // one at a time, a fit's first: a revolution after it is taken asks again
  }
  builder_->start(lockstep_.commanded_config(), spindle_hz);
  build_due_ = revolutions_ + build_delay_revolutions_;
}

void Pipeline::take_model_build(bool due_only, bool start_next) {
  if (!builder_ || !builder_->busy() || (due_only && revolutions_ < build_due_)) {
    return;
  }
  // A fit of a window from before a relabelling: its build is taken (the builder hands over
  // nothing else) and the model built again, as it was, at once.
  std::optional<model::ModelConfig> before;
  if (building_fit_ && building_fit_->stale) {
    before = lockstep_.commanded_config();
  }
  builder_->take_into(lockstep_);
  count_model_build();
  if (before) {
    ++identifications_superseded_;
    building_fit_.reset();
    builder_->start(*before, wanted_hz_);
    build_due_ = revolutions_ + build_delay_revolutions_;
    return;
  }
  if (building_fit_) {
    apply_fit(*building_fit_);
    building_fit_.reset();
  }
  if (start_next) {
    start_fit_build();  // a fit that waited for this build
  }
}

void Pipeline::count_model_build() {
  ++model_builds_;
  const model::SteadyStateStats& st = lockstep_.steady_state_stats();
  if (st.unconverged_slots > 0) {
    ++model_builds_unsettled_;
    if (st.unconverged_slots > model_unsettled_slots_most_) {
      model_unsettled_slots_most_ = st.unconverged_slots;
      model_slots_of_most_ = st.slots;
    }
  }
  model_builds_area_unsettled_ += st.area_converged ? 0 : 1;
}

void Pipeline::submit_window() {
  if (identifier_ == nullptr || window_rpm_count_ == 0 || sync_.revolutions() == 0) {
    return;
  }
  for (int a = 0; a < 3; ++a) {
    sync_.average(a, window_.force_N[static_cast<std::size_t>(a)]);
  }
  window_.spindle_rpm = window_rpm_sum_ / window_rpm_count_;
  window_.revolutions = sync_.revolutions();
  window_rpm_sum_ = 0.0;
  window_rpm_count_ = 0;
  // Due when the next window ends: the fit has a window's time to finish.
  const std::int64_t end_us = utime_at(ring_.newest());
  identifier_->submit(window_, last_revolution(), end_us,
                      revolutions_ + config_.sync_window_revolutions);
  // While no estimate comes (fits rejected, or live, a worker that cannot keep up), the alerts
  // follow the flute forces; the next accepted estimate takes over again. Windows the live
  // identifier skips for its CPU budget do not count while the last estimate is recent enough
  // (identify::EstimateWatch).
  const double window_s = 60.0 * window_.revolutions / window_.spindle_rpm;
  if (estimate_watch_.window_submitted(end_us, window_s, identifier_->budget_period_s())) {
    alerts_.expect_estimates(false);
  }
}

void Pipeline::take_identification() {
  if (identifier_ == nullptr) {
    return;
  }
  const std::optional<identify::IdentifiedWindow> w = identifier_->take_due(revolutions_);
  if (!w) {
    return;
  }
  const identify::FitResult& fit = w->fit;
  const double unexplained = identify::unexplained_variance(fit.residual_rms_N, fit.measured_rms_N);
  if (!fit.ok || !(unexplained <= config_.identification.max_unexplained)) {
    ++identifications_rejected_;
    return;  // a model that does not fit the cut says nothing reliable about it
  }
  if (w->revolution - w->window_revolutions + 1 < labelling_revolution_) {
    ++identifications_superseded_;  // its flutes named from another CE1 (a relabelling since)
    return;
  }
  estimate_watch_.estimate_accepted(w->utime_us);
  alerts_.on_identification(*w, [this](const Alert& a) { sink_.on_alert(a); });
  if (!config_.lockstep) {
    return;
  }
  // The model is rebuilt with the parameters on builder_'s thread and takes them when due (a
  // newer fit replaces one still waiting for the builder).
  PendingFit f;
  f.config = fit.config;
  f.alignment_rad = fit.alignment_rad.value;
  // The window's alignment holds while the tracker's angle zero is the one it was measured in.
  f.same_lock = w->revolution - w->window_revolutions + 1 >= lock_revolution_;
  f.lock = locks_;
  f.window_revolution = w->revolution;
  f.unexplained = unexplained;
  if (waiting_fit_) {
    ++identifications_superseded_;  // never built: this newer one replaces it
  }
  waiting_fit_ = std::move(f);
  start_fit_build();
}

void Pipeline::start_fit_build() {
  // Not before the first model (built at the lock, at once): it comes with a speed.
  if (!waiting_fit_ || !lockstep_.has_model() || !builder_ || builder_->busy()) {
    return;
  }
  // At the newest speed the model was asked to follow (a fit's build follows it too; set by
  // follow_speed() before the first model, which this waits for).
  builder_->start(waiting_fit_->config, wanted_hz_);
  build_due_ = revolutions_ + build_delay_revolutions_;
  building_fit_ = std::move(waiting_fit_);
  waiting_fit_.reset();
}

void Pipeline::apply_fit(const PendingFit& f) {
  if (f.same_lock && f.lock == locks_) {
    // The fit's alignment, on the window's revolutions: no correlation on the old model's shape.
    lockstep_.set_alignment(f.alignment_rad);
    aligned_on_template_ = false;
    next_alignment_revolutions_ = 0;
  } else if (sync_.first_window() || sync_.revolutions() >= sync_.window()) {
    // A lock since: the tracker's angle zero moved. On the average as it is (this lock's
    // template, or its revolutions), the alignments due still to come.
    lockstep_.align(sync_);
  } else {
    // Part-way through a later window of this lock (its first was aligned on): on this one
    // once it is full, not on its first few revolutions.
    next_alignment_revolutions_ = sync_.window();
  }
  ++identifications_taken_;
  event(PipelineEventKind::kModelUpdated, input_sample(measured_until_), f.window_revolution,
        f.unexplained, "identified parameters taken by the model in lockstep");
}

void Pipeline::on_revolution(const RevolutionEvents& ev) {
  const auto n = static_cast<std::size_t>(ev.flutes);
  // A revolution that a gap in the samples cut into (counted with the gap) is not measured: the
  // ring holds the samples since the gap only, and the rows before them are a lap old.
  if (ev.no_data || std::ceil(ev.boundary_sample[0]) < static_cast<double>(ring_.oldest()) ||
      std::floor(ev.boundary_sample[n]) > static_cast<double>(ring_.newest())) {
    return;
  }
  take_model_build(true);
  take_identification();
  const std::int64_t first = nearest_sample(ev.event_sample[0]);
  // The model follows the filtered revolution period, not one revolution's jitter.
  follow_speed(rate_hz_ / events_.samples_per_revolution());
  RevolutionRecord& r = record_;
  analyzer_.analyze(
      ev, events_.event_template(), ring_,
      config_.lockstep && lockstep_.aligned() && !aligned_on_template_ ? &lockstep_ : nullptr, r);
  measured_until_ = static_cast<std::int64_t>(std::floor(ev.event_sample[n]));

  // A revolution without cutting force is counted, not reported; a few in a row end the cut.
  double peak = 0.0;
  for (std::size_t j = 0; j < n; ++j) {
    peak = std::max(peak, r.measured.peak_resultant_N[j]);
  }
  if (!stats_.cutting(r.measured)) {
    ++idle_revolutions_;
    if (!idle_) {
      idle_ = true;
      event(PipelineEventKind::kCuttingStopped, input_sample(first), 0, peak,
            "no cutting force in the revolution");
    }
    if (++idle_streak_ >= kIdleToStop) {
      events_.stop();
      event(PipelineEventKind::kLockLost, input_sample(first), 0, 0.0, "no cutting force");
    }
    return;
  }
  idle_streak_ = 0;
  if (idle_) {
    idle_ = false;
    event(PipelineEventKind::kCuttingResumed, input_sample(first), 0, peak, "cutting force again");
  }
  // A revolution joins the synchronous average when its bounds (the CE1 events) were found,
  // even if a flute in between left no event (a flute that does not cut).
  if (ev.bounded) {
    analyzer_.add_to_average(ev, events_.event_template(), ring_, sync_);
    ++sync_revolutions_since_report_;
    if (r.spindle_rpm > 0.0) {
      window_rpm_sum_ += r.spindle_rpm;
      ++window_rpm_count_;
    }
    if (config_.lockstep && lockstep_.aligned() && next_alignment_revolutions_ > 0 &&
        sync_.revolutions() >= next_alignment_revolutions_) {
      align_on_revolutions(ev, input_sample(first), r);
    }
  }
  r.revolution = revolution_base_ + revolutions_++;
  valid_revolutions_ += r.measured.valid ? 1 : 0;
  r.utime_us = utime_at(first) - nearest_integer(tooth_delay_s_ * 1e6);
  stats_.add(r);
  if (r.spindle_rpm > 0.0) {
    last_rpm_ = r.spindle_rpm;  // the last measured speed (one coasting revolution states none)
  }
  recent_speeds_[recent_speeds_next_] = {ev.event_sample[0], ev.event_sample[n], r.spindle_rpm};
  recent_speeds_next_ = (recent_speeds_next_ + 1) % recent_speeds_.size();
  sink_.on_revolution(r);
  alerts_.on_revolution(r, [this](const Alert& a) { sink_.on_alert(a); });
  tell_alert_state(input_sample(first), r.spindle_rpm);
  if (check_labelling(r, input_sample(first))) {
    return;  // its window is another labelling's: the relabelling's lock starts a new one
  }
  // Every window of revolutions as it fills, whatever the block size: a block holding more than
  // a window's revolutions (calibrate's 4,096 samples at 20 kHz and 30,000 rpm: 100) must not
  // leave the windows between its ends unfitted.
  if (sync_revolutions_since_report_ >= config_.sync_window_revolutions) {
    sync_revolutions_since_report_ = 0;
    submit_window();
    // Named by its last revolution (as identification names the window), not the next one.
    sink_.on_sync_average(sync_, lockstep_.aligned() ? &lockstep_ : nullptr, last_revolution(),
                          utime_at(ring_.newest()));
  }
}

void Pipeline::start_labelling(std::int64_t anchor) {
  // A lock of the tracker's own starts the count of relabellings; a relabelling's carries it. A
  // lock long after a relabelling (the cut stopped before its lock came) is the tracker's own.
  const auto soon = static_cast<std::int64_t>(kRelabellingLockWindows * tracker_.window_samples() *
                                              static_cast<std::size_t>(decimation_));
  const bool relabelling_lock = relabelling_ && anchor - relabelled_at_ <= soon;
  relabellings_ = relabelling_lock ? relabellings_ : 0;
  relabelling_ = false;
  if (relabellings_ > 0) {
    labelling_revolution_ = lock_revolution_;
  }
  label_peak_sum_N_.fill(0.0);
  label_revolutions_ = 0;
  label_candidate_ = 0;
  label_windows_ = 0;
}

void Pipeline::forget_labelling() {
  relabelling_ = false;
  relabellings_ = 0;
}

bool Pipeline::check_labelling(const RevolutionRecord& r, std::int64_t sample) {
  // CE1 is the flute with the largest force on the lock's template revolutions. Where those
  // were unlike the cut (a knock of 20 revolutions with the flutes' forces swapped), α and ΔFy
  // would come from the other edge for as long as the lock lasts (α 204° for the cut's 155°).
  // So while the alerts' flute-force baseline forms, kFluteLabellingWindows full windows in a
  // row in which the same other flute holds clearly more force lock again. Once the baseline is
  // armed, another flute growing stronger is the runout change the alerts raise, not a
  // labelling to correct. A disturbance after a good lock long enough to relabel is undone the
  // same way once it ends (the new template chose the disturbance's CE1), up to
  // kMostRelabellings times.
  const int flutes = config_.model.tool.flutes;
  if (flutes < 2 || !r.measured.bounded || alerts_.baseline().ready) {
    return false;
  }
  for (int j = 0; j < flutes; ++j) {
    label_peak_sum_N_[static_cast<std::size_t>(j)] +=
        r.measured.peak_resultant_N[static_cast<std::size_t>(j)];
  }
  if (++label_revolutions_ < config_.sync_window_revolutions) {
    return false;
  }
  std::size_t strongest = 0;
  for (std::size_t j = 1; j < static_cast<std::size_t>(flutes); ++j) {
    if (label_peak_sum_N_[j] > label_peak_sum_N_[strongest]) {
      strongest = j;
    }
  }
  const double ce1_N = label_peak_sum_N_[0];
  const bool doubt = strongest != 0 && label_peak_sum_N_[strongest] > kFluteLabellingMargin * ce1_N;
  const double ratio = ce1_N > 0.0 ? label_peak_sum_N_[strongest] / ce1_N : 0.0;
  label_peak_sum_N_.fill(0.0);
  label_revolutions_ = 0;
  if (doubt) {
    label_windows_ = strongest == label_candidate_ ? label_windows_ + 1 : 1;
  } else {
    label_windows_ = 0;
  }
  label_candidate_ = doubt ? strongest : 0;
  if (label_windows_ < kFluteLabellingWindows || relabellings_ >= kMostRelabellings) {
    return false;  // the labelling holds (so far), or relabelling gave up for this lock
  }
  events_.stop();
  relabelling_ = true;
  relabelled_at_ = ring_.newest();
  ++relabellings_;
  ++flutes_relabelled_;
  // Fits of windows before it name the flutes otherwise: not taken.
  if (waiting_fit_) {
    ++identifications_superseded_;
    waiting_fit_.reset();
  }
  if (building_fit_) {
    building_fit_->stale = true;
  }
  event(PipelineEventKind::kFlutesRelabelled, sample, static_cast<std::int64_t>(strongest) + 1,
        ratio,
        "another flute held more force than CE1 over the windows since the lock: locking "
        "again, the new template choosing CE1");
  last_rpm_ = 0.0;
  return true;
}

void Pipeline::align_on_revolutions(const RevolutionEvents& ev, std::int64_t sample,
                                    RevolutionRecord& r) {
  // The template's tooth events come from another estimator (on the average of two tracker
  // windows) than the revolutions' searches: on simulated cuts the lock's offset lay 2-6° from
  // the one on the revolutions, and the residuals of the first window's revolutions, aligned by
  // the lock's offset, were 7-36 times what the model leaves once aligned on them.
  const bool first = aligned_on_template_;
  const bool full = sync_.revolutions() >= sync_.window();
  const double template_rad = lockstep_.offset_rad();
  if (!lockstep_.align(sync_)) {
    return;  // (not with a model and a revolution in the average) the next revolution tries again
  }
  next_alignment_revolutions_ = full ? 0 : std::min(2 * sync_.revolutions(), sync_.window());
  if (first && !full) {
    // A few revolutions against the template's two windows: a peak a pitch away (a tool
    // entering, a knock) is not taken. Those revolutions are unlike the cut: the average starts
    // again without them (kept, they bent the alignment that took them: up to 5x the cut's
    // residual over the next 15 revolutions) — a few times, within the lock's first window.
    // Then the template may be what is wrong: the average grows until a full window decides.
    const double pitch_rad = kTwoPi / config_.model.tool.flutes;
    const double moved_rad =
        std::remainder(lockstep_.offset_rad() - template_rad, kTwoPi);  // (−π, π]
    if (std::fabs(moved_rad) > 0.25 * pitch_rad) {
      lockstep_.set_alignment(template_rad);
      if (first_alignment_restarts_ < kFirstAlignmentRestarts &&
          revolution_base_ + revolutions_ - lock_revolution_ < config_.sync_window_revolutions) {
        ++first_alignment_restarts_;
        restart_average();
        next_alignment_revolutions_ = 1;
      }
      return;
    }
  }
  if (first) {
    aligned_on_template_ = false;
    event(PipelineEventKind::kModelAligned, sample, sync_.revolutions(),
          lockstep_.alignment_correlation(), "model aligned on the lock's first revolutions");
    analyzer_.analyze_model(ev, events_.event_template(), ring_, lockstep_, r);  // this one's
  } else if (full) {
    event(PipelineEventKind::kModelAligned, sample, sync_.revolutions(),
          lockstep_.alignment_correlation(), "model aligned on a full window of revolutions");
  }
}

void Pipeline::tell_alert_state(std::int64_t sample, double rpm) {
  const AlertEngine::Baseline& base = alerts_.baseline();
  const bool holding = alerts_.holding();
  if (holding && !alerts_holding_) {
    event(PipelineEventKind::kAlertsHeld, sample, std::llround(base.spindle_rpm), rpm,
          "runout change and wear drift hold until a baseline forms at the new speed or the "
          "speed comes back");
  }
  if (base.ready && (!alerts_armed_ || base.spindle_rpm != alerts_baseline_rpm_)) {
    event(PipelineEventKind::kAlertsArmed, sample, 0, base.spindle_rpm,
          alerts_armed_ ? "a new flute-force baseline at this speed"
                        : "the flute-force baseline formed");
  } else if (base.ready && alerts_holding_ && !holding) {
    event(PipelineEventKind::kAlertsArmed, sample, 0, base.spindle_rpm,
          "the speed came back to the flute-force baseline's");
  }
  alerts_holding_ = holding;
  alerts_armed_ = base.ready;
  alerts_baseline_rpm_ = base.spindle_rpm;
}

PipelineStatus Pipeline::status() const {
  PipelineStatus s;
  s.input = input_.counters();
  s.revolutions = revolutions_;
  s.valid_revolutions = valid_revolutions_;
  s.idle_revolutions = idle_revolutions_;
  s.model_builds = model_builds_;
  s.model_builds_unsettled = model_builds_unsettled_;
  s.model_unsettled_slots_most = model_unsettled_slots_most_;
  s.model_slots_of_most = model_slots_of_most_;
  s.model_builds_area_unsettled = model_builds_area_unsettled_;
  s.identifications_taken = identifications_taken_;
  s.identifications_rejected = identifications_rejected_;
  s.identifications_superseded = identifications_superseded_;
  s.alert_held_revolutions = alerts_.held_revolutions();
  s.alerts_holding = alerts_holding_;
  s.flutes_relabelled = flutes_relabelled_;
  s.relabelled_from_revolution = labelling_revolution_;
  s.cutting_revolutions = cutting_revolutions_ + finished_tail_revolutions_;
  s.utime_us = input_.utime_of(std::max<std::int64_t>(0, input_.next_sample() - 1));
  const auto& e = tracker_.estimate();
  // The last revolution's speed only while revolutions are measured: after the lock is lost the
  // spindle may have stopped.
  s.spindle_rpm = events_.active() && last_rpm_ > 0.0 ? last_rpm_ : (e.valid ? e.spindle_rpm : 0.0);
  s.cutting = e.cutting || events_.active();
  s.state = events_.active()              ? "measuring"
            : e.valid                     ? "tracking"
            : e.updates > 0 && !e.cutting ? "no cutting"
                                          : "acquiring";
  s.event_kind = to_string(events_.event_template().kind);
  return s;
}

}  // namespace millwatch::monitor
