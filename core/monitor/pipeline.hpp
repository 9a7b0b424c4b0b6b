#pragma once
// The monitoring pipeline: dynamometer samples in, every revolution measured, residuals against
// the model in lockstep, spindle state and alerts out. The live daemon and the replay build the
// same pipeline from the same MonitorConfig; only the source and the pacing differ. Everything
// is driven by sample time (the blocks' utime), so a replay of a recorded stream reproduces the
// live results exactly (the lockstep model's rebuilds on ModelBuilder's thread included: they
// apply a fixed number of revolutions after they were asked for).
//
// A block's way through the stages, each owning its state:
//   InputCheck        flags and counts bad samples, gaps, bad blocks
//   Conditioner       axis map → low-pass ×3 → tare                       (conditioner.hpp)
//   SampleRing        filtered fx, fy, fz and Fx² + Fy², by sample index
//   SpindleTracker    speed and phase from the force spectrum; locks on consistent windows
//   ToothEventTracker at a lock: a template of the revolution's tooth events from the ring,
//                     then every revolution's events, back to the start of the cut and on
//   RevolutionAnalyzer features, own speed, angle map, model revolution, residuals
//   RevolutionStats   α and ΔFy over the last window; idle revolutions; AlertEngine
// Outputs go to a PipelineSink, called from the thread that calls process(). After set-up the
// steady state allocates nothing, except when a lock builds the model (a speed change or
// identified parameters rebuild it on ModelBuilder's thread).

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/identify/estimate_watch.hpp"
#include "core/identify/identifier.hpp"
#include "core/monitor/alert_engine.hpp"
#include "core/monitor/conditioner.hpp"
#include "core/monitor/input_check.hpp"
#include "core/monitor/lockstep.hpp"
#include "core/monitor/model_builder.hpp"
#include "core/monitor/monitor_config.hpp"
#include "core/monitor/revolution_analyzer.hpp"
#include "core/monitor/revolution_record.hpp"
#include "core/monitor/revolution_stats.hpp"
#include "core/monitor/sample_block.hpp"
#include "core/monitor/sample_ring.hpp"
#include "core/monitor/sync_average.hpp"
#include "core/monitor/tooth_events.hpp"
#include "core/signal/butterworth_lowpass.hpp"
#include "core/signal/spindle_tracker.hpp"

