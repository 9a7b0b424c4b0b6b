#include "core/monitor/tooth_events.hpp"

#include <Eigen/Dense>
#include <numbers>
#include <vector>

namespace millwatch::monitor {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
// Where the cut's geometry leaves a pause between the flutes: a dynamometer's ringing there
// rebounds to ~15 % of the span (its resonance a little above the 3.3 kHz low-pass).
constexpr double kPauseQuietFraction = 0.25;
// Two arms of a W in the synchronous average count as about as deep within this fraction of
// the window's span (a 6-flute cut through a 4.5 kHz dynamometer at 13,000 rpm: 0.3–2 %):
// well below the quiet level that makes a stretch a pause (10 %), so that an arm taken for a
// valley still says whether the cut pauses there.
constexpr double kTemplateBasinDepth = 0.05;
constexpr int kStartFit = 32;             // CE1 events kept on the way back to start the filter
constexpr int kParabolaEvents = 6;        // the fewest a parabola may start it from (on a ramp)
constexpr double kCurvatureSigmas = 4.0;  // a ramp: curvature beyond this many standard errors
constexpr double kMinPulse = 0.2;         // of the lock's force: around an event, the cut's force
// The CE1 events' times are tracked by a fading-memory g-h-k filter (position: the event,
// velocity: the revolution period, acceleration: the period's change per revolution; gains
// from one memory factor θ: g = 1 − θ³, h = 1.5·(1 − θ²)(1 − θ), k = 0.5·(1 − θ)³). It
// remembers ~1/(1 − θ) revolutions, so predictions and the reported speed hardly jitter, and
// it follows a ramp (a constant change of period per revolution) without lag; as a ramp ends it
// runs on for about as long. θ = 0.75 (4 revolutions): at 0.85 a 6-flute cut ramping 11,000 →
// 13,000 rpm in 0.3 s was stated at 13,222 rpm (+1.7 %) after the spindle had settled (now
// +0.56 %), the ramps of EveryRevolution erred by up to 56 rpm (now 31), while the PHM cut's
// speed jitters ± 1.1 rpm over its revolutions (was ± 0.5).
constexpr double kMemory = 0.75;
// A manoeuvre (a ramp's start or end: the CE1 event off its prediction by more than
// kManoeuvre times the filter's typical miss) shortens the memory to kFastMemory for
// kFastRevolutions revolutions, so that the filter takes up or drops the period's change in
// about two revolutions instead of four; the typical miss (a running mean of |miss|, each term
// capped at kManoeuvre times it, so that a ramp does not inflate it) keeps the steady cut's
// jitter as low as before. A 2-flute cut ramping 24,000 → 26,000 rpm in 0.2 s at 50 kHz is then
// stated within 35 rpm of the spindle over each revolution, RMS 4.0 rpm, where θ = 0.75 alone
// erred by up to 63 rpm, RMS 11.0; the PHM cuts' speeds are unchanged.
constexpr double kFastMemory = 0.5;
constexpr double kManoeuvre = 4.0;
constexpr int kFastRevolutions = 3;
constexpr double kMissMemory = 0.95;
constexpr double kMinMiss_samples = 0.01;  // noise-free cuts: no manoeuvre in rounding

struct Gains {
  double g, h, k;
};
constexpr Gains gains_of(double memory) {
  return {1.0 - memory * memory * memory, 1.5 * (1.0 - memory * memory) * (1.0 - memory),
          0.5 * (1.0 - memory) * (1.0 - memory) * (1.0 - memory)};
}
constexpr Gains kGains = gains_of(kMemory);
constexpr Gains kFastGains = gains_of(kFastMemory);

struct StartState {
  double anchor = 0.0;  // CE1 event of the start turn, samples
  double period = 0.0;  // samples per revolution there
  double rate = 0.0;    // change of the period per revolution
  double spread = 0.0;  // the events' scatter about a steady line (σ from their MAD), samples
};

double median_of(std::span<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// Whether the parabola c (normal matrix a) over the events kept (deviation ≤ limit) has a
/// curvature beyond kCurvatureSigmas of its standard error.
bool curvature_stands_out(std::span<const std::int64_t> turn, std::span<const double> sample,
                          std::int64_t start_turn, double limit, std::span<const double> deviation,
                          const Eigen::Matrix3d& a, const Eigen::Vector3d& c) {
  double rss = 0.0;
  int kept = 0;
  for (std::size_t i = 0; i < turn.size(); ++i) {
    if (deviation[i] > limit) {
      continue;
    }
    const auto t = static_cast<double>(turn[i] - start_turn);
    const double r = sample[i] - (c[0] + c[1] * t + c[2] * t * t);
    rss += r * r;
    ++kept;
  }
  const double variance = rss / (kept - 3) * a.inverse()(2, 2);
  return c[2] * c[2] > kCurvatureSigmas * kCurvatureSigmas * variance;
}

/// The CE1 events' times as a function of their turn, robustly: a line through the median
/// interval first (the revolution where the cut begins has a distorted valley), then a least-
/// squares line — or parabola, on a ramp, with enough events — through the events within three
/// median absolute deviations of it.
StartState fit_start(std::span<const std::int64_t> turn, std::span<const double> sample,
                     std::int64_t start_turn, double fallback_period) {
  const std::size_t n = turn.size();
  StartState out{sample.empty() ? 0.0 : sample[0], fallback_period, 0.0};
  std::array<double, kStartFit> scratch{};
  std::size_t intervals = 0;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t k = 0; k < n; ++k) {
      if (turn[k] == turn[i] + 1) {
        scratch[intervals++] = sample[k] - sample[i];
      }
    }
  }
  if (intervals == 0) {
    return out;
  }
  const double period = median_of(std::span(scratch).first(intervals));
  for (std::size_t i = 0; i < n; ++i) {
    scratch[i] = sample[i] - period * static_cast<double>(turn[i] - start_turn);
  }
  const double anchor = median_of(std::span(scratch).first(n));
  for (std::size_t i = 0; i < n; ++i) {
    scratch[i] = std::fabs(sample[i] - anchor - period * static_cast<double>(turn[i] - start_turn));
  }
  std::array<double, kStartFit> deviation = scratch;
  const double mad = median_of(std::span(deviation).first(n));
  const double limit = std::max(3.0 * 1.4826 * mad, 0.05);
  out.spread = 1.4826 * mad;
  // Normal equations of s = a + b·t + c·t² over the events kept.
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Vector3d y = Eigen::Vector3d::Zero();
  int kept = 0;
  std::int64_t span = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (scratch[i] > limit) {
      continue;
    }
    const auto t = static_cast<double>(turn[i] - start_turn);
    const Eigen::Vector3d row(1.0, t, t * t);
    a += row * row.transpose();
    y += row * sample[i];
    ++kept;
    span = std::max(span, turn[i] - start_turn);
  }
  out.anchor = anchor;
  out.period = period;
  if (kept >= kParabolaEvents && span >= kParabolaEvents) {
    const Eigen::Vector3d c = a.ldlt().solve(y);
    // Over fewer than 16 revolutions a parabola's end slope is noisy: taken only where its
    // curvature stands out of the events' scatter — a ramp, whose period a line would give at
    // the fit's middle, not at its start (5,000 rpm/s, 14 revolutions back: 0.4 % off).
    if ((kept >= 16 && span >= 16) ||
        curvature_stands_out(turn, sample, start_turn, limit, scratch, a, c)) {
      out.anchor = c[0];
      out.period = c[1];
      out.rate = 2.0 * c[2];
      return out;
    }
  }
  if (kept >= 2 && span >= 1) {
    const Eigen::Vector2d c = a.topLeftCorner<2, 2>().ldlt().solve(y.head<2>());
    out.anchor = c[0];
    out.period = c[1];
  }
  return out;
}

