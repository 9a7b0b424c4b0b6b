#pragma once
// Tool-state alerts from the per-revolution records, the identified windows (runout and force
// coefficients with their σ, core/identify) and the input counters, with a stated false-alarm
// rate.
//
// Flute force. Each flute's force in a revolution is the length of its range vector,
//   F_j = √(Σ_axis range_N[j][axis]²)   (N; range = max − min of fx, fy, fz in the flute's period),
// which a channel offset (charge-amplifier drift) does not change. From it:
//   mean flute force  M = mean_j F_j,   share  s_j = F_j/M − 1,
//   imbalance         I = (max_j F_j − min_j F_j)/M = max_j s_j − min_j s_j,
//   strength          g_j = F_j / max_k F_k.
//
// Baseline. The first `baseline_blocks` × `block_revolutions` valid revolutions. For each series
// (s_j, M) the median, σ = 1.4826·MAD and the lag-1 autocorrelation ρ of the single revolutions
// give the σ of a block median, σ_b = 1.2533·σ·√((1 + ρ)/(1 − ρ))/√B (AR(1) long-run inflation),
// compared with the MAD of the baseline's own block medians; the larger of the two, floored at
// `sigma_floor` (relative to the mean flute force), is used.
//
// Estimates. on_identification() takes each fitted window (in window order, after its last
// revolution): the cutting-radius differences d_j = r_j − r_CE1 (what the force pins, physics-notes
// "What the force can tell about runout"), ρ and γ for the text, and the force coefficients, each
// with σ. The window's feed per tooth is the commanded one at the window's mean actual speed
// (from the revolutions: the feed rate is fixed, f_t = f_t,cmd·n_cmd/n). The estimates' baseline
// is the first `estimate_baseline_windows` fitted windows: per quantity the median and the σ of
// one window about it, the larger of 1.4826·MAD/√2 of successive windows' differences (blind to
// a slow trend) and the windows' median statistical σ (the systematic σ is a bias common to the
// windows of one cut and left out of comparisons between them; the texts give total σ's), floored
// (sigma_floor × f_t for radii, × the value for coefficients), times √(1 + 1/n) for the baseline's
// own error. A window at another speed or feed (beyond `conditions_tolerance`) starts a new one
// (coefficients are compared at constant conditions); alerts raised stay until they clear or
// rebaseline(). Once a fitted window has arrived (or from the start after expect_estimates()),
// runout and wear drift follow the estimates; before that, or with identification off, they
// follow the flute forces as described below.
//
// Detectors (each raised once and cleared once; ARL₀ = `false_alarm_revolutions` per detector,
// i.e. at most one false alarm per ARL₀ revolutions of an unchanged cut):
//  runout         (the runout_high) From the estimates: flute j's chip at the slot centre
//                 against the pass n flutes back is n·f_t + r_j − r_{j−n} (chip_geometry.hpp;
//                 to first order in ρ/R), and the chip is the least over the passes, so flute j
//                 stops cutting when f_t ≤ f*_j = max_{n=1..N−1} (r_{j−n} − r_j)/n ([000]: for
//                 N_z = 2, f* = r_CE1 − r_CE2 ≈ 2ρ·cos γ, i.e. f_t/ρ = 2 = N_z at γ = 0; 3 flutes
//                 1.5ρ and 0.75ρ, 4 flutes ρ, ρ, ρ/3 at γ = 0). The statistic is u = max_j f*_j/f_t
//                 (1: a flute stops cutting) with σ_u from the radii's total σ (statistical and
//                 systematic; a pair not through CE1 takes σ_a + σ_b). Raised when
//                 u − z·σ_u > `runout_feed_fraction` for `estimate_windows` windows in a row, z =
//                 `estimate_sigmas`; cleared when u + z·σ_u < hysteresis × the limit as long. A
//                 level alarm: a false one needs the estimate z σ beyond a truth at the limit,
//                 P(Z > 3) = 0.13 % per window there (persistence lowers it; far less below).
//                 Without estimates: I of a revolution above `runout_imbalance` for
//                 `persist_revolutions`, cleared below `hysteresis`·limit for as long (no design
//                 rate). A window whose estimate cannot tell (u − z·σ_u below the clearing
//                 level and u + z·σ_u above the limit: where a flute cuts nothing the force
//                 bounds a runout beyond the feed poorly, [002]'s copper slot) counts as the
//                 flute forces' level says, and a raise or clear it makes quotes them.
//  runout change  Three detectors, one alert (whichever trips first raises it):
//                 per revolution (large steps, within revolutions): a flute's share s_j beyond
//                   its baseline median by more than max(z_r·σ_j, `runout_step_min`), σ_j the σ
//                   of a single revolution's share, on the same side for
//                   `runout_step_revolutions` revolutions in a row, while no flute is below its
//                   breakage limit (a collapse is breakage; neither flute-force detector
//                   raises while breakage is active). P(|Z| > z_r) = 1/(ARL₀·detectors):
//                   a Gaussian bound on one revolution; persistence only lowers the rate.
//                 per block (small steps): each flute's block-median share s̃_j against the
//                   baseline: a two-sided CUSUM of z = (s̃_j − μ_j)/σ_b,j with allowance
//                     k_j = max(cusum_k, runout_change_min/(2σ_b,j)) + baseline_margin/√n_b
//                   (changes below runout_change_min/2 never accumulate; the last term covers
//                   the baseline mean's own error up to `baseline_margin` standard errors) and
//                   threshold h_j from Siegmund's ARL at k_j without the margin term, for ARL₀/B
//                   blocks shared by both sides and the flutes (one detector for 2 flutes, whose
//                   shares are ± each other; one per flute for more). A CUSUM above h_j is
//                   confirmed on the excursion's blocks after its first (which may straddle the
//                   change): their mean must lie beyond the allowance k_j·σ_b,j. Cleared when a
//                   CUSUM of (hysteresis·k_j·σ_b,j − d)/σ_b,j, d the deviation in the raised
//                   direction, with allowance cusum_k exceeds h_j (for the per-revolution
//                   detector too).
//                 per window (from the estimates): a radius difference d_j beyond its baseline by
//                   more than max(z_w·σ_j, `runout_change_min_um`) on the same side for
//                   `estimate_windows` windows in a row, P(|Z| > z_w) = W/(ARL₀·(N − 1)) for
//                   windows of W revolutions (Gaussian bound on one window); cleared when every
//                   d_j is back within hysteresis × that as long.
//                 A change raised by the flute forces is stated physically when the first window
//                 wholly after its onset is fitted: one info message (active, severity info)
//                 with r_CE1 − r_CEj and ρ, γ before (the estimates' baseline, or the last window
//                 before the onset) → after, each ± σ.
//  wear drift     From the estimates: per fitted coefficient c (up to kMaxCoefficients) the rise
//                 x = c/c̄ − 1 over its baseline: a one-sided CUSUM of (x − coefficient_increase)/σ
//                 with allowance cusum_k + baseline_margin/√n and h for ARL₀/W windows shared by
//                 the coefficients, while the true rise is at most the limit (a coefficient whose
//                 baseline σ exceeds a third of the limit is not pinned and not followed, e.g.
//                 K_ac without a measured Fz); confirmed on the
//                 excursion's windows after its first (their mean rise must exceed the limit);
//                 cleared by the mirror CUSUM of (hysteresis·limit − x)/σ.
//                 Without estimates: per block the rise r = M̃/μ_M − 1 of the block-median mean
//                 flute force, a one-sided CUSUM of (r − wear_increase)/σ_r likewise (ARL₀/B
//                 blocks), confirmed and cleared the same way.
//  breakage       per revolution, a flute's strength relative to its baseline strength,
//                 q_j = g_j/ĝ_j, below τ_j = min(breakage_fraction, 1 − z·σ_q,j) for
//                 `persist_revolutions`, with P(Z > z) = 1/(ARL₀·flutes) (Gaussian bound on a
//                 single revolution; persistence only lowers the rate); cleared above
//                 τ_j/hysteresis for as long.
//  sensor         saturated or non-finite samples above `sensor_bad_fraction` of the samples of a
//                 status interval, or gaps in the stream; cleared at the first clean interval.
// Conditions: a flute's share of the force and the mean flute force move with the feed per tooth
// (f_t = f_t,cmd·n_cmd/n at a fixed feed rate: a 10 % slower spindle cuts 11 % thicker chips, and
// with runout the flutes' shares change with it), so the flute-force baseline holds at one speed.
// Its revolutions are within `conditions_tolerance` of the first one's speed (the baseline starts
// again from a revolution beyond it), and it keeps their median speed. A revolution more than that
// off the baseline's speed is not compared (runout change per revolution and per block, wear drift
// without estimates: held_revolutions() counts them) and starts a new baseline at its speed; a
// speed that comes back within the tolerance before the new baseline is complete returns to the
// old one. Breakage (relative strengths, nearly independent of f_t) and the imbalance runout stay
// on throughout. Alerts raised stay raised; their clearing detectors restart on the new baseline.
//
// Severity: breakage is an alarm, the others warnings, clears and the runout change's identified
// follow-up are info. rebaseline() forgets both baselines (a new tool) and clears the change
// alerts at the next revolution.
//
// Alert fields: runout value = u (I without estimates), threshold = the limit; runout change
// value = I after the change, threshold = the baseline's I (from the estimates: value =
// r_CE1 − r_CEj after, threshold = before, µm; likewise the follow-up); wear drift value = the rise
// after (x or r), threshold = the limit; breakage value = q_j of the weakest flute, threshold =
// τ_j. Everything is allocated at construction; examining a revolution or a window allocates
// nothing.

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "core/monitor/change_detector.hpp"
#include "core/monitor/revolution_features.hpp"

