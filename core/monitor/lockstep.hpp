#pragma once
// The model in lockstep with the measurement.
//
// The model's periodic steady state at the measured speed (model::evaluate_steady_state, chip
// load from the commanded feed rate: f_t·n_cmd/n_meas) is the model's force over the spindle
// angle: its mean revolution (skipped passes average out, as in the measured synchronous
// average). It goes through the same low-pass filter as the measured force, as the filter's
// periodic steady state (model::PeriodicResponse: harmonic k of the spindle frequency times
// H(k·f), so the same lag; |H(k·f)|² when the measurement is filtered forwards and backwards) —
// measured and modelled forces are compared like with like. It is aligned to the measurement
// once per lock (and again on a full window of revolutions): correlated circularly with the
// measured revolution-synchronous average, all three axes together; the best shift (refined to
// a fraction of a bin) is the model's angle offset against the tracker's zero. From then on
// each measured sample's angle gives its model sample. Following a new speed re-evaluates the
// steady state and the filter (allocation-free after the first build; 0.16 ms for the plain
// model, 4.3 ms for [000]'s full one: bench/model_benchmark) — the pipeline has it done on
// ModelBuilder's thread and takes the result (take_model()).

#include <array>
#include <cstdint>
#include <vector>

#include "core/model/periodic_response.hpp"
#include "core/model/steady_state.hpp"
#include "core/monitor/sync_average.hpp"
#include "core/signal/butterworth_lowpass.hpp"

namespace millwatch::monitor {

class Lockstep {
 public:
  /// forces_on_line()'s table, a row per model grid point k: fx, fy, fz at k, 0, and their steps
  /// to k + 1 (cyclic), 0 — a sample's interpolation reads one cache line, the values and the
  /// steps each one 256-bit load.
  struct alignas(64) LineRow {
    std::array<double, 8> v;
  };

  Lockstep() = default;
  /// @param model the cut as commanded (process.spindle_rpm is the commanded speed)
  /// @param zero_phase the measurement is filtered forwards and backwards (|H|², no lag)
  Lockstep(const model::ModelConfig& model, const signal::ButterworthDesign& filter,
           bool zero_phase = false);

  /// Evaluates the model's steady revolution at the measured speed and filters it (allocates
  /// at the first build only). Returns whether it was rebuilt (speed changed by more than 0.2 %).
  bool set_spindle_hz(double spindle_hz);
  [[nodiscard]] bool has_model() const { return built_; }
  /// The cut as commanded that the model is built from (the identified parameters once taken).
  [[nodiscard]] const model::ModelConfig& commanded_config() const { return commanded_; }
  /// Builds the model of `commanded` at `spindle_hz` afresh, whatever was built before (a spare
  /// built off the sample thread: ModelBuilder).
  void build(const model::ModelConfig& commanded, double spindle_hz);
  /// Takes `built`'s model — its configuration, speed, waveforms and table — and hands it this
  /// one's (swapped, nothing allocated). The alignment stays this one's (as at a new speed); a
  /// new revision.
  void take_model(Lockstep& built);

  /// Takes an alignment (model angle minus tracker angle, rad) found elsewhere (an identified
  /// fit's); aligned once built.
  void set_alignment(double alignment_rad);

  /// Aligns the model with the measured synchronous average; returns false when there is
  /// nothing to align (no model, empty average).
  bool align(const SyncAverage& measured);
  [[nodiscard]] bool aligned() const { return aligned_; }
  /// Model angle minus tracker angle (rad).
  [[nodiscard]] double offset_rad() const { return offset_rad_; }
  /// Normalised correlation of the alignment (1 = identical shapes).
  [[nodiscard]] double alignment_correlation() const { return correlation_; }

  /// The filtered model force (N, model frame) at a tracker angle (rad, any turn).
  [[nodiscard]] std::array<double, 3> force_at(double tracker_angle_rad) const;
  /// force_at() along a line of tracker angles, angle0_rad + i·step_rad for i < count (step_rad
  /// ≥ 0, less than a turn): row i of `rows` (4 doubles a row, as the sample ring's) takes fx,
  /// fy, fz and fx² + fy². The position on the model's grid advances by a step per sample
  /// instead of a division and a floor each. An AVX kernel where the CPU has it and `allow_avx`
  /// (the tests compare the two: the same rows, bit for bit).
  void forces_on_line(double angle0_rad, double step_rad, std::size_t count, double* rows,
                      bool allow_avx = true) const;
  /// Changes whenever the filtered model or its alignment does (a build, new parameters, an
  /// alignment), from one sequence for the whole process (a copy shares its original's until
  /// either changes): what was measured on the model revolution holds while it stays the same.
  /// 0 until the first build or alignment.
  [[nodiscard]] std::uint64_t revision() const { return revision_; }
  /// The spindle frequency the model was built for (Hz; 0 before the first build).
  [[nodiscard]] double spindle_hz() const { return spindle_hz_; }

  /// The model's revolution (unfiltered), index k at model angle 2πk/steps.
  [[nodiscard]] const model::ForceWaveform& waveform() const { return waveform_; }
  /// The model's revolution filtered (periodic steady state) on `bins` tracker-angle bins.
  void filtered_on_tracker_grid(int axis, int bins, std::vector<double>& out) const;
  [[nodiscard]] const model::ModelConfig& model_config() const { return config_; }
  /// What the evaluation of the model built last did (model::SteadyStateStats): how many of
  /// its slots did not repeat within model::kMaxSlotRevolutions (their state there stands in
  /// the mean revolution) and whether the ploughed areas settled with the deflection. The mean
  /// revolution is exact for a cycle cut at model::kMaxCycleRevolutions (each slot's own
  /// period), so only these say that the model revolution is approximate.
  [[nodiscard]] const model::SteadyStateStats& steady_state_stats() const { return stats_; }

 private:
  void filter_periodic();
  void revise();

  model::ModelConfig commanded_;
  model::ModelConfig config_;
  signal::ButterworthDesign filter_;
  bool zero_phase_ = false;
  model::SteadyStateWorkspace workspace_;
  model::PeriodicResponse response_;
  model::ForceWaveform waveform_;
  std::array<std::vector<double>, 3> filtered_;  // periodic steady-state filtered waveform
  // filtered_ for forces_on_line(), a row per grid point (LineRow).
  std::vector<LineRow> line_table_;
  // Scratch of align(): the model and the measured average on the tracker grid, correlations.
  std::array<std::vector<double>, 3> model_bins_, measured_bins_;
  std::vector<double> correlation_scratch_;
  model::SteadyStateStats stats_;  // of the build the model is
  std::uint64_t revision_ = 0;
  double spindle_hz_ = 0.0;
  double offset_rad_ = 0.0;
  double correlation_ = 0.0;
  bool built_ = false;
  bool aligned_ = false;
};

}  // namespace millwatch::monitor
