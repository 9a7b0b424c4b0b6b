#pragma once
// Tool-state alerts from the per-revolution records and the input counters, with a stated
// false-alarm rate.
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
// Detectors (each raised once and cleared once; ARL₀ = `false_alarm_revolutions` per detector,
// i.e. at most one false alarm per ARL₀ revolutions of an unchanged cut):
//  runout         I of a revolution above `runout_imbalance` for `persist_revolutions`; cleared
//                 below `hysteresis`·limit for as long. A level alarm: its rate is not a design
//                 figure.
//  runout change  per block of B revolutions, each flute's block-median share s̃_j against the
//                 baseline: a two-sided CUSUM of z = (s̃_j − μ_j)/σ_b,j with allowance
//                   k_j = max(cusum_k, runout_change_min/(2σ_b,j)) + baseline_margin/√n_b
//                 (changes below runout_change_min/2 never accumulate; the last term covers the
//                 baseline mean's own error up to `baseline_margin` standard errors) and
//                 threshold h_j from Siegmund's ARL at k_j without the margin term, for ARL₀/B
//                 blocks shared by both sides and the flutes (one detector for 2 flutes, whose
//                 shares are ± each other; one per flute for more). A CUSUM above h_j is
//                 confirmed on the excursion's blocks after its first (which may straddle the
//                 change): their mean must lie beyond the allowance k_j·σ_b,j, and is the "after"
//                 of the text. Cleared when a CUSUM of (hysteresis·k_j·σ_b,j − d)/σ_b,j, d the
//                 deviation in the raised direction, with allowance cusum_k exceeds h_j.
//  wear drift     per block, the rise r = M̃/μ_M − 1 of the block-median mean flute force: a
//                 one-sided CUSUM of (r − wear_increase)/σ_r with allowance cusum_k + margin
//                 term and h for ARL₀/B blocks while the true rise is at most the limit,
//                 confirmed as above (the mean rise over those blocks must exceed the limit);
//                 cleared by the mirror CUSUM of (hysteresis·wear_increase − r)/σ_r.
//  breakage       per revolution, a flute's strength relative to its baseline strength,
//                 q_j = g_j/ĝ_j, below τ_j = min(breakage_fraction, 1 − z·σ_q,j) for
//                 `persist_revolutions`, with P(Z > z) = 1/(ARL₀·flutes) (Gaussian bound on a
//                 single revolution; persistence only lowers the rate); cleared above
//                 τ_j/hysteresis for as long.
//  sensor         saturated or non-finite samples above `sensor_bad_fraction` of the samples of a
//                 status interval, or gaps in the stream; cleared at the first clean interval.
// Severity: breakage is an alarm, the others warnings, clears are info. rebaseline() forgets
// the baseline (a new tool) and clears the change alerts at the next revolution.
//
// Alert fields: runout value = I, threshold = the limit; runout change value = I after the
// change (the confirming blocks' mean), threshold = the baseline's I; wear drift value = r after
// (likewise), threshold = the limit; breakage value = q_j of the weakest flute, threshold = τ_j.
// Everything is allocated at construction; examining a revolution allocates nothing.

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "core/monitor/change_detector.hpp"
#include "core/monitor/revolution_features.hpp"

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
  double sigma_floor = 0.001;    ///< least σ of a block share or rise (fraction of the mean)
  /// Least relevant change of a flute's share of the mean flute force (2 flutes: the imbalance
  /// changes by twice this); 0 = any statistically detectable change.
  double runout_change_min = 0.02;
  double wear_increase = 0.15;     ///< limit of the mean flute force's rise over its baseline
  double breakage_fraction = 0.3;  ///< a flute below this of its baseline strength is broken
  double sensor_bad_fraction = 0.001;
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
  /// Examines the input counters since the previous call.
  template <typename Sink>
  void on_input(const InputCounters& c, std::int64_t utime_us, Sink&& sink) {
    examine(c, utime_us);
    flush(sink);
  }
  /// Forget the baseline (a new tool, a reconfiguration); active runout change, wear drift and
  /// breakage alerts are cleared at the next revolution.
  void rebaseline();

  /// The baseline, once complete (for tests and diagnostics).
  struct Baseline {
    bool ready = false;
    int flutes = 0;
    double mean_force_N = 0.0;                          ///< μ_M, median of M
    double rise_sigma = 0.0;                            ///< σ_r of a block's relative rise
    std::array<double, kMaxFlutes> share{};             ///< μ_j, median of s_j
    std::array<double, kMaxFlutes> share_sigma{};       ///< σ_b,j of a block-median share
    std::array<double, kMaxFlutes> strength{};          ///< ĝ_j, median of g_j
    std::array<double, kMaxFlutes> breakage_limit{};    ///< τ_j
    std::array<double, kMaxFlutes> change_allowance{};  ///< k_j
    std::array<double, kMaxFlutes> change_threshold{};  ///< h_j
    double wear_allowance = 0.0;
    double wear_threshold = 0.0;
  };
  [[nodiscard]] const Baseline& baseline() const { return baseline_; }

 private:
  struct Level {
    bool active = false;
    int streak = 0;
  };
  struct Flutes {
    int count = 0;
    std::array<double, kMaxFlutes> force_N{};
    double mean_N = 0.0;
    double imbalance = 0.0;
  };
  struct Block {
    std::array<double, kMaxFlutes> share{};
    double mean_N = 0.0;
  };
  static constexpr int kRecentBlocks = 64;

  void examine(const RevolutionRecord& r);
  void examine(const InputCounters& c, std::int64_t utime_us);
  void check_runout(const Flutes& f, std::int64_t rev, std::int64_t t);
  void check_breakage(const Flutes& f, std::int64_t rev, std::int64_t t);
  void add_to_baseline(const Flutes& f);
  void finish_baseline();
  void add_to_block(const Flutes& f, std::int64_t rev, std::int64_t t);
  void check_runout_change(const Block& b, std::int64_t rev, std::int64_t t);
  void check_wear(const Block& b, std::int64_t rev, std::int64_t t);
  void clear_after_rebaseline(std::int64_t rev, std::int64_t t);
  /// Mean of the newest `blocks` recent blocks (at most kRecentBlocks).
  Block recent_mean(int blocks) const;
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
  int breakage_flute_ = 0;

  // Baseline: flute forces of its revolutions, [revolution·kMaxFlutes + flute].
  Baseline baseline_;
  int flutes_ = 0;
  int baseline_count_ = 0;
  std::vector<double> baseline_force_N_;
  std::vector<double> series_, scratch_, block_medians_;
  bool rebaselined_ = false;

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
  int change_flute_ = 0;
  int change_side_ = 1;
  // Wear drift: raise and clear CUSUMs.
  Cusum wear_raise_, wear_clear_;
  bool wear_active_ = false;

  std::int64_t last_bad_ = 0, last_samples_ = 0, last_gaps_ = 0;
  std::array<Alert, 8> pending_{};
  int pending_count_ = 0;
};

}  // namespace millwatch::monitor