namespace millwatch::identify {
struct IdentifiedWindow;
}

namespace millwatch::monitor {

struct RevolutionRecord;
struct InputCounters;

/// Force coefficients of an identified window the wear detector follows.
inline constexpr int kMaxCoefficients = 8;

enum class AlertKind : std::int8_t {
  kRunout = 1,  ///< runout high (the short flute's chip vanishing; without estimates: imbalance)
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
  bool active = true;           ///< raised (true) or cleared (false)
  std::int64_t revolution = 0;  ///< at detection; −1: before the stream's first revolution
  std::int64_t utime_us = 0;
  double value = 0.0;
  double threshold = 0.0;
  std::string_view quantity;        ///< name with unit of value/threshold
  std::array<char, 256> message{};  ///< one line for the operator
};

struct AlertConfig {
  double runout_imbalance = 0.25;  ///< limit of I = (max − min)/mean of the flute forces
  int persist_revolutions = 10;    ///< runout and breakage: revolutions to raise or clear
  double hysteresis = 0.8;         ///< clear at this fraction of a limit (breakage: limit/this)
  int block_revolutions = 25;      ///< B: revolutions per block of the change detectors
  int baseline_blocks = 20;        ///< n_b: blocks in the baseline
  /// ARL₀: average revolutions between false alarms of one change detector on an unchanged cut.
  double false_alarm_revolutions = 1e7;
  double cusum_k = 0.5;          ///< CUSUM allowance, σ of a block statistic
  double baseline_margin = 3.0;  ///< baseline standard errors added to the allowance
  /// Least σ of a block share or rise (fraction of the mean), of a radius difference (fraction
  /// of the feed per tooth) and of a coefficient (fraction of its baseline).
  double sigma_floor = 0.001;
  /// Least relevant change of a flute's share of the mean flute force (2 flutes: the imbalance
  /// changes by twice this); 0 = any statistically detectable change.
  double runout_change_min = 0.02;
  /// Per-revolution runout change: least change of a flute's share in single revolutions, and
  /// the revolutions in a row it must last.
  double runout_step_min = 0.05;
  int runout_step_revolutions = 2;
  double wear_increase = 0.15;     ///< limit of the mean flute force's rise over its baseline
  double breakage_fraction = 0.3;  ///< a flute below this of its baseline strength is broken
  double sensor_bad_fraction = 0.001;
  /// Runout from the estimates: limit of u = (largest radius deficit per feed)/f_t (1: a flute
  /// stops cutting), and the σ by which the estimate must pass it (or, to clear, its hysteresis).
  double runout_feed_fraction = 0.5;
  double estimate_sigmas = 3.0;
  int estimate_windows = 2;            ///< fitted windows in a row to raise or clear
  int estimate_baseline_windows = 10;  ///< fitted windows in the estimates' baseline
  double runout_change_min_um = 0.2;   ///< least relevant change of a radius difference, µm
  double coefficient_increase = 0.10;  ///< limit of a force coefficient's rise over its baseline
  /// Relative change of the window's speed or feed per tooth that starts a new estimates' baseline;
  /// of a revolution's speed, that holds the flute-force detectors and starts their new baseline.
  double conditions_tolerance = 0.01;
};

/// @throws config::ConfigError naming the field.
AlertConfig alert_config_from_json(const nlohmann::json& j, const std::string& path);
nlohmann::json to_json(const AlertConfig& c);

class AlertEngine {
 public:
  AlertEngine() : AlertEngine(AlertConfig{}) {}
  /// Allocates the baseline and block storage.
  explicit AlertEngine(const AlertConfig& config);