double wrap_2pi(double a) {
  a = std::fmod(a, kTwoPi);
  return a < 0.0 ? a + kTwoPi : a;
}

}  // namespace

const char* to_string(ToothEventKind kind) {
  return kind == ToothEventKind::kCentroid ? "pulse_centroid" : "valley";
}

bool pauses_between_flutes(const model::ModelConfig& config) {
  const std::vector<double> psi = model::flute_pitch_angles_rad(config.tool);
  if (psi.empty()) {
    return false;
  }
  double pitch = kTwoPi - psi.back();  // the last flute's to the first's
  for (std::size_t j = 1; j < psi.size(); ++j) {
    pitch = std::min(pitch, psi[j] - psi[j - 1]);
  }
  const model::EngagedArc arc = model::engaged_arc(config);
  const double engaged = arc.to_rad - arc.from_rad + model::helix_lag_total_rad(config);
  return pitch - engaged >= kQuietPitch * pitch;
}

ToothEventTemplate find_tooth_event_template(std::span<const double> avg, int flutes,
                                             bool pauses_expected) {
  ToothEventTemplate t;
  t.flutes = flutes;
  const int bins = static_cast<int>(avg.size());
  if (flutes < 1 || flutes > kMaxFlutes || bins < 8 * flutes) {
    return t;
  }
  auto at = [&](long k) { return avg[static_cast<std::size_t>(((k % bins) + bins) % bins)]; };
  // One valley per tooth period, and all at the same place in their periods: the average
  // folded onto one pitch (the mean of its N pitch-long segments) has its lowest point where
  // the flutes' valleys are on average, and each flute's valley is the lowest bin within a
  // quarter pitch of there — of a W's two arms about as deep, the one there (nearest_basin()).
  // (The deepest minima alone can mix two kinds of valley — after a
  // pulse's ringing rebound and before the next pulse, equally deep — from flute to flute.)
  const double pitch_bins = static_cast<double>(bins) / flutes;
  const auto pitch_whole = static_cast<int>(std::ceil(pitch_bins));
  double lowest_fold = 0.0;
  int fold_at = 0;
  for (int b = 0; b < pitch_whole; ++b) {
    double sum = 0.0;
    for (int m = 0; m < flutes; ++m) {
      sum += at(b + static_cast<long>(std::lround(m * pitch_bins)));
    }
    if (b == 0 || sum < lowest_fold) {
      lowest_fold = sum;
      fold_at = b;
    }
  }
  std::vector<int> picked;
  for (int m = 0; m < flutes; ++m) {
    const double centre = fold_at + m * pitch_bins;
    const auto from = static_cast<long>(std::ceil(centre - 0.25 * pitch_bins));
    const auto to = static_cast<long>(std::floor(centre + 0.25 * pitch_bins));
    long best = from;
    for (long k = from; k <= to; ++k) {
      if (at(k) < at(best)) {
        best = k;
      }
    }
    // Of a W's two arms about as deep, the one where the flutes' valleys are on average.
    best = static_cast<long>(nearest_basin(at, std::lround(centre), best, from, to,
                                           std::max(1L, std::lround(pitch_bins / 7.0)),
                                           kTemplateBasinDepth));
    picked.push_back(static_cast<int>(((best % bins) + bins) % bins));
  }
  std::sort(picked.begin(), picked.end());
  if (std::adjacent_find(picked.begin(), picked.end()) != picked.end()) {
    return t;  // two windows found the same bin: no distinct tooth events
  }

  // A pause between every pair of pulses makes an interrupted cut.
  const double lo = *std::min_element(avg.begin(), avg.end());
  const double hi = *std::max_element(avg.begin(), avg.end());
  const double quiet = lo + (pauses_expected ? kPauseQuietFraction : kQuietFraction) * (hi - lo);
  const int min_gap = std::max(2, static_cast<int>(kQuietPitch * bins / flutes));
  std::array<double, kMaxFlutes> gap_centre{};
  bool interrupted = hi > lo;
  for (int i = 0; i < flutes && interrupted; ++i) {
    const int v = picked[static_cast<std::size_t>(i)];
    int left = 0, right = 0;
    while (left < bins / 2 && at(v - left - 1) <= quiet) {
      ++left;
    }
    while (right < bins / 2 && at(v + right + 1) <= quiet) {
      ++right;
    }
    interrupted = at(v) <= quiet && left + right + 1 >= min_gap;
    // The middle of the quiet stretch, but never more than a quarter pitch from where the
    // flutes' valleys are on average: a flute that does not cut leaves one long stretch, and
    // both boundaries in it must stay a pitch apart. That place is the one nearest v: `picked`
    // is sorted, and a window's lowest bin can lie before 0 (v wrapped to the end), which moves
    // it past the others (two equal minima of a W: the one nearer the flutes' mean valley).
    const double nominal = fold_at + std::round((v - fold_at) / pitch_bins) * pitch_bins;
    const double centre = v + 0.5 * (right - left);
    const double off = std::remainder(centre - nominal, static_cast<double>(bins));
    gap_centre[static_cast<std::size_t>(i)] =
        nominal + std::clamp(off, -0.25 * pitch_bins, 0.25 * pitch_bins);
  }

  const double bin_rad = kTwoPi / bins;
  std::array<double, kMaxFlutes> boundary{};
  std::array<double, kMaxFlutes> event{};
  std::array<double, kMaxFlutes> peak{};
  std::array<double, kMaxFlutes> weight{};
  for (int i = 0; i < flutes; ++i) {
    const auto ui = static_cast<std::size_t>(i);
    const int from = picked[ui];
    int to = picked[static_cast<std::size_t>((i + 1) % flutes)];
    if (to <= from) {
      to += bins;
    }
    double p = 0.0;
    for (int k = from; k <= to; ++k) {
      p = std::max(p, at(k));
    }
    peak[ui] = p;
    if (!interrupted) {
      const Extremum e = refine_extremum(at, from, 1, true);
      boundary[ui] = event[ui] = wrap_2pi(e.position * bin_rad);
      continue;
    }
    // The pulse's centroid of squared force above the quiet level, between the gaps' centres.
    const double g0 = gap_centre[ui];
    double g1 = gap_centre[static_cast<std::size_t>((i + 1) % flutes)];
    while (g1 <= g0) {
      g1 += bins;
    }
    double sum_w = 0.0, sum_wk = 0.0;
    for (auto k = static_cast<long>(std::ceil(g0)); k <= static_cast<long>(std::floor(g1)); ++k) {
      const double w = std::max(0.0, at(k) * at(k) - lo * lo);
      sum_w += w;
      sum_wk += w * static_cast<double>(k);
    }
    weight[ui] = sum_w;
    boundary[ui] = wrap_2pi(g0 * bin_rad);
    event[ui] = wrap_2pi((sum_w > 0.0 ? sum_wk / sum_w : 0.5 * (g0 + g1)) * bin_rad);
  }
  // A flute whose window holds (almost) no pulse does not cut: its event is the middle of its
  // window, where the tracker will find it quiet.
  const double heaviest = *std::max_element(weight.begin(), weight.begin() + flutes);
  for (int i = 0; i < flutes && interrupted; ++i) {
    const auto ui = static_cast<std::size_t>(i);
    if (weight[ui] < 0.05 * heaviest) {
      double g1 = gap_centre[(ui + 1) % static_cast<std::size_t>(flutes)];
      while (g1 <= gap_centre[ui]) {
        g1 += bins;
      }
      event[ui] = wrap_2pi(0.5 * (gap_centre[ui] + g1) * bin_rad);
    }
  }
  const auto ce1 =
      static_cast<int>(std::max_element(peak.begin(), peak.begin() + flutes) - peak.begin());
  // Unwrapped in the order of rotation, CE1 first; each boundary at or before its event.
  t.kind = interrupted ? ToothEventKind::kCentroid : ToothEventKind::kValley;
  for (int j = 0; j < flutes; ++j) {
    const auto from = static_cast<std::size_t>((ce1 + j) % flutes);
    double e = event[from];
    while (j > 0 && e < t.event_rad[0]) {
      e += kTwoPi;
    }
    double b = boundary[from];
    while (b > e) {
      b -= kTwoPi;
    }
    while (b + kTwoPi <= e) {
      b += kTwoPi;
    }
    t.event_rad[static_cast<std::size_t>(j)] = e;
    t.boundary_rad[static_cast<std::size_t>(j)] = b;
  }
  t.valid = true;
  return t;
}

