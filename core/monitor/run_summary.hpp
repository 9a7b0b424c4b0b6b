#pragma once
// Summary of a monitoring run (a replay, or a daemon's life): what the pipeline measured over
// all its revolutions, and what went wrong. Feed it the pipeline's outputs; to_json() gives the
// replay's summary:
//   samples, duration_s, revolutions (valid), revolutions_measured, revolutions_cutting (the
//   turns while the tracker heard cutting: what every revolution is measured against),
//   spindle_rpm (mean of the revolutions' own speeds), spindle_rpm_commanded, tooth_event,
//   alpha_deg {mean, std}, tooth_period_s [per flute], peak_force_N {fx, fy, fz, resultant: per
//   flute} (each with its revolution-to-revolution spread: tooth_period_s_std, peak_force_N_std),
//   delta_fy_N, residual_rms_N {fx, fy, fz, measured}, alerts [...], dropped_samples,
//   warnings [...]
// and more detail (model features, counters) beside them. Every number is finite or null, and
// every null has a warning that says why.

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/monitor/pipeline.hpp"

namespace millwatch::monitor {

class RunSummary {
 public:
  explicit RunSummary(const MonitorConfig& config);

  void add(const RevolutionRecord& r);
  void add(const SpindleUpdate& u);
  void add(const Alert& a);
  void add(const PipelineEvent& e);
  /// The pipeline's final status (counters, samples).
  void finish(const PipelineStatus& status);
  /// The configuration changed on a reload (from revolution `revolution`, at `utime_us`): the
  /// summary states the new cut as commanded; a tool with another number of flutes starts α,
  /// the periods, peaks, ΔFy and residuals afresh (one tool's flutes are not another's), with a
  /// warning saying so.
  /// `samples_before`: the samples taken before it (the pipelines' replaced), at the old rate —
  /// the summary's duration sums each rate's samples at their own rate.
  void reconfigure(const MonitorConfig& config, std::int64_t revolution, std::int64_t utime_us,
                   std::int64_t samples_before = 0);
  /// The last identified window: {"runout", "coefficients", "fit"} (identify::to_json).
  void set_identification(nlohmann::json identification) {
    identification_ = std::move(identification);
  }

  /// Identification does not run, and why (e.g. "--no-identify"; empty: it runs): the summary
  /// then says it was off, not that the record was too short for a window.
  void set_identification_off(std::string why) { identification_off_ = std::move(why); }

  /// A warning from outside the pipeline (a shell's: a configured rate the recording set aside),
  /// stated after the pipeline's own and counted as none of them (it explains no absent value).
  void note(std::string kind, std::string detail, std::int64_t utime_us) {
    notes_.push_back({std::move(kind), 1, 0, utime_us, std::move(detail)});
  }

  [[nodiscard]] nlohmann::json to_json() const;
  [[nodiscard]] std::int64_t valid_revolutions() const { return valid_; }
  [[nodiscard]] const MonitorConfig& config() const { return config_; }

 private:
  struct Running {
    double sum = 0.0;
    double sum_sq = 0.0;
    std::int64_t n = 0;
    void add(double v) {
      sum += v;
      sum_sq += v * v;
      ++n;
    }
    void merge(const Running& o) {
      sum += o.sum;
      sum_sq += o.sum_sq;
      n += o.n;
    }
    [[nodiscard]] double mean() const;
    [[nodiscard]] double stddev() const;
    [[nodiscard]] double rms() const;
  };
  /// What the flutes' labelling names: α, ΔFy (measured and the model's), each flute's tooth
  /// period and peaks.
  struct FluteStatistics {
    Running alpha, delta_fy, model_alpha, model_delta_fy;
    std::array<Running, kMaxFlutes> period{};
    std::array<std::array<Running, 3>, kMaxFlutes> peak{};
    std::array<Running, kMaxFlutes> peak_resultant{};
    void merge(const FluteStatistics& o);
  };
  struct Warning {
    std::string kind;
    std::int64_t occurrences = 0;
    std::int64_t samples = 0;
    std::int64_t first_utime_us = 0;
    std::string detail;
  };

  MonitorConfig config_;
  int flutes_ = 0;
  std::int64_t revolutions_ = 0;
  std::int64_t valid_ = 0;
  std::int64_t bounded_ = 0;
  Running rpm_, tracker_rpm_;
  std::int64_t first_revolution_utime_us_ = 0, last_revolution_utime_us_ = 0;
  // The flute statistics of the locks before the current one, and of the current one: a
  // relabelling (kFlutesRelabelled) leaves the current lock's out (its flutes named from
  // another CE1), not the earlier locks'. The valid revolutions left out so far.
  FluteStatistics kept_, since_lock_;
  std::int64_t relabelled_out_ = 0;
  std::array<Running, 3> residual_{};
  Running measured_rms_;
  std::vector<nlohmann::json> alerts_;
  std::vector<Warning> warnings_;
  void warn(const std::string& kind, const std::string& detail) const;
  /// The flute statistics of the whole record (those kept and the current lock's).
  [[nodiscard]] FluteStatistics flute_statistics() const;
  /// Warns when another flute than CE1 holds the larger force over the record.
  void warn_flute_labelling(const FluteStatistics& f) const;
  mutable std::vector<Warning> derived_;  // warnings to_json() adds for absent values
  std::vector<Warning> notes_;            // note()'s
  // Before the last reload that changed the rate: the samples and their duration at theirs.
  std::int64_t samples_at_rate_change_ = 0;
  double duration_before_s_ = 0.0;
  PipelineStatus status_;
  nlohmann::json identification_;  // null until a window is fitted
  std::string identification_off_;
};

}  // namespace millwatch::monitor