  /// Examines one revolution; calls sink(const Alert&) for each change of state.
  template <typename Sink>
  void on_revolution(const RevolutionRecord& r, Sink&& sink) {
    examine(r);
    flush(sink);
  }
  /// Examines one identified window, handed over after its last revolution (windows in order;
  /// an older or unfitted one is ignored); calls sink(const Alert&) for each change of state.
  template <typename Sink>
  void on_identification(const identify::IdentifiedWindow& w, Sink&& sink) {
    examine(w);
    flush(sink);
  }
  /// An in-plane channel that carries no cutting force while the other does (0 fx, 1 fy; -1:
  /// none): sensor trouble from the next on_input() on, until it is -1 again. `range_ratio`:
  /// the smaller channel's synchronous range over the other's, and `limit` the ratio below which
  /// it is dead (the alert's value and threshold, raised and cleared).
  void set_dead_channel(int channel, double range_ratio = 0.0, double limit = 0.0) {
    dead_channel_ = channel;
    dead_range_ratio_ = range_ratio;
    dead_range_limit_ = limit;
  }
  /// Examines the input counters since the previous call.
  template <typename Sink>
  void on_input(const InputCounters& c, std::int64_t utime_us, Sink&& sink) {
    examine(c, utime_us);
    flush(sink);
  }
  /// Clears every active alert, saying `why` (this engine is being replaced, e.g. on a reload:
  /// its successor starts with none raised); each clear carries the figures it was raised on.
  template <typename Sink>
  void clear_active(std::string_view why, Sink&& sink) {
    clear_all(why);
    flush(sink);
  }
  /// Identification runs (identified windows will come): runout and wear drift wait for the
  /// estimates instead of following the flute forces until the first window arrives. With
  /// `expected` false (estimates stopped coming: fits rejected, a worker that cannot keep up)
  /// they follow the flute forces again, even after estimates came, until the next window.
  void expect_estimates(bool expected = true);
  /// Forget the baselines (a new tool, a reconfiguration); active runout change, wear drift and
  /// breakage alerts are cleared at the next revolution.
  void rebaseline();
  /// The stream so far ends at revolution `last_revolution`, time `utime_us` (a successor's,
  /// after a reload: an alert or a clear before this engine's first revolution names them, as
  /// it would have without the reload). Call before the first revolution.
  void continue_after(std::int64_t last_revolution, std::int64_t utime_us) {
    last_revolution_ = last_revolution;
    last_utime_us_ = utime_us;
  }