double ToothEventTracker::lead(int flute) const {
  return lead_fraction_[static_cast<std::size_t>(flute)] * period_;
}

EventSearch ToothEventTracker::search(const SampleRing& ring, int flute, double predicted) const {
  const auto detect = [&](std::int64_t n) { return ring.at(detect_, n); };
  const std::int64_t oldest = std::max(ring.oldest(), earliest_);
  const int flutes = config_.flutes;
  if (template_.kind == ToothEventKind::kCentroid) {
    const int next = (flute + 1) % flutes;
    const double from = predicted - lead(flute);
    const double to = predicted + spacing_[static_cast<std::size_t>(flute)] * period_ - lead(next);
    EventSearch e = find_centroid(detect, oldest, ring.newest(), from, to);
    if (e.status != EventSearch::Status::kWait && e.status != EventSearch::Status::kGone &&
        !pulse_around(ring, 0.5 * (from + to), 0.5 * (to - from))) {
      e.status = EventSearch::Status::kQuiet;  // the flute did not cut
    }
    if (e.status != EventSearch::Status::kFound) {
      e.position = predicted;
    }
    return e;
  }
  const double pitch = period_ / flutes;
  const auto half = static_cast<std::int64_t>(std::ceil(config_.search_fraction_of_pitch * pitch));
  const int fit = config_.fit_half_width > 0
                      ? config_.fit_half_width
                      : std::max(2, static_cast<int>(std::lround(pitch / 7.0)));
  EventSearch e = find_valley(detect, oldest, ring.newest(), predicted, half, fit);
  if (e.status == EventSearch::Status::kFound && !pulse_around(ring, e.position, 0.5 * pitch)) {
    e.status = EventSearch::Status::kNotFound;  // a minimum of the noise between cuts
  }
  return e;
}