namespace millwatch::monitor {

struct SpindleUpdate {
  std::int64_t utime_us = 0;  ///< time of the estimate's window centre
  std::int64_t seq = 0;
  std::int64_t revolution = 0;  ///< tracked turns since the stream began
  signal::SpindleEstimate estimate;
  double commanded_rpm = 0.0;
};

enum class PipelineEventKind {
  kBlockRejected,   ///< detail: why; count: samples dropped
  kGap,             ///< count: samples missing
  kNonFinite,       ///< count: samples replaced in the block
  kSaturated,       ///< count: samples at the range in the block
  kLockAcquired,    ///< value: spindle rpm; count: revolutions found before the lock
  kLockLost,        ///< detail: why; the tooth events' speed leaving the tracker's: value,
                    ///< their rpm; count, the tracker's (rounded)
  kModelAligned,    ///< value: alignment correlation; count: revolutions in the average
  kModelUpdated,    ///< identified parameters taken by the model; value: unexplained fraction
  kCuttingStopped,  ///< value: the revolution's peak force, N
  kCuttingResumed,  ///< value: the revolution's peak force, N
  kRecordTooShort,  ///< value: seconds the configured windows need; count: samples of the
                    ///< longest stretch between breaks in the stream
  kNoSteadySignal,  ///< cutting seen, but no two successive windows agreed (count: windows)
  kNoTemplate,      ///< locked, but the revolution's tooth events could not be told apart
  /// Unlocked tracker windows in a row (count) agreed on a strongest spectral line (value, Hz)
  /// that no speed searched explains (signal::SpindleEstimate::line_outside_search): once per
  /// spell without a lock. describe_line_outside_search() words it.
  kSpeedOutOfRange,
  /// The flute-force change detectors hold (AlertEngine): the revolution's speed (value, rpm) is
  /// more than alerts.conditions_tolerance off their baseline's (count: that speed, rpm rounded).
  kAlertsHeld,
  /// The flute-force change detectors compare again: a baseline formed (the first, or one at a
  /// new speed) or the speed came back to the baseline's (detail says which); value: its speed.
  kAlertsArmed,
  /// kFluteLabellingWindows full windows in a row since the lock, while the alerts' baseline
  /// forms, had the same other flute (count: its number, 1-based, in the lock's labelling) hold
  /// more force than CE1 (value: its peak |Fxy| over CE1's, summed over the last window; 0 when
  /// CE1 held none): the lock's template held unusual revolutions (a knock, a carried chip). The
  /// tooth events stop and the next tracker window locks again, its template choosing CE1
  /// afresh; the revolutions since the last one measured are measured from the new CE1 (the
  /// part of one between the two CE1 events is not). Windows identified before it are not
  /// taken (identifications_superseded).
  kFlutesRelabelled
};

std::string_view to_string(PipelineEventKind kind);

/// How much more force than CE1 another flute must hold for CE1 to be in doubt: the pipeline's
/// relabelling over a window (kFlutesRelabelled) and the run summary's warning over the record.
/// A clear margin: flutes of nearly equal force may trade places as the tool wears.
inline constexpr double kFluteLabellingMargin = 1.1;
/// Windows in a row in which the same flute must hold that margin over CE1 for the pipeline to
/// relabel: a knock or a chip carried for a window's revolutions after a good lock is no reason.
inline constexpr int kFluteLabellingWindows = 2;
/// Relabellings after one lock, at most: a template that keeps choosing a CE1 the revolutions
/// disagree with is not relocked for ever (the run summary then warns).
inline constexpr int kMostRelabellings = 3;
/// A relabelling's lock comes within this many tracker windows of it (the next consistent ones);
/// a later lock (the cut stopped first) is the tracker's own.
inline constexpr std::size_t kRelabellingLockWindows = 4;

struct PipelineEvent {
  PipelineEventKind kind = PipelineEventKind::kGap;
  std::int64_t utime_us = 0;
  std::int64_t sample = 0;
  std::int64_t block_seq = 0;
  std::int64_t count = 0;
  double value = 0.0;
  std::string_view detail;
};

/// A kSpeedOutOfRange event's detail where a line stands at its z-th sub-harmonic as well
/// (signal::SpindleEstimate::line_has_spindle_line); any other detail: either reading.
extern const char* const kLineWithSpindleLine;

/// A kSpeedOutOfRange event (its line in value, Hz) in words: the speeds the line means as the
/// spindle frequency and as the tooth-passing one of `config`'s tool, against the commanded
/// speed and the tracker's search — the tooth-passing reading first where the event's detail is
/// kLineWithSpindleLine, else the one nearer the commanded speed.
std::string describe_line_outside_search(const PipelineEvent& e, const MonitorConfig& config);

struct PipelineStatus {
  InputCounters input;
  std::int64_t revolutions = 0;        ///< revolutions reported (cutting)
  std::int64_t valid_revolutions = 0;  ///< ... with every tooth event found
  std::int64_t idle_revolutions = 0;   ///< measured without a cutting force (not reported)
  std::int64_t model_builds = 0;       ///< lockstep model (re)builds: locks and speed changes
  /// Builds whose steady state had slots that did not repeat within model::kMaxSlotRevolutions
  /// (accumulation without a period: their state there stands in the model revolution, which
  /// is then approximate), the most such slots of one build and that build's slots; builds
  /// whose ploughed areas did not settle with the deflection (Lockstep::steady_state_stats()).
  std::int64_t model_builds_unsettled = 0;
  int model_unsettled_slots_most = 0;
  int model_slots_of_most = 0;
  std::int64_t model_builds_area_unsettled = 0;
  std::int64_t identifications_taken = 0;     ///< identified parameters the model took
  std::int64_t identifications_rejected = 0;  ///< ... it did not take (fit failed or poor)
  /// Accepted for the model but never taken by it: a newer fit replaced it while it waited for
  /// the model builder, the run ended (or was handed over) before its build was due, or the
  /// flutes were relabelled since its window (kFlutesRelabelled; nor do the alerts take it).
  /// (With the model in lockstep off, accepted fits go to the alerts alone and count in none of
  /// the three but for those a relabelling overtook.)
  std::int64_t identifications_superseded = 0;
  /// Revolutions the flute-force change detectors held: the speed more than the alerts'
  /// conditions_tolerance off their baseline's (AlertEngine::held_revolutions()).
  std::int64_t alert_held_revolutions = 0;
  bool alerts_holding = false;  ///< they hold now (AlertEngine::holding())
  /// Relabellings of the flutes (kFlutesRelabelled) and the first revolution of the last one's
  /// lock: the revolutions before it name their flutes from another CE1 (0: none).
  std::int64_t flutes_relabelled = 0;
  std::int64_t relabelled_from_revolution = 0;
  /// Revolutions the spindle turned while the tracker heard cutting (an estimate: the time each
  /// cutting window covers past the last one counted, times its speed, and the samples since its
  /// last window at the last speed) — what "every revolution" is measured against.
  double cutting_revolutions = 0.0;
  std::int64_t utime_us = 0;  ///< newest sample
  /// While measuring, the last revolution's speed; else the tracker's (0: none).
  double spindle_rpm = 0.0;
  bool cutting = false;
  std::string_view state = "acquiring";
  std::string_view event_kind = "valley";  ///< tooth event of the current template
};

/// Receives the pipeline's outputs (default: ignore).
class PipelineSink {
 public:
  virtual ~PipelineSink() = default;
  virtual void on_revolution(const RevolutionRecord& /*record*/) {}
  virtual void on_spindle(const SpindleUpdate& /*update*/) {}
  /// Every sync-average window of revolutions: the measured average and the model (may be
  /// null), named by the last revolution reported in it.
  virtual void on_sync_average(const SyncAverage& /*measured*/, const Lockstep* /*model*/,
                               std::int64_t /*revolution*/, std::int64_t /*utime_us*/) {}
  virtual void on_alert(const Alert& /*alert*/) {}
  virtual void on_event(const PipelineEvent& /*event*/) {}
};

class Pipeline {
 public:
  /// @throws config::ConfigError for an inconsistent configuration.
  Pipeline(const MonitorConfig& config, PipelineSink& sink);