  /// The baseline, once complete (for tests and diagnostics).
  struct Baseline {
    bool ready = false;
    int flutes = 0;
    double spindle_rpm = 0.0;                           ///< median speed (0: not known)
    double mean_force_N = 0.0;                          ///< μ_M, median of M
    double rise_sigma = 0.0;                            ///< σ_r of a block's relative rise
    std::array<double, kMaxFlutes> share{};             ///< μ_j, median of s_j
    std::array<double, kMaxFlutes> share_sigma{};       ///< σ_b,j of a block-median share
    std::array<double, kMaxFlutes> step_limit{};        ///< per-revolution runout-change limit
    std::array<double, kMaxFlutes> strength{};          ///< ĝ_j, median of g_j
    std::array<double, kMaxFlutes> breakage_limit{};    ///< τ_j
    std::array<double, kMaxFlutes> change_allowance{};  ///< k_j
    std::array<double, kMaxFlutes> change_threshold{};  ///< h_j
    double wear_allowance = 0.0;
    double wear_threshold = 0.0;
  };
  [[nodiscard]] const Baseline& baseline() const { return baseline_; }
  /// Revolutions the flute-force change detectors did not compare with their baseline: the
  /// speed was more than conditions_tolerance off the baseline's (a new baseline forming).
  [[nodiscard]] std::int64_t held_revolutions() const { return held_revolutions_; }
  /// Whether the flute-force change detectors hold now (a new baseline forming at another speed).
  [[nodiscard]] bool holding() const { return reforming_; }