bool ToothEventTracker::pulse_around(const SampleRing& ring, double position, double reach) const {
  const auto from = std::max(ring.oldest(), static_cast<std::int64_t>(position - reach));
  const auto to = std::min(ring.newest(), static_cast<std::int64_t>(position + reach));
  for (std::int64_t n = from; n <= to; ++n) {
    if (ring.at(detect_, n) >= min_pulse_) {
      return true;
    }
  }
  return false;
}

std::string_view to_string(ToothEventLoss loss) {
  switch (loss) {
    case ToothEventLoss::kNone:
      return "the tooth events run";
    case ToothEventLoss::kBarren:
      return "the tooth events were lost: revolutions in a row without any valley found";
    case ToothEventLoss::kCoasted:
      return "the tooth events were lost: revolutions in a row without their closing CE1 event";
    case ToothEventLoss::kPeriod:
      return "the tooth events were lost: their revolution period left the tool's";
  }
  return "the tooth events were lost";
}

bool ToothEventTracker::start(const ToothEventTemplate& tmpl, const signal::PhaseModel& phase,
                              double anchor_sample, std::int64_t earliest_sample,
                              const SampleRing& ring, int detect_channel) {
  active_ = false;
  loss_ = ToothEventLoss::kNone;
  if (!tmpl.valid || tmpl.flutes != config_.flutes || !phase.valid || ring.empty()) {
    return false;
  }
  template_ = tmpl;
  detect_ = detect_channel;
  earliest_ = earliest_sample;
  const int flutes = config_.flutes;
  for (int j = 0; j < flutes; ++j) {
    const auto uj = static_cast<std::size_t>(j);
    const double next = j + 1 < flutes ? tmpl.event_rad[uj + 1] : tmpl.event_rad[0] + kTwoPi;
    spacing_[uj] = (next - tmpl.event_rad[uj]) / kTwoPi;
    lead_fraction_[uj] = (tmpl.event_rad[uj] - tmpl.boundary_rad[uj]) / kTwoPi;
  }
  const double f_hz = phase.spindle_hz_at(anchor_sample);
  period_ = phase.sample_rate_hz / f_hz;
  period_rate_ = 0.0;
  const double start_period = period_;

  // The CE1 event nearest the anchor, and the force there: an event counts only where the
  // force around it reaches a fifth of that (noise between cuts has minima too).
  const double e0 = tmpl.event_rad[0];
  const auto m =
      static_cast<std::int64_t>(std::llround((phase.angle_at(anchor_sample) - e0) / kTwoPi));
  const double anchor_predicted = phase.sample_at(e0 + kTwoPi * static_cast<double>(m));
  min_pulse_ = 0.0;
  double reference = 0.0;
  for (auto n = static_cast<std::int64_t>(anchor_predicted - 0.5 * period_);
       n <= static_cast<std::int64_t>(anchor_predicted + 0.5 * period_); ++n) {
    if (n >= ring.oldest() && n <= ring.newest()) {
      reference = std::max(reference, ring.at(detect_, n));
    }
  }
  min_pulse_ = kMinPulse * kMinPulse * reference;
  const EventSearch anchor = search(ring, 0, anchor_predicted);
  if (anchor.status != EventSearch::Status::kFound) {
    return false;
  }

  // Walk back event by event to where the events stop (the cut's start, the ring's end, or the
  // last revolution measured before), keeping the earliest CE1 events found.
  std::array<double, kStartFit> ce1_sample{};
  std::array<std::int64_t, kStartFit> ce1_turn{};
  int ce1_count = 0;
  auto keep = [&](std::int64_t turn, double sample) {  // the earliest kStartFit are kept
    ce1_sample[static_cast<std::size_t>(ce1_count % kStartFit)] = sample;
    ce1_turn[static_cast<std::size_t>(ce1_count % kStartFit)] = turn;
    ++ce1_count;
  };
  double position = anchor.position;
  std::int64_t turn = m;
  keep(turn, position);
  double last_ce1 = position;
  bool last_ce1_found = true;
  int flute = 0;
  int misses = 0;
  while (true) {
    const int previous = (flute - 1 + flutes) % flutes;
    const double predicted = position - spacing_[static_cast<std::size_t>(previous)] * period_;
    if (predicted - lead(previous) - 2.0 * period_ / flutes < static_cast<double>(earliest_)) {
      break;
    }
    const EventSearch e = search(ring, previous, predicted);
    if (e.status == EventSearch::Status::kGone || e.status == EventSearch::Status::kWait) {
      break;
    }
    const bool found = e.status == EventSearch::Status::kFound;
    position = e.position;
    misses = found ? 0 : misses + 1;
    if (misses >= flutes) {
      break;  // a revolution without one event: the cut starts here
    }
    flute = previous;
    if (flute == 0) {
      --turn;
      if (found && last_ce1_found) {
        period_ = last_ce1 - position;  // the local revolution period, for the next step back
      }
      last_ce1 = position;
      last_ce1_found = found;
      if (found) {
        keep(turn, position);
      }
    }
    if (std::fabs(period_ / start_period - 1.0) > 0.5) {
      break;  // not the same cut any more
    }
  }

  // The filter starts from the CE1 events found on the way back.
  const int used = std::min(ce1_count, kStartFit);
  std::int64_t start_turn = ce1_turn[0];
  double start = ce1_sample[0];  // the earliest CE1 event: the first revolution's start
  for (int i = 0; i < used; ++i) {
    if (ce1_turn[static_cast<std::size_t>(i)] < start_turn) {
      start_turn = ce1_turn[static_cast<std::size_t>(i)];
      start = ce1_sample[static_cast<std::size_t>(i)];
    }
  }
  const StartState s0 = fit_start(std::span(ce1_turn).first(static_cast<std::size_t>(used)),
                                  std::span(ce1_sample).first(static_cast<std::size_t>(used)),
                                  start_turn, start_period);
  anchor_ = s0.anchor;
  period_ = s0.period;
  period_rate_ = s0.rate;
  // The filter's typical miss starts at the events' scatter on the way back (a short record's
  // few revolutions would not settle it from the first miss alone).
  typical_miss_ = std::max(s0.spread, kMinMiss_samples);
  last_beyond_ = 0.0;
  fast_revolutions_ = 0;
  turn_ = start_turn;
  next_flute_ = 1 % flutes;
  events_in_revolution_ = 1;
  revolution_.event_sample[0] = start;
  revolution_.boundary_sample[0] = start - lead(0);
  revolution_.found[0] = true;
  revolution_.quiet[0] = false;
  barren_revolutions_ = 0;
  coasted_revolutions_ = 0;
  gone_in_revolution_ = 0;
  sequence_ = 0;
  needed_ = static_cast<std::int64_t>(start);
  active_ = true;
  return true;
}