  /// Processes one block from any source.
  /// Whether the input check took the block (false: rejected, and counted).
  bool process(const SampleBlock& block);
  /// End of the record: processes the samples still held (zero-phase filtering), counts the
  /// turns heard since the tracker's last window, and says what the record was too short for.
  /// The last call for a record.
  void finish();
  /// This pipeline is replaced mid-stream (a reload): processes the samples still held and
  /// clears its active alerts, saying why (the successor starts with none), without the
  /// record-level verdicts of finish() — the stream goes on. The last call for this pipeline.
  void hand_over(std::string_view why);
  /// Numbers this pipeline's revolutions from `first_revolution` and its spindle updates after
  /// `last_spindle_seq`, the stream having reached `last_utime_us` (a successor's, after a
  /// reload: the numbers a subscriber sees go on). Before the first block.
  void continue_numbering(std::int64_t first_revolution, std::int64_t last_spindle_seq,
                          std::int64_t last_utime_us) {
    revolution_base_ = first_revolution;
    spindle_seq_ = last_spindle_seq;
    alerts_.continue_after(first_revolution - 1, last_utime_us);
  }
  /// The input goes on from a predecessor's (a reload) at the same sample rate: samples missing
  /// between the time it expected next (its next_input_utime_us()) and this pipeline's first
  /// block are a gap, counted as dropped once (those of blocks it rejected are counted already).
  /// Before the first block. At another rate, nothing: blocks at the new rate were rejected by
  /// the predecessor without moving its expected time, and would count twice.
  void continue_input_after(const Pipeline& predecessor) {
    input_.continue_after(predecessor.input_);
  }
  /// The utime (µs) the next input sample is expected at (empty until the first block taken,
  /// unless continue_input_after() said).
  [[nodiscard]] std::optional<std::int64_t> next_input_utime_us() const {
    return input_.next_utime();
  }
  /// The sequence number of the last spindle update (0: none yet).
  [[nodiscard]] std::int64_t last_spindle_seq() const { return spindle_seq_; }

