#pragma once
// Batch calibration across cuts (`millwatch calibrate`): one set of force-law coefficients and
// one runout for a feed sweep with one tool in one clamping ([000] Sect. 5, [001] Table 4).
//
//   CutWindows collect;                        // a PipelineSink: the monitor's windows of a cut
//   ... run monitor::Pipeline over the recording with it ...
//   cuts.push_back({name, commanded, filter, collect.windows});
//   CalibrationResult r = calibrate(cuts, {.tared = false});
//   nlohmann::json preset = material_preset(r, provenance);
//
// Per cut, the monitor's revolution-synchronous windows (30 revolutions each, every one of them
// from revolutions whose tooth events were found) are averaged into one revolution, weighted by
// revolutions: each window is first turned onto the cut's first window (its tracker zero may
// move when the lock is lost and found again) by the rotation that best matches their harmonics;
// windows whose speed is off the cut's median by more than max_speed_change are left out (not
// steady; counted). Then fit_cuts (window_fit.hpp) fits every cut at once, and the classic
// average-force regression (average_force_regression.hpp) runs on the same cuts' mean forces.
//
// The mean force (harmonic k = 0) joins the fit only when the channels are tared (`tared`):
// otherwise the charge amplifiers' offset would be read as force. The classic regression has
// nothing but the mean, so it is computed either way and says that it needs tared channels.

#include <array>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/identify/average_force_regression.hpp"
#include "core/identify/window_fit.hpp"
#include "core/monitor/pipeline.hpp"

namespace millwatch::identify {

/// Collects a cut's synchronous-average windows and each window's mean speed (the revolutions'
/// measured speeds since the previous window), as ShellSink hands them to the identifier.
class CutWindows : public monitor::PipelineSink {
 public:
  void on_revolution(const monitor::RevolutionRecord& r) override;
  void on_sync_average(const monitor::SyncAverage& measured, const monitor::Lockstep* model,
                       std::int64_t revolution, std::int64_t utime_us) override;
  [[nodiscard]] const std::vector<MeasuredRevolution>& windows() const { return windows_; }
  /// Revolutions the monitor measured (a cut shorter than one window has some, but no window).
  [[nodiscard]] std::int64_t revolutions() const { return revolutions_; }

 private:
  std::vector<MeasuredRevolution> windows_;
  double rpm_sum_ = 0.0;
  int rpm_count_ = 0;
  std::int64_t revolutions_ = 0;
};

/// A cut's windows averaged into one revolution.
struct WindowAverage {
  MeasuredRevolution revolution;
  int windows_used = 0;
  int windows_left_out = 0;       ///< off the median speed (not steady)
  double largest_turn_rad = 0.0;  ///< the largest rotation a window needed onto the first
};

/// @param max_speed_change relative speed change from the median that leaves a window out
/// @throws std::invalid_argument for no window, or windows on different grids
WindowAverage average_windows(const std::vector<MeasuredRevolution>& windows,
                              double max_speed_change = 0.005);

struct CalibrationCut {
  std::string name;          ///< for messages and the provenance (e.g. the file)
  model::ModelConfig model;  ///< as commanded: this cut's feed per tooth, speed, engagement
  FilterResponse filter;     ///< the measurement's filter (causal H, or |H|² for zero phase)
  std::vector<MeasuredRevolution> windows;
};

/// Starts a calibration refines at least (a window fit: 2), its minima compared
/// (FitOptions::competing_minima). On PHM 2010's cut 158 four other starts of the eight end in
/// distinct minima within the noise of each other.
inline constexpr int kCalibrationRefinedStarts = 8;

struct CalibrationOptions {
  /// fit.use_mean is set from `tared`; a coefficient_floor of 0 becomes 0.005 (absolute
  /// values: window_fit.hpp); fit.refined_starts at least kCalibrationRefinedStarts and
  /// fit.competing_minima on
  FitOptions fit;
  bool tared = false;  ///< the channels were tared before each cut: fit the mean too
  double max_speed_change = 0.005;
  /// The share of the force's variance the joint fit may leave unexplained before the result
  /// warns that the model does not describe the cuts (identification.max_unexplained's).
  double max_unexplained_variance = 0.2;
};

/// What the calibration says about one cut.
struct CalibratedCut {
  std::string name;
  double feed_per_tooth_um = 0.0;  ///< commanded
  double chip_load_um = 0.0;       ///< actual: commanded f_t · n_cmd / n
  double spindle_rpm = 0.0;        ///< measured (the windows' mean)
  int revolutions = 0;             ///< averaged
  int windows = 0;
  int windows_left_out = 0;
  std::array<double, 3> mean_force_N{};  ///< per revolution, model frame (offset included)
  CutFitQuality fit;
};

struct CalibrationResult {
  bool ok = false;
  std::string message;
  bool tared = false;
  JointFitResult joint;
  std::vector<CalibratedCut> cuts;
  AverageForceRegression classic;
  /// Why the coefficients are not the material's, one sentence each (calibration_warnings()),
  /// then each cut the joint fit leaves more than max_unexplained_variance of unexplained
  /// (of several cuts; "cut NAME: …").
  std::vector<std::string> warnings;
};

/// What makes a joint fit's coefficients unfit for a material preset: the fit leaves more of the
/// force's variance unexplained than max_unexplained_variance (the model does not describe the
/// cuts), or a tangential or normal coefficient (k_t…, k_n…) lies below zero by more than 2σ —
/// a force pulling the tool into the cut, the fit standing in for what the model lacks.
std::vector<std::string> calibration_warnings(const FitResult& fit,
                                              double max_unexplained_variance);

/// @throws std::invalid_argument naming the cut: no window, or a tool, law or effects that
///         differ from the first cut's
CalibrationResult calibrate(const std::vector<CalibrationCut>& cuts,
                            const CalibrationOptions& options = {});

/// The calibration as `millwatch calibrate --json` prints it: "coefficients" {name: {value,
/// std, classic, classic_std}}, "runout" (as the replay summary's), "cuts" [per cut: file, feeds,
/// speed, revolutions, fit quality], "classic" (lines, note), "fit", "warnings" [sentences].
/// Every number finite or null.
nlohmann::json to_json(const CalibrationResult& result);

/// The material preset: {"format": "millwatch-material/1", "material": {the model
/// configuration's "material" section with the fitted coefficients}, "coefficients" {σ, for
/// information}, "runout" {…, information only: the monitor identifies it on every window},
/// "fit", "warnings" (calibration_warnings(), empty when none), "provenance"}. The replay and the
/// daemon take its "material" (README, "Calibration").
nlohmann::json material_preset(const CalibrationResult& result, const std::string& material_name,
                               const nlohmann::json& provenance);

}  // namespace millwatch::identify