ToothEventTracker::Step ToothEventTracker::step(const SampleRing& ring) {
  const int flutes = config_.flutes;
  const int flute = next_flute_;
  // From the filtered CE1 event of this revolution and the flutes' spacing.
  double fraction = 0.0;
  for (int j = 0; j < events_in_revolution_; ++j) {
    fraction += spacing_[static_cast<std::size_t>(j % flutes)];
  }
  const double predicted = anchor_ + fraction * (period_ + 0.5 * fraction * period_rate_);
  const EventSearch e = search(ring, flute, predicted);
  if (e.status == EventSearch::Status::kWait) {
    needed_ = e.needed;
    return Step::kWait;
  }
  const bool found = e.status == EventSearch::Status::kFound;
  const auto k = static_cast<std::size_t>(events_in_revolution_);
  if (k == 1 && sequence_ > 0) {  // this revolution opens with the last one's closing event
    const auto n = static_cast<std::size_t>(flutes);
    revolution_.event_sample[0] = revolution_.event_sample[n];
    revolution_.boundary_sample[0] = revolution_.boundary_sample[n];
    revolution_.found[0] = revolution_.found[n];
    revolution_.quiet[0] = revolution_.quiet[n];
  }
  revolution_.event_sample[k] = e.position;
  revolution_.boundary_sample[k] = e.position - lead(flute);
  revolution_.found[k] = found;
  revolution_.quiet[k] = e.status == EventSearch::Status::kQuiet;
  gone_in_revolution_ += e.status == EventSearch::Status::kGone ? 1 : 0;
  next_flute_ = (flute + 1) % flutes;
  ++events_in_revolution_;
  if (events_in_revolution_ <= flutes) {
    return Step::kEvent;
  }
  close_revolution();
  return Step::kRevolution;
}