  /// Identification (not owned; null: none). Every synchronous-average window goes to it, due
  /// back a window of revolutions after its end (when the next window ends); at that revolution
  /// the model in lockstep takes the identified parameters (runout, force-law coefficients,
  /// alignment) when the fit explains the window (at most identification.max_unexplained of its
  /// variance unexplained, 20 % by default),
  /// else keeps its own. Revolution-counted, so a replay hands over exactly where the live run
  /// did when no result came late (identify::Identifier).
  /// The alert engine follows the estimates it takes (runout high, runout change, wear drift);
  /// after three windows without an accepted one (fits rejected, or a live worker that cannot
  /// keep up; with a CPU budget, three budget periods: identify::EstimateWatch) it follows the
  /// flute forces until the next.
  void attach_identifier(identify::Identifier* identifier) {
    identifier_ = identifier;
    alerts_.expect_estimates(identifier != nullptr);
  }

  [[nodiscard]] PipelineStatus status() const;
  [[nodiscard]] const MonitorConfig& config() const { return config_; }
  /// The tracker's phase model at full rate (valid while locked).
  [[nodiscard]] const signal::PhaseModel& phase() const { return phase_; }
  [[nodiscard]] const Lockstep& lockstep() const { return lockstep_; }
  /// Whether the model revolution is measured once per model and alignment and placed on each
  /// turn (the default), or measured anew on every turn (the tests compare the two).
  void keep_model_revolution(bool keep) { analyzer_.keep_model_revolution(keep); }
  /// Whether a block going on from the last has its samples checked in the filter's pass (the
  /// default; Conditioner::filter_checked, on a measuring grid or every sample) or in the input
  /// check's own pass before it (the tests compare the two).
  void check_samples_in_filter(bool in_filter) { check_in_filter_ = in_filter; }
  [[nodiscard]] const signal::ButterworthDesign& filter() const { return filter_; }
  /// The tooth-event template of the current (or last) lock.
  [[nodiscard]] const ToothEventTemplate& event_template() const {
    return events_.event_template();
  }

