#pragma once
// Tooth events: the instants that cut the force into revolutions and flute periods.
//
// Continuous cuts (a slot, wide side milling): the event is the valley between one flute's cut
// and the next ([001] eq 36, [003] Table 4), sought on the squared in-plane force, where a
// valley is a smooth parabola, and located to a fraction of a sample by a local cubic fit.
// Interrupted cuts (the force returns to zero between teeth, e.g. side milling at small radial
// immersion): a valley there is a flat stretch of noise, not an event. The event is then the
// centroid of the tooth's pulse of squared force above the quiet level, and each flute's force
// window starts in the middle of the quiet stretch before its pulse. Which kind a cut has is
// decided once per lock from the revolution-synchronous average (ToothEventTemplate).
//
// ToothEventTracker follows the events revolution after revolution: each event is sought
// around where the previous one and the current revolution period put it (an α-β filter on
// the revolution period follows ramps), never more than a fraction of a pitch away. At a lock
// it walks back through the sample ring from the lock's window to the start of the cut, so that
// the revolutions before the lock are measured too, and then measures forward.
//
// Flute 0 is CE1 (the flute whose period holds the largest force: [001]/[003]'s main edge).
// Without a once-per-revolution reference this labelling is a convention.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <string_view>
#include <utility>

#include "core/model/model_config.hpp"
#include "core/monitor/extremum.hpp"
#include "core/monitor/revolution_features.hpp"
#include "core/monitor/sample_ring.hpp"
#include "core/signal/phase_model.hpp"