void ToothEventTracker::close_revolution() {
  const int flutes = config_.flutes;
  const auto n = static_cast<std::size_t>(flutes);
  RevolutionEvents& r = revolution_;
  r.flutes = flutes;
  r.turn = turn_;
  r.sequence = ++sequence_;
  bool all = true, any = false;
  for (std::size_t k = 0; k <= n; ++k) {
    all = all && r.found[k];
    any = any || r.found[k];
  }
  r.valid = all;
  r.bounded = r.found[0] && r.found[n];
  // Events without samples (a gap) say nothing about the cut: such a revolution is skipped.
  r.no_data = gone_in_revolution_ >= flutes;
  gone_in_revolution_ = 0;

  // g-h-k filter on the CE1 events (a revolution whose closing CE1 was not found coasts).
  const double x = anchor_ + period_ + 0.5 * period_rate_;
  const double v = period_ + period_rate_;
  const double residual = r.found[n] ? r.event_sample[n] - x : 0.0;
  if (r.found[n]) {
    const double miss = std::fabs(residual);
    const double limit = kManoeuvre * typical_miss_;
    // Beyond the typical miss twice in a row, to the same side: a manoeuvre persists, a
    // noisy event (real cuts' valleys have heavy tails) does not.
    const double beyond = miss > limit ? residual : 0.0;
    if (beyond * last_beyond_ > 0.0) {
      fast_revolutions_ = kFastRevolutions;
    }
    last_beyond_ = beyond;
    typical_miss_ = std::max(kMinMiss_samples, kMissMemory * typical_miss_ +
                                                   (1.0 - kMissMemory) * std::min(miss, limit));
  }
  const Gains& gain = fast_revolutions_ > 0 ? kFastGains : kGains;
  fast_revolutions_ = std::max(0, fast_revolutions_ - 1);
  anchor_ = x + gain.g * residual;
  period_ = v + gain.h * residual;
  // A revolution that coasts (its closing CE1 not found) keeps the period but not its change:
  // carried on from a ramp that has ended, the change would run the events off the cut, a few
  // percent a revolution, faster than a tracker window could catch it.
  period_rate_ = r.found[n] ? period_rate_ + 2.0 * gain.k * residual : 0.0;
  r.period_samples = period_ - 0.5 * period_rate_;  // over the revolution just closed
  // The flutes' spacing follows every event found with its revolution's first: as positions
  // along the revolution (C_j, C_0 = 0, C_N = 1), so that a flute found only now and then, or
  // never (it does not cut), leaves its neighbours' spacing free to follow.
  if (r.found[0]) {
    std::array<double, kMaxFlutes + 1> c{};
    for (std::size_t j = 0; j < n; ++j) {
      c[j + 1] = c[j] + spacing_[j];
    }
    for (std::size_t j = 1; j < n; ++j) {
      if (r.found[j]) {
        const double measured = (r.event_sample[j] - r.event_sample[0]) / r.period_samples;
        c[j] += config_.spacing_gain * (measured - c[j]);
      }
    }
    for (std::size_t j = 0; j < n; ++j) {
      spacing_[j] = std::max(0.05 / flutes, c[j + 1] - c[j]);
    }
    double sum = 0.0;
    for (std::size_t j = 0; j < n; ++j) {
      sum += spacing_[j];
    }
    for (std::size_t j = 0; j < n; ++j) {
      spacing_[j] /= sum;
    }
  }
  last_closed_ = static_cast<std::int64_t>(std::floor(r.event_sample[n]));
  barren_revolutions_ = any || r.no_data ? 0 : barren_revolutions_ + 1;
  coasted_revolutions_ = r.found[n] || r.no_data ? 0 : coasted_revolutions_ + 1;
  const ToothEventLoss loss = barren_revolutions_ >= config_.lost_after   ? ToothEventLoss::kBarren
                              : coasted_revolutions_ >= kCoastRevolutions ? ToothEventLoss::kCoasted
                              : !(period_ > 4.0 * flutes)                 ? ToothEventLoss::kPeriod
                                                                          : ToothEventLoss::kNone;
  if (loss != ToothEventLoss::kNone) {
    active_ = false;
    loss_ = loss;
  }
  ++turn_;
  events_in_revolution_ = 1;
}

}  // namespace millwatch::monitor