  /// The estimates' baseline, once complete (for tests and diagnostics).
  struct EstimateBaseline {
    bool ready = false;
    int windows = 0;
    int flutes = 0;
    double spindle_rpm = 0.0;                               ///< the windows' mean actual speed
    double feed_per_tooth_um = 0.0;                         ///< f_t at that speed
    std::array<double, kMaxFlutes> radius_difference_um{};  ///< d̄_j = r_j − r_CE1 (median)
    std::array<double, kMaxFlutes> radius_sigma_um{};       ///< σ of one window's d_j about d̄_j
    std::array<double, kMaxFlutes> radius_limit_um{};  ///< runout-change limit of |d_j − d̄_j|
    std::array<double, kMaxFlutes> radius_total_sigma_um{};  ///< median total σ of d_j (absolute)
    double rho_um = 0.0, rho_sigma_um = 0.0;                 ///< median ρ, median total σ
    bool rho_lower_bound = false;  ///< some window's ρ a lower bound (on a contact edge)
    double gamma_rad = 0.0, gamma_sigma_rad = 0.0;  ///< γ (circular mean), median total σ
    int coefficients = 0;
    std::array<std::array<char, 32>, kMaxCoefficients> coefficient_name{};
    std::array<double, kMaxCoefficients> coefficient{};        ///< c̄ (median)
    std::array<double, kMaxCoefficients> coefficient_sigma{};  ///< σ of one window's c/c̄
    double wear_allowance = 0.0;
    double wear_threshold = 0.0;
  };
  [[nodiscard]] const EstimateBaseline& estimate_baseline() const { return estimate_base_; }

 private:
  struct Level {
    bool active = false;
    int streak = 0;
  };
  /// What an alert was raised on: a clear by a new baseline reports it (there is no new value).
  struct Raised {
    double value = 0.0;
    double threshold = 0.0;
    std::string_view quantity;
  };
  /// What raises a sensor alert, in the order it is named: a dead in-plane channel, bad
  /// samples above their limit, gaps.
  enum class SensorCause { kDeadChannel, kBadSamples, kGaps };
  /// The sensor alert's value for `cause`, raised or cleared: the quantity, its figure now and
  /// its limit.
  [[nodiscard]] Raised sensor_figure(SensorCause cause, double bad_fraction,
                                     std::int64_t new_gaps) const;
  struct Flutes {
    int count = 0;
    std::array<double, kMaxFlutes> force_N{};
    std::array<double, kMaxFlutes> share{};
    double mean_N = 0.0;
    double imbalance = 0.0;
  };
  struct Block {
    std::array<double, kMaxFlutes> share{};
    double mean_N = 0.0;
  };
  /// What one fitted window says.
  struct WindowEstimate {
    int flutes = 0;
    std::int64_t first_revolution = 0, last_revolution = 0;
    double spindle_rpm = 0.0, feed_per_tooth_um = 0.0;
    std::array<double, kMaxFlutes> radius_difference_um{}, radius_sigma_um{},
        radius_sigma_stat_um{};
    double rho_um = 0.0, rho_sigma_um = 0.0, gamma_rad = 0.0, gamma_sigma_rad = 0.0;
    bool rho_lower_bound = false;  ///< at a flute's contact edge (FitResult)
    int edge_flute = -1;           ///< the flute there (FitResult), −1 off an edge
    int coefficients = 0;
    std::array<double, kMaxCoefficients> coefficient{}, coefficient_sigma_stat{};
  };
  enum class ChangeSource : std::int8_t { kRevolution, kBlock, kEstimate };
  static constexpr int kRecentBlocks = 64;
  static constexpr int kRecentWindows = 64;
  static constexpr int kRecentRevolutions = 1024;  // speeds, for the windows' feed per tooth
  static constexpr int kStepRevolutions = 32;      // shares, for the per-revolution detector