namespace millwatch::monitor {

const char* to_string(ToothEventKind kind);

struct ToothEventTemplate {
  int flutes = 0;
  ToothEventKind kind = ToothEventKind::kValley;
  /// Tracker angle of each flute's event, CE1 first, in the order of rotation, unwrapped:
  /// event_rad[0] ∈ [0, 2π) ≤ event_rad[1] ≤ ... < event_rad[0] + 2π.
  std::array<double, kMaxFlutes> event_rad{};
  /// Angle at which each flute's force window starts (≤ event_rad[j]; equal for valleys).
  std::array<double, kMaxFlutes> boundary_rad{};
  bool valid = false;
};

/// Finds the events on the revolution-synchronous average of the in-plane resultant √(Fx²+Fy²)
/// (uniform angle grid from the tracker's zero). A cut is "interrupted" when every gap between
/// pulses stays within 10 % of the force's span above its lowest level (the filter's ringing) for
/// at least 20 % of a pitch; within 25 % when `pauses_expected` (the commanded cut leaves a pause
/// between the flutes, pauses_between_flutes(): a dynamometer's ringing there makes the valley
/// between two pulses a W, whose two minima trade places from flute to flute and revolution to
/// revolution, while the pulses' centroids stay put).
ToothEventTemplate find_tooth_event_template(std::span<const double> resultant_average, int flutes,
                                             bool pauses_expected = false);
/// Whether the commanded cut leaves a pause between the flutes' cuts: the flutes' pitch exceeds
/// the engaged arc (model::engaged_arc, with the helix lag) by 20 % of a pitch or more.
bool pauses_between_flutes(const model::ModelConfig& config);

/// A stretch of the in-plane resultant within this fraction of its span above its lowest level
/// is quiet (a filter's ringing stays below it)...
inline constexpr double kQuietFraction = 0.1;
/// ...and a quiet stretch this long (fraction of a pitch) is a pause between the flutes' cuts.
inline constexpr double kQuietPitch = 0.2;

/// Outcome of one event search.
struct EventSearch {
  /// kQuiet: no pulse at all where the flute's should be (it did not cut).
  enum class Status { kFound, kNotFound, kGone, kWait, kQuiet };
  Status status = Status::kNotFound;
  double position = 0.0;    ///< fractional sample (the prediction when not found)
  std::int64_t needed = 0;  ///< kWait: the newest sample the search needs
};

/// The first sample of [from, to] at `detect`'s lowest value: what one scan from `from` keeping
/// each value below the lowest so far (`v < lowest`: a NaN is never taken, and one at `from`
/// stays) finds. The even and the odd samples after `from` are scanned as two interleaved
/// chains of comparisons, half as long as one (each waits on its last minimum), and the lower
/// of their minima taken, the earlier sample on a tie: the same sample.
template <typename Signal>
std::int64_t first_minimum(const Signal& detect, std::int64_t from, std::int64_t to) {
  std::int64_t best_even = from;  // from, from + 2, ...
  double low_even = detect(from);
  std::int64_t best_odd = to + 1;  // from + 1, from + 3, ...: none yet
  double low_odd = std::numeric_limits<double>::infinity();
  std::int64_t n = from + 1;
  for (; n + 1 <= to; n += 2) {
    const double odd = detect(n);
    const double even = detect(n + 1);
    if (odd < low_odd) {
      low_odd = odd;
      best_odd = n;
    }
    if (even < low_even) {
      low_even = even;
      best_even = n + 1;
    }
  }
  if (n <= to) {
    const double odd = detect(n);
    if (odd < low_odd) {
      low_odd = odd;
      best_odd = n;
    }
  }
  // +∞ is never taken by the odd chain, as the single scan never takes it after a finite value
  // (nor after +∞, which it equals); a NaN at `from` keeps the even chain, both comparisons false.
  return low_odd < low_even || (low_odd == low_even && best_odd < best_even) ? best_odd : best_even;
}

/// A ridge this high (fraction of the search window's span, its highest sample over its lowest)
/// parts two valleys: the arms of a W-shaped valley (a dynamometer's ringing, ~15° apart on a
/// six-flute tool) stand apart by several percent; the ripple of noise along a valley's floor
/// by far less.
inline constexpr double kBasinRidge = 0.01;
/// ...and a valley that much shallower than the window's lowest is a shoulder, not an arm.
inline constexpr double kBasinDepth = 0.2;

/// The valley of [from, to] the prediction `center` lies in: the bottom n of the basin reached
/// by walking downhill from `center`, where it lies inside the window, is the lowest sample
/// within ± width of itself (a valley the fit sees as one), a ridge higher than kBasinRidge of
/// the window's span parts it from `lowest` (the window's lowest sample) and it is within
/// `depth` of the span as deep; otherwise `lowest`. Where a W's two arms are about as deep,
/// the lowest sample flips between them from one revolution to the next with the noise (a
/// flute's period ±15°); the arm the tracked event follows stays followed. Reads `detect` within
/// [from − width, to + width].
template <typename Signal>
std::int64_t nearest_basin(const Signal& detect, std::int64_t center, std::int64_t lowest,
                           std::int64_t from, std::int64_t to, std::int64_t width,
                           double depth = kBasinDepth) {
  if (center <= from || center >= to || center == lowest) {
    return lowest;
  }
  std::int64_t n = center;
  const std::int64_t step = detect(center - 1) < detect(center) ? -1 : 1;
  while (n + step >= from && n + step <= to && detect(n + step) < detect(n)) {
    n += step;
  }
  if (n == lowest || n == from || n == to) {
    return lowest;
  }
  // A valley the fit sees as one: the lowest within ± width (the ripple of sparse samples on
  // a steep flank is no second valley).
  for (std::int64_t k = n - width; k <= n + width; ++k) {
    if (detect(k) < detect(n)) {
      return lowest;
    }
  }
  double ridge = detect(n);
  for (std::int64_t k = std::min(n, lowest); k <= std::max(n, lowest); ++k) {
    ridge = std::max(ridge, detect(k));
  }
  double top = ridge;
  for (std::int64_t k = from; k <= to; ++k) {
    top = std::max(top, detect(k));
  }
  const double span = top - detect(lowest);
  return ridge - detect(n) > kBasinRidge * span && detect(n) - detect(lowest) < depth * span
             ? n
             : lowest;
}

/// A valley of `detect` (callable on absolute sample n ∈ [oldest, newest]) within ± half
/// samples of `predicted`, refined by a cubic over ± fit_half samples: the valley the
/// prediction lies in (nearest_basin(): of two parted by a ridge, not the deeper one). Found
/// only when its lowest sample is interior to the search window and the fit is curved upwards.
/// Reads `detect` within [oldest, newest] only.
template <typename Signal>
EventSearch find_valley(const Signal& detect, std::int64_t oldest, std::int64_t newest,
                        double predicted, std::int64_t half, int fit_half) {
  EventSearch out;
  const std::int64_t center = nearest_sample(predicted);
  out.position = predicted;
  // Room for the fit to re-centre (and for the fits a sample either side, below).
  const std::int64_t room = std::max<std::int64_t>(3 * fit_half, fit_half + 1);
  if (center + half + room > newest) {
    out.status = EventSearch::Status::kWait;
    out.needed = center + half + room;
    return out;
  }
  if (center - half - room < oldest) {
    out.status = EventSearch::Status::kGone;
    return out;
  }
  const std::int64_t lowest = first_minimum(detect, center - half, center + half);
  // A lowest sample on the window's edge says the valley lies beyond it: not found, whatever
  // ripple lies nearer the prediction. Inside, the valley the prediction lies in (inside too).
  const bool interior = lowest > center - half && lowest < center + half;
  const std::int64_t best =
      interior ? nearest_basin(detect, center, lowest, center - half, center + half, fit_half)
               : lowest;
  // Fit around the prediction when the data agree with it: a window chosen by the noisy
  // minimum itself leans towards the flatter side of an asymmetric valley (a bias of noise).
  // Then re-centre on the vertex until the window sits on it, so that the result does not
  // depend on the prediction.
  std::int64_t fit_center = std::llabs(best - center) <= fit_half ? center : best;
  // The fits on this window and on the windows a sample either side, computed together: none
  // waits on another, so their chains of divisions and roots overlap, and the re-centring and
  // the blend below mostly take one of them (the same fits as computed when asked). Inside the
  // bounds checked above: the fit's window moves by a sample.
  const std::int64_t near = fit_center;
  const std::array<Extremum, 3> nearby = {refine_extremum(detect, near - 1, fit_half, true),
                                          refine_extremum(detect, near, fit_half, true),
                                          refine_extremum(detect, near + 1, fit_half, true)};
  const auto fit_at = [&](std::int64_t c) {
    return std::llabs(c - near) <= 1 ? nearby[static_cast<std::size_t>(c - near + 1)]
                                     : refine_extremum(detect, c, fit_half, true);
  };
  Extremum e = nearby[1];
  const bool retry = !e.valid && std::llabs(best - center) + 1 >= fit_half;
  if (retry) {
    // The vertex lies just beyond the window around the prediction (a sharp valley seen by
    // few samples): start at the minimum, found at that window's edge. Not when the minimum
    // sits inside it: then the valley has no clean vertex (worn edges, real data) and a
    // minimum of the noise is no event.
    fit_center = best;
    e = fit_at(fit_center);
  }
  for (int i = 0; i < 3 && e.valid && nearest_sample(e.position) != fit_center; ++i) {
    fit_center = nearest_sample(e.position);
    // Each step moves the window by up to fit_half: the checks above leave room for two such
    // steps and the blend's window a sample over (below). A vertex that walks further is no
    // valley of this search, and its fit would read samples the caller does not have.
    if (fit_center - fit_half - 1 < oldest || fit_center + fit_half + 1 > newest) {
      e.valid = false;
      break;
    }
    e = fit_at(fit_center);
  }
  if (retry && e.valid && std::fabs(e.position - static_cast<double>(best)) > fit_half) {
    e.valid = false;  // the re-centred fit wandered off to another valley (a ringing rebound)
  }
  if (interior && e.valid) {
    // The fit's window jumps by a sample as the vertex crosses a half sample, and with it the
    // fit's small bias on an asymmetric valley: blend with the fit on the neighbouring window
    // so that the located valley moves continuously with the signal.
    const double offset = e.position - static_cast<double>(fit_center);
    const std::int64_t other = fit_center + (offset >= 0.0 ? 1 : -1);
    const Extremum f = fit_at(other);
    const double w = std::min(0.5, std::fabs(offset));
    out.status = EventSearch::Status::kFound;
    out.position = f.valid ? (1.0 - w) * e.position + w * f.position : e.position;
  } else {
    out.status = EventSearch::Status::kNotFound;
  }
  return out;
}

/// The centroid of a pulse of `detect` above its quiet level within [from, to]: Σ n·w / Σ w with
/// w = detect − (smallest sample in the window). Found when the window's ends are quiet (below
/// 15 % of the pulse's height), so that the whole pulse is inside.
template <typename Signal>
EventSearch find_centroid(const Signal& detect, std::int64_t oldest, std::int64_t newest,
                          double from, double to) {
  EventSearch out;
  out.position = 0.5 * (from + to);
  const auto lo = static_cast<std::int64_t>(std::ceil(from));
  const auto hi = static_cast<std::int64_t>(std::floor(to));
  if (hi > newest) {
    out.status = EventSearch::Status::kWait;
    out.needed = hi;
    return out;
  }
  if (lo < oldest || hi - lo < 4) {
    out.status = lo < oldest ? EventSearch::Status::kGone : EventSearch::Status::kNotFound;
    return out;
  }
  double floor = detect(lo), top = floor;
  for (std::int64_t n = lo; n <= hi; ++n) {
    const double v = detect(n);
    floor = std::min(floor, v);
    top = std::max(top, v);
  }
  const double height = top - floor;
  double sum_w = 0.0, sum_wn = 0.0;
  for (std::int64_t n = lo; n <= hi; ++n) {
    const double w = detect(n) - floor;
    sum_w += w;
    sum_wn += w * static_cast<double>(n - lo);
  }
  const bool quiet_ends = detect(lo) - floor < 0.15 * height && detect(hi) - floor < 0.15 * height;
  if (height > 0.0 && sum_w > 0.0 && quiet_ends) {
    out.status = EventSearch::Status::kFound;
    out.position = static_cast<double>(lo) + sum_wn / sum_w;
  } else {
    out.status = EventSearch::Status::kNotFound;
  }
  return out;
}

/// The middle of a pause in `detect` (callable on absolute sample n ∈ [from, to]): the quiet
/// stretch — samples at or below `quiet` — that holds the lowest sample within ± half of
/// `predicted`, its ends placed where `detect` crosses `quiet` (linearly between the samples, so
/// that the middle moves continuously with the signal). Found when the stretch is at least
/// `min_run` samples long, ends inside [from, to] and has its middle within ± half of
/// `predicted` (a flute that does not cut leaves a stretch two pitches long, whose middle is no
/// event on either side of it: not found, as a valley search finds none there).
/// The lockstep model's valley where its force pauses between the flutes while the measured
/// valleys do not (noise, a dynamometer's ringing): on a flat stretch a valley fit lands on an
/// edge or on a ripple of the filter's ringing, which put the model's α of an equal-pitch tool
/// without runout 8° off its pitch on a real cut (PHM 2010 cut 158).
template <typename Signal>
EventSearch find_quiet_middle(const Signal& detect, std::int64_t from, std::int64_t to,
                              double predicted, std::int64_t half, double quiet, double min_run) {
  EventSearch out;
  out.position = predicted;
  const std::int64_t center = nearest_sample(predicted);
  const std::int64_t lo = std::max(from, center - half);
  const std::int64_t hi = std::min(to, center + half);
  if (hi <= lo) {
    return out;
  }
  const std::int64_t lowest = first_minimum(detect, lo, hi);
  if (!(detect(lowest) <= quiet)) {
    return out;
  }
  std::int64_t left = lowest, right = lowest;
  while (left > from && detect(left - 1) <= quiet) {
    --left;
  }
  while (right < to && detect(right + 1) <= quiet) {
    ++right;
  }
  if (left == from || right == to) {
    return out;  // the stretch goes on beyond the samples: its middle is not known
  }
  const double before = detect(left - 1), after = detect(right + 1);
  const double start = static_cast<double>(left - 1) + (before - quiet) / (before - detect(left));
  const double end = static_cast<double>(right) + (quiet - detect(right)) / (after - detect(right));
  const double middle = 0.5 * (start + end);
  if (!(end - start >= min_run) || !(std::fabs(middle - predicted) <= static_cast<double>(half))) {
    return out;  // (a NaN beside the stretch fails here too)
  }
  out.status = EventSearch::Status::kFound;
  out.position = middle;
  return out;
}

/// Revolutions in a row with samples but without their closing CE1 event after which the
/// tooth events are lost (ToothEventTracker::advance): the revolution's bounds were the g-h-k
/// filter's extrapolation all along.
inline constexpr int kCoastRevolutions = 6;

/// Why the tooth events stopped on their own (ToothEventTracker::take_loss()).
enum class ToothEventLoss {
  kNone,
  kBarren,   ///< lost_after revolutions in a row without any event found
  kCoasted,  ///< kCoastRevolutions in a row without their closing CE1 event
  kPeriod,   ///< the filter's period left what a revolution of this tool can be
};

/// What a user reads for a loss (a literal: it outlives any sink).
std::string_view to_string(ToothEventLoss loss);

struct ToothEventConfig {
  int flutes = 2;
  double sample_rate_hz = 50000.0;
  double search_fraction_of_pitch = 0.3;  ///< valley search half-window
  int fit_half_width = 0;                 ///< valley fit half-width in samples; 0 = automatic
  double spacing_gain = 0.05;             ///< how fast measured events move the flutes' spacing
  int lost_after = 3;  ///< revolutions without one event found: the cut has stopped
};

/// One revolution's events, CE1 to the next CE1.
struct RevolutionEvents {
  std::int64_t sequence = 0;  ///< revolutions since start()
  std::int64_t turn = 0;      ///< the tracker's turn: event j sits at event_rad[j] + 2π·turn
  int flutes = 0;
  std::array<double, kMaxFlutes + 1> event_sample{};
  std::array<double, kMaxFlutes + 1> boundary_sample{};
  std::array<bool, kMaxFlutes + 1> found{};
  std::array<bool, kMaxFlutes + 1> quiet{};  ///< no pulse where the flute's should be
  /// The revolution's period (samples), filtered over the last revolutions: its speed is
  /// f_s/period_samples (the raw period e_N − e_0 jitters with the events).
  double period_samples = 0.0;
  bool valid = false;    ///< every event found
  bool bounded = false;  ///< both CE1 events found: the revolution's span is measured
  bool no_data = false;  ///< the revolution fell into a gap in the samples: nothing measured
};

class ToothEventTracker {
 public:
  ToothEventTracker() = default;
  explicit ToothEventTracker(const ToothEventConfig& config) : config_(config) {}