 private:
  void restart_stream(std::int64_t first_sample);
  void bridge_gap(std::int64_t first_sample);
  void fill_gap(const CheckedBlock& c);
  /// Checked samples (instrument frame) from sample `first` through the conditioner and on.
  void condition(std::int64_t first, std::span<const double> fx, std::span<const double> fy,
                 std::span<const double> fz);
  /// Processes the samples still held and checks the input since the last health check.
  void flush_tail();
  /// The number of the last revolution reported (a reload's successor numbers on).
  [[nodiscard]] std::int64_t last_revolution() const { return revolution_base_ + revolutions_ - 1; }
  /// Everything after the conditioner, for filtered sample n.
  void downstream(std::int64_t n, double fx, double fy, double fz);
  /// downstream() for `count` samples from n on, within run_limit(n).
  void downstream_run(std::int64_t n, std::size_t count, const double* fx, const double* fy,
                      const double* fz);
  /// How many samples from n on downstream_run() can take at once: up to the next one that
  /// needs a look (a tracker update, the tooth events' next needed sample, a health check).
  void measure_run(std::int64_t n, std::size_t count, const double* fx, const double* fy,
                   const double* fz);
  [[nodiscard]] std::size_t run_limit(std::int64_t n) const;
  /// The first measuring sample at or after input sample n, and back.
  [[nodiscard]] std::int64_t measuring_sample(std::int64_t n) const {
    return n >= 0 ? (n + stride_ - 1) / stride_ : -((-n) / stride_);
  }
  [[nodiscard]] std::int64_t input_sample(std::int64_t m) const {
    return m == INT64_MIN ? m : m * stride_;
  }
  [[nodiscard]] std::int64_t utime_at(std::int64_t m) const {
    return input_.utime_of(input_sample(m));
  }
  void on_tracker_update();
  /// Follows the tracker's strongest line outside its search over unlocked windows and reports
  /// it (kSpeedOutOfRange) once they agree on it.
  void note_line_outside_search(const signal::SpindleEstimate& e, std::int64_t center);
  /// Turns heard while cutting since the tracker's last window, not counted by it yet.
  [[nodiscard]] double heard_since_update() const;
  void start_events();
  /// The synchronous average and its window's counts start afresh (a lock; revolutions unlike
  /// the cut at its start).
  void restart_average();
  /// The tooth events over the ring's new samples, and a kLockLost event if they stopped on
  /// their own.
  void advance_events();
  /// The tooth events' speed (rpm) over the revolution holding measuring sample n, 0 if none of
  /// the last revolutions since the lock holds it.
  [[nodiscard]] double events_rpm_at(double n) const;
  /// The tooth-event template at a lock; nullptr, or why there is none (a literal).
  const char* build_template(std::int64_t anchor, ToothEventTemplate& out);
  void on_revolution(const RevolutionEvents& events);
  /// The lockstep model follows the spindle speed (rebuilt when it moved by more than 0.2 %):
  /// the first model, and with `now` (a lock), at once; else on builder_'s thread, taken
  /// build_delay_revolutions_ later (take_model_build()).
  void follow_speed(double spindle_hz, bool now = false);
  /// The model builder_ was asked for goes into the lockstep, waited for if it is not done:
  /// when due (`due_only`), or at once (before anything else changes the model); a fit's with
  /// its alignment. Then, with `start_next`, the build of a fit that waited for it.
  void take_model_build(bool due_only, bool start_next = true);
  /// Counts the build the lockstep model now is, and what its steady state was like.
  void count_model_build();
  /// Starts building the model of the fit waiting for builder_, if it is free.
  void start_fit_build();
  /// Aligns the model on the revolutions in the average (the one just added, `ev`, last): the
  /// schedule's next, the event; on the lock's first, the revolution's model part (`r`).
  void align_on_revolutions(const RevolutionEvents& ev, std::int64_t sample, RevolutionRecord& r);
  /// Identified parameters taken by the model (built with them): their alignment, the event.
  struct PendingFit;
  void apply_fit(const PendingFit& f);
  /// The window just completed goes to the identifier.
  void submit_window();
  /// The identified parameters due at this revolution, if any, go to the model.
  void take_identification();
  /// A lock's labelling starts to be checked (a relabelling's lock, at `anchor` soon after it,
  /// counts on).
  void start_labelling(std::int64_t anchor);
  /// The relabellings are over: the next lock is the tracker's own (a restarted stream).
  void forget_labelling();
  /// Sums the revolution's flute forces and, over each full window since the lock, checks that
  /// CE1 holds the largest; true when the events stopped to relabel (kFlutesRelabelled).
  bool check_labelling(const RevolutionRecord& r, std::int64_t sample);
  /// Tells the alert engine's flute-force state changes (kAlertsHeld, kAlertsArmed).
  void tell_alert_state(std::int64_t sample, double rpm);
  /// `block_utime_us`: a rejected block's own time, which the event takes where plausible.
  void event(PipelineEventKind kind, std::int64_t sample, std::int64_t count, double value,
             std::string_view detail, std::int64_t block_seq = 0,
             std::optional<std::int64_t> block_utime_us = std::nullopt);