  void examine(const RevolutionRecord& r);
  void examine(const identify::IdentifiedWindow& w);
  void examine(const InputCounters& c, std::int64_t utime_us);
  void check_runout(const Flutes& f, std::int64_t rev, std::int64_t t);
  /// The flute forces' imbalance as a level (check_runout's rule), kept while the estimates
  /// lead too: what decides runout where they cannot.
  void track_imbalance(const Flutes& f);
  /// Returns whether a flute is below its breakage limit in this revolution.
  bool check_breakage(const Flutes& f, std::int64_t rev, std::int64_t t);
  void check_runout_step(const Flutes& f, bool collapsing, std::int64_t rev, std::int64_t t);
  /// Adds a revolution at `rpm` (0: not known) to the baseline being formed; restarts it when
  /// the speed is beyond the tolerance of its first revolution's.
  void add_to_baseline(const Flutes& f, double rpm);
  /// Whether `rpm` is within conditions_tolerance of `reference_rpm` (either unknown: yes).
  [[nodiscard]] bool same_speed(double rpm, double reference_rpm) const;
  void finish_baseline();
  void add_to_block(const Flutes& f, std::int64_t rev, std::int64_t t);
  void check_runout_change(const Block& b, std::int64_t rev, std::int64_t t);
  void check_wear(const Block& b, std::int64_t rev, std::int64_t t);
  void clear_after_rebaseline(std::int64_t rev, std::int64_t t, std::string_view why);
  void clear_all(std::string_view why);
  /// Emits the clear of an alert of `kind` with the figures it was raised on.
  void clear_as_raised(AlertKind kind, const char* what, std::string_view why, std::int64_t rev,
                       std::int64_t t);
  /// Mean of the newest `blocks` recent blocks (at most kRecentBlocks).
  Block recent_mean(int blocks) const;
  /// Raises a runout change found by the flute forces (per revolution or per block).
  void start_change(ChangeSource source, int flute, int side, std::int64_t onset);

  // Estimates.
  bool read_window(const identify::IdentifiedWindow& w, WindowEstimate& e) const;
  void check_runout_high(const WindowEstimate& e, std::int64_t rev, std::int64_t t);
  /// Counts the newest window into the baseline (its windows are the newest recent ones).
  void add_to_estimate_baseline();
  void finish_estimate_baseline();
  void restart_estimate_baseline();
  void check_estimate_change(const WindowEstimate& e, std::int64_t rev, std::int64_t t);
  void state_change_identified(const WindowEstimate& e, std::int64_t rev, std::int64_t t);
  void check_coefficient_wear(const WindowEstimate& e, std::int64_t rev, std::int64_t t);
  /// The newest recent window, `back` windows back (0: the newest).
  [[nodiscard]] const WindowEstimate& recent_window(int back) const;

  Alert* emit(AlertKind kind, AlertSeverity severity, bool active, std::int64_t revolution,
              std::int64_t utime_us, double value, double threshold, std::string_view quantity);
  template <typename Sink>
  void flush(Sink&& sink) {
    for (int i = 0; i < pending_count_; ++i) {
      sink(static_cast<const Alert&>(pending_[static_cast<std::size_t>(i)]));
    }
    pending_count_ = 0;
  }

  AlertConfig config_;
  double breakage_z_ = 0.0;  // z of the per-revolution breakage bound (per flute count)
  Level runout_, breakage_, sensor_;
  // The flute forces' runout level, whoever leads runout: raised after persist_revolutions
  // above the limit, down after as many below hysteresis × the limit (runs saturate there), and
  // the I of the last revolution that completed either run.
  bool imbalance_high_ = false;
  int imbalance_above_run_ = 0, imbalance_below_run_ = 0;
  double imbalance_above_ = 0.0, imbalance_below_ = 0.0;
  int breakage_flute_ = 0;