  /// Starts following the events of `tmpl` (tracker angles of the lock `phase`): finds the CE1
  /// event nearest `anchor_sample`, walks back through the ring to the earliest run of found
  /// events at or after `earliest_sample`, and measures forward from there. Nothing is
  /// allocated. Returns false when not even the anchor's event is found.
  bool start(const ToothEventTemplate& tmpl, const signal::PhaseModel& phase, double anchor_sample,
             std::int64_t earliest_sample, const SampleRing& ring, int detect_channel);
  /// Stops following (the caller's own reason: no loss to take).
  void stop() {
    active_ = false;
    loss_ = ToothEventLoss::kNone;
  }
  /// Why the events stopped on their own since the last call (kNone if they did not), once.
  ToothEventLoss take_loss() { return std::exchange(loss_, ToothEventLoss::kNone); }

  /// Measures every revolution whose samples are in the ring, calling sink(RevolutionEvents)
  /// for each, in order. Stops (active() false) once lost_after revolutions in a row had no
  /// event found, or kCoastRevolutions had samples but not their closing CE1 event (the
  /// revolution's bounds are then the filter's guess; the other flutes' events would keep it
  /// going for ever: 30 revolutions in ToothEventTracker.GivesUpRevolutionsWhose…). Events that
  /// are found but are not the flutes' are the pipeline's to catch, against the spindle
  /// tracker's speed (kEventSpeedDisagreement).
  template <typename Sink>
  void advance(const SampleRing& ring, Sink&& sink) {
    while (active_) {
      const Step s = step(ring);
      if (s == Step::kWait) {
        return;
      }
      if (s == Step::kRevolution) {
        sink(static_cast<const RevolutionEvents&>(revolution_));
      }
    }
  }