  MonitorConfig config_;
  PipelineSink& sink_;
  InputCheck input_;
  signal::ButterworthDesign filter_;
  Conditioner conditioner_;
  signal::SpindleTracker tracker_;
  // The measuring stages (ring, tracker, tooth events, analyser, model) take every stride_-th
  // filtered sample, at rate_hz_; their sample numbers count those (input sample / stride_).
  int stride_ = 1;
  double rate_hz_ = 0.0;
  int decimation_ = 1;        // the tracker takes every decimation_-th measuring sample
  int decimation_phase_ = 0;  // measuring samples until the tracker's next one
  signal::PhaseModel phase_;  // the tracker's, at the measuring rate
  SampleRing ring_;
  ToothEventTracker events_;
  RevolutionAnalyzer analyzer_;
  SyncAverage sync_;
  // The in-plane resultant's average on the same grid and window, for the tooth events'
  // template at a lock (build_template()).
  SyncAverageOf<1> resultant_;
  Lockstep lockstep_;
  RevolutionStats stats_;
  AlertEngine alerts_;

  std::int64_t stream_start_ = 0;
  std::int64_t last_sample_ = -1;
  std::int64_t stretch_first_ = 0;    // first input sample since the last break in the stream
  std::int64_t longest_stretch_ = 0;  // input samples of the longest stretch before it (0: none)
  std::int64_t measured_until_ = INT64_MIN;  // end of the last revolution measured
  std::int64_t revolutions_ = 0;
  std::int64_t model_builds_ = 0;
  std::int64_t model_builds_unsettled_ = 0;
  int model_unsettled_slots_most_ = 0;
  int model_slots_of_most_ = 0;
  std::int64_t model_builds_area_unsettled_ = 0;
  std::int64_t valid_revolutions_ = 0;
  std::int64_t idle_revolutions_ = 0;
  bool check_in_filter_ = true;  // check_samples_in_filter()
  bool idle_ = false;            // the last revolution had no cutting force
  int idle_streak_ = 0;
  bool ever_locked_ = false;     // the tooth events started at least once
  bool tracker_locked_ = false;  // the tracker locked at least once (kNoTemplate said the rest)
  std::int64_t inconsistent_windows_ = 0;  // cutting windows that did not agree, since a lock
  // Successive unlocked windows whose strongest line lies outside the search and agrees
  // (note_line_outside_search): how many, their mean (Hz), whether this spell without a lock
  // reported it, and whether any spell did.
  int line_run_ = 0;
  double line_run_hz_ = 0.0;
  bool line_reported_ = false;
  bool line_ever_reported_ = false;
  std::int64_t alias_windows_ = 0;  // windows the tracker refused as an alias (finish())
  std::string no_signal_detail_;    // finish()'s kNoSteadySignal detail, with the threshold
  double cutting_revolutions_ = 0.0;
  // Where the last cutting window counted in cutting_revolutions_ ended (measuring samples): a
  // cutting window adds the time it covers past it, at most its own length.
  double cutting_counted_until_ = -std::numeric_limits<double>::infinity();
  double finished_tail_revolutions_ = 0.0;  // heard after the last window, counted by finish()
  bool was_cutting_ = false;
  double last_rpm_ = 0.0;
  // The last revolutions' spans (measuring samples) and speeds: the tooth events' speed at a
  // tracker window's centre, which a ramp leaves far from the newest revolution's.
  struct RevolutionSpeed {
    double from = 0.0, to = 0.0, rpm = 0.0;
  };
  std::array<RevolutionSpeed, 32> recent_speeds_{};
  std::size_t recent_speeds_next_ = 0;
  // The lock's alignment is on its template average, in the tracker's angle; the revolutions
  // place their samples by their tooth events (on_revolution()). Until the model is aligned on
  // a revolution so placed, it states no residuals; then it is aligned again as the average
  // doubles, up to a full window (next_alignment_revolutions_: 0, none due). A fit from before a
  // lock, taken part-way through a later window, is aligned when that window is full (the
  // synchronous average's windows follow one another: apply_fit()). A first alignment
  // more than a quarter pitch from the template's is refused: the average starts again (up to
  // kFirstAlignmentRestarts times in the lock's first window; first_alignment_restarts_) or,
  // after that, grows until the next alignment due (align_on_revolutions()).
  bool aligned_on_template_ = false;
  int next_alignment_revolutions_ = 0;
  int first_alignment_restarts_ = 0;
  std::int64_t spindle_seq_ = 0;
  std::int64_t sync_revolutions_since_report_ = 0;
  std::int64_t next_health_check_ = 0;
  std::int64_t max_bridged_gap_ = 0;
  std::int64_t max_filled_gap_ = 1;              // samples: filled by fill_gap()
  std::array<std::vector<double>, 3> gap_fill_;  // its samples (max_filled_gap_ each)
  std::array<double, 3> last_reading_{};         // the last checked sample (instrument frame)
  double tooth_delay_s_ = 0.0;
  RevolutionRecord record_;  // scratch for the revolution being analysed
  identify::Identifier* identifier_ = nullptr;
  identify::MeasuredRevolution window_;  // reused: no allocation after the first window
  double window_rpm_sum_ = 0.0;          // speeds of the window's bounded revolutions
  int window_rpm_count_ = 0;
  std::int64_t lock_revolution_ = 0;  // first revolution of the current lock
  std::int64_t revolution_base_ = 0;  // the number of this pipeline's first revolution
  std::int64_t identifications_taken_ = 0;
  std::int64_t identifications_rejected_ = 0;
  std::int64_t identifications_superseded_ = 0;
  identify::EstimateWatch estimate_watch_;  // when the alerts stop waiting for estimates
  std::vector<double> template_average_;
  // The in-plane channels' smaller synchronous range over the larger, as build_template() last
  // found them (a dead channel's sensor alert states it, raised and cleared).
  double flat_range_ratio_ = 0.0;
  bool pauses_expected_ = false;  // the commanded cut pauses between flutes (the template's test)
  // The alert engine's flute-force state after the last revolution (for kAlertsHeld/Armed).
  bool alerts_holding_ = false;
  bool alerts_armed_ = false;
  double alerts_baseline_rpm_ = 0.0;
  // Rebuilds off this thread (made with the first model, at the lock); the one asked for applies
  // from revolution build_due_ on, build_delay_revolutions_ after it was asked for.
  std::unique_ptr<ModelBuilder> builder_;
  std::int64_t build_due_ = 0;
  std::int64_t build_delay_revolutions_ = 2;
  // Identified parameters accepted for the model (take_identification()), waiting for builder_
  // or being built by it.
  struct PendingFit {
    model::ModelConfig config;
    double alignment_rad = 0.0;
    bool same_lock = false;  // the window was measured since the lock
    std::int64_t lock = 0;   // that lock's number (locks_)
    std::int64_t window_revolution = 0;
    double unexplained = 0.0;
    bool stale = false;  // the flutes were relabelled while it was built: not to be taken
  };
  std::optional<PendingFit> waiting_fit_;
  std::optional<PendingFit> building_fit_;
  std::int64_t locks_ = 0;  // locks that reached the model (start_events())
  // Flute labelling (check_labelling()): each flute's peak |Fxy| summed over the bounded
  // revolutions since the lock or the last check; the flute that held clearly more force than
  // CE1 over the last windows (0: none) and in how many windows in a row; whether the events
  // stopped to relabel (the next lock is the relabelling's); the relabellings since the last
  // lock of the tracker's own; the first revolution of the current labelling (identified
  // windows from before it name the flutes otherwise).
  std::array<double, kMaxFlutes> label_peak_sum_N_{};
  int label_revolutions_ = 0;
  std::size_t label_candidate_ = 0;
  int label_windows_ = 0;
  bool relabelling_ = false;
  std::int64_t relabelled_at_ = 0;  // the stream's newest sample when it relabelled
  int relabellings_ = 0;
  std::int64_t flutes_relabelled_ = 0;  // in all (PipelineStatus::flutes_relabelled)
  std::int64_t labelling_revolution_ = 0;
  double wanted_hz_ = 0.0;  // the speed the model was last asked to follow
};

}  // namespace millwatch::monitor