  // Baseline: flute forces of its revolutions, [revolution·kMaxFlutes + flute].
  Baseline baseline_;
  int flutes_ = 0;
  int baseline_count_ = 0;
  std::vector<double> baseline_force_N_;
  std::vector<double> baseline_rpm_;  // the baseline's revolutions' speeds (0: not known)
  bool reforming_ = false;            // a new baseline forms at another speed
  std::int64_t held_revolutions_ = 0;
  std::vector<double> series_, scratch_, block_medians_;
  bool rebaselined_ = false;
  // By AlertKind (kRunout 1 … kSensor 5): the newest raise of each kind.
  std::array<Raised, static_cast<std::size_t>(AlertKind::kSensor) + 1> raised_{};

  // The block being filled: shares [flute·B + i] and mean force [kMaxFlutes·B + i].
  std::vector<double> block_values_;
  int block_count_ = 0;
  std::array<Block, kRecentBlocks> recent_{};
  int recent_next_ = 0;
  int recent_count_ = 0;

  // Runout change: per flute, an upward and a downward CUSUM and the clearing CUSUM.
  std::array<Cusum, kMaxFlutes> change_up_{}, change_down_{};
  Cusum change_clear_;
  bool change_active_ = false;
  ChangeSource change_source_ = ChangeSource::kBlock;
  int change_flute_ = 0;
  int change_side_ = 1;
  std::int64_t change_onset_ = 0;  // first revolution of the change (estimated)
  bool change_identify_ = false;   // the follow-up with the estimates is due
  // Per-revolution detector: the last revolutions' shares, and per flute the run beyond limit.
  std::array<std::array<double, kMaxFlutes>, kStepRevolutions> step_shares_{};
  int step_next_ = 0;
  std::array<int, kMaxFlutes> step_streak_{}, step_side_{};
  double step_z_ = 0.0;
  // Wear drift: raise and clear CUSUMs.
  Cusum wear_raise_, wear_clear_;
  bool wear_active_ = false;
  bool wear_from_estimates_ = false;

  // Estimates.
  bool estimates_ = false;  // a fitted window has arrived: runout and wear follow the estimates
  bool estimates_expected_ = false;
  [[nodiscard]] bool follow_estimates() const { return estimates_ || estimates_expected_; }
  std::int64_t last_window_ = -1;
  std::int64_t last_revolution_ = -1, last_utime_us_ = 0;  // −1: no revolution yet
  std::array<double, kRecentRevolutions> recent_rpm_{};
  std::array<std::int64_t, kRecentRevolutions> recent_rpm_revolution_{};
  EstimateBaseline estimate_base_;
  std::array<WindowEstimate, kRecentWindows> windows_{};  // ring of the recent windows
  int windows_next_ = 0;
  int windows_count_ = 0;
  int estimate_base_count_ = 0;  // windows gathered towards the estimates' baseline
  std::array<double, kRecentWindows> estimate_series_{}, estimate_scratch_{};
  double window_z_ = 0.0;  // z of the per-window runout-change bound
  std::array<int, kMaxFlutes> window_streak_{}, window_side_{};
  int window_clear_streak_ = 0;
  bool runout_first_known_ = false;
  double runout_first_ratio_ = 0.0;  // u of the first fitted window (the runout text's "before")
  std::array<Cusum, kMaxCoefficients> coefficient_raise_{};
  Cusum coefficient_clear_;
  int wear_coefficient_ = 0;

  std::int64_t last_bad_ = 0, last_samples_ = 0, last_gaps_ = 0;
  int dead_channel_ = -1;
  int dead_channel_said_ = -1;  // the dead channel the active sensor alert names (-1: none)
  double dead_range_ratio_ = 0.0;
  double dead_range_limit_ = 0.0;
  SensorCause sensor_cause_ = SensorCause::kBadSamples;  // what raised the active sensor alert
  std::array<Alert, 8> pending_{};
  int pending_count_ = 0;
};

}  // namespace millwatch::monitor