  [[nodiscard]] bool active() const { return active_; }
  /// The newest sample the next event needs (valid while active).
  [[nodiscard]] std::int64_t needed_sample() const { return needed_; }
  [[nodiscard]] const ToothEventTemplate& event_template() const { return template_; }
  /// Current revolution period estimate (samples).
  [[nodiscard]] double samples_per_revolution() const { return period_; }
  /// Sample of the last CE1 event that closed a revolution (INT64_MIN before any).
  [[nodiscard]] std::int64_t last_closed_sample() const { return last_closed_; }

 private:
  enum class Step { kWait, kEvent, kRevolution };
  Step step(const SampleRing& ring);
  /// Searches the event of `flute` predicted at `predicted` (samples).
  EventSearch search(const SampleRing& ring, int flute, double predicted) const;
  [[nodiscard]] double lead(int flute) const;  // boundary → event, samples
  /// Whether the force within ± reach of `position` reaches the cut's (min_pulse_).
  [[nodiscard]] bool pulse_around(const SampleRing& ring, double position, double reach) const;
  void close_revolution();

  ToothEventConfig config_;
  ToothEventTemplate template_;
  int detect_ = 3;
  double min_pulse_ = 0.0;  // detect level an event's neighbourhood must reach
  bool active_ = false;
  ToothEventLoss loss_ = ToothEventLoss::kNone;
  std::int64_t needed_ = 0;
  std::int64_t earliest_ = 0;
  std::int64_t last_closed_ = INT64_MIN;
  // Fraction of a revolution from flute j's event to the next flute's, and from each flute's
  // boundary to its event.
  std::array<double, kMaxFlutes> spacing_{};
  std::array<double, kMaxFlutes> lead_fraction_{};
  // g-h-k filter of the CE1 events: this revolution's CE1 event (sample), the revolution period
  // (samples) and its change per revolution.
  double anchor_ = 0.0;
  double period_ = 0.0;
  double period_rate_ = 0.0;
  double typical_miss_ = 0.0;     // running mean of the CE1 events' |miss| of their prediction
  double last_beyond_ = 0.0;      // the last miss if beyond the typical one (0 if not)
  int fast_revolutions_ = 0;      // revolutions left on the short memory after a manoeuvre
  int next_flute_ = 0;            // flute of the next event
  int events_in_revolution_ = 0;  // events of the current revolution so far (incl. its CE1)
  int barren_revolutions_ = 0;    // revolutions in a row without any event found
  int coasted_revolutions_ = 0;   // ... with samples but without their closing CE1 event
  int gone_in_revolution_ = 0;    // events of the current revolution without samples (a gap)
  std::int64_t turn_ = 0;
  std::int64_t sequence_ = 0;
  RevolutionEvents revolution_;
};

}  // namespace millwatch::monitor
