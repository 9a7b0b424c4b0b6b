#pragma once
// What a replay keeps of a run beyond its summary, for people to read and plot: one row per
// revolution (written as it comes to `--revolutions FILE`, CSV or JSON Lines), the spindle speed
// over time, the last revolution-synchronous average (measured and model) and the raw force's
// spectrum. It observes the pipeline (a PipelineSink beside the summary's) and the raw blocks.
//
// A revolution's row: revolution, t_s, spindle_rpm, valid, cutting, each flute's period_s,
// alpha_deg, each flute's peak fx, fy, fz and resultant (N), delta_fy_N, residual_rms_N per axis
// (empty while the model is not aligned), alerts (the kinds active, separated by ';'). Periods,
// α and ΔFy are empty unless the revolution is valid (every tooth event found); the peaks unless
// its bounds (both CE1 events) were found — what the summary averages.

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "core/monitor/pipeline.hpp"
#include "shell/output_file.hpp"

namespace millwatch::shell {

class RunRecorder : public monitor::PipelineSink {
 public:
  /// A revolution as plotted (the subset kept in memory).
  struct Row {
    std::int64_t revolution = 0;
    double t_s = 0.0;
    double spindle_rpm = 0.0;
    bool valid = false;    ///< every tooth event found: α and ΔFy
    bool bounded = false;  ///< both CE1 events found: the peaks
    double alpha_deg = 0.0;
    double delta_fy_N = 0.0;
    std::array<double, monitor::kMaxFlutes> peak_resultant_N{};
  };
  struct SpindlePoint {
    double t_s = 0.0;
    double rpm = 0.0;
  };
  /// The last synchronous average: bins × (fx, fy, fz) measured and model.
  struct SyncSnapshot {
    std::int64_t revolution = 0;
    int window_revolutions = 0;
    bool model_valid = false;
    std::array<std::vector<double>, 3> measured, model;
  };

  /// @param revolutions_path where the rows go ("" none; .jsonl: JSON Lines, else CSV)
  /// @param keep_for_plots keep rows, speeds, the average and raw samples in memory
  RunRecorder(int flutes, const std::filesystem::path& revolutions_path, bool keep_for_plots);

  void on_revolution(const monitor::RevolutionRecord& r) override;
  void on_spindle(const monitor::SpindleUpdate& u) override;
  void on_sync_average(const monitor::SyncAverage& measured, const monitor::Lockstep* model,
                       std::int64_t revolution, std::int64_t utime_us) override;
  void on_alert(const monitor::Alert& a) override;
  void on_event(const monitor::PipelineEvent& e) override;
  /// The raw samples of a block (kept for the spectrum: the first kSpectrumSamples).
  void add_samples(const monitor::SampleBlock& b);
  /// Completes the revolution file. @throws std::runtime_error naming it.
  void commit();

  static constexpr std::size_t kSpectrumSamples = std::size_t{1} << 20;
  [[nodiscard]] const std::vector<Row>& rows() const { return rows_; }
  [[nodiscard]] const std::vector<SpindlePoint>& spindle() const { return spindle_; }
  [[nodiscard]] const SyncSnapshot& sync() const { return sync_; }
  [[nodiscard]] const std::array<std::vector<double>, 3>& raw() const { return raw_; }
  [[nodiscard]] double raw_rate_hz() const { return raw_rate_hz_; }
  [[nodiscard]] int flutes() const { return flutes_; }
  [[nodiscard]] std::int64_t rows_written() const { return written_; }

 private:
  void write_header();
  std::string active_alerts() const;

  int flutes_;
  bool jsonl_ = false;
  bool keep_;
  std::unique_ptr<OutputFile> file_;
  std::int64_t written_ = 0;
  std::string line_;  // scratch
  std::vector<Row> rows_;
  std::size_t stride_ = 1;  // rows kept: every stride_-th (halved when too many)
  std::vector<SpindlePoint> spindle_;
  SyncSnapshot sync_;
  std::array<std::vector<double>, 3> raw_;
  double raw_rate_hz_ = 0.0;
  bool raw_done_ = false;
  std::array<bool, 8> active_{};  // by AlertKind
  bool cutting_ = true;
  std::int64_t lock_ = 0;       // the locks so far (kLockAcquired): the row's lock
  std::int64_t labelling_ = 0;  // the flutes' relabellings so far (kFlutesRelabelled)
};

}  // namespace millwatch::shell
