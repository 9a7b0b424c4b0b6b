#pragma once
// Simulates a dynamometer recording of a cut with known truth.
//
// Per spindle revolution the model's periodic steady state at that revolution's conditions
// (speed, feed, runout, flank wear, coefficient drift; model/steady_state.hpp, dynamometer
// resonance included) gives the force on the tool over the spindle angle. When accumulation makes
// the force repeat only every L revolutions, revolution n plays revolution n mod L of that cycle
// (so skipped passes and their sub-harmonics are in the record); the model is evaluated again only
// when the conditions change. Each sample takes the force at the spindle angle of its time
// (SpindleProfile) and passes it through the measurement chain:
//   axis map to the dynamometer's reading (a dynamometer under the workpiece reads −F),
//   + charge-amplifier drift + mains hum + white noise, then ADC clipping and quantisation.
// The feed rate is fixed by the commanded speed (f_t·N_z·n_cmd, as model::at_actual_speed), so a
// spindle running faster than commanded cuts thinner chips. A stop/start is a feed hold: no
// cutting from the start of the deceleration until the spindle is back at speed. A change of
// conditions takes effect at once, without a transient (each revolution is a steady state).
//
// Samples come in blocks (next_block); apart from the truth list (reserved for the record's
// expected revolutions) nothing is allocated once constructed, except when new conditions give
// an accumulation cycle of a length not met before (the evaluator plans its FFT then).

#include <array>
#include <cstdint>
#include <random>
#include <span>
#include <vector>

#include "core/model/steady_state.hpp"
#include "core/sim/channel_stats.hpp"
#include "core/sim/scenario.hpp"
#include "core/sim/spindle_profile.hpp"

namespace millwatch::sim {

/// What the simulator used for one revolution: the truth a test or the sidecar reports.
struct RevolutionTruth {
  double start_s = 0.0;            ///< time of the revolution's first sample
  double spindle_rpm = 0.0;        ///< actual speed then
  double feed_per_tooth_um = 0.0;  ///< actual chip load from the fixed feed rate
  double runout_offset_um = 0.0;
  double runout_angle_rad = 0.0;
  std::vector<double> wear_um;      ///< per flute
  double coefficient_factor = 1.0;  ///< every force coefficient × this (coefficient drift)
  bool cutting = true;
  /// Played from a cut cycle (PlayedSteadyStates::cycles_cut) round again: its revolution
  /// n mod kMaxCycleRevolutions, not the model's revolution n.
  bool round_again = false;
};

/// What the model's steady states played so far were like (model::SteadyState and its stats),
/// over the simulator's evaluations (one per change of conditions: a ramp's speed, runout, wear).
struct PlayedSteadyStates {
  int evaluations = 0;
  /// Evaluations whose cycle (the least common multiple of the slots' periods) exceeded
  /// model::kMaxCycleRevolutions: a record that long plays its first revolutions round again,
  /// each exact, the seam not (SteadyState::cycle_exact false; RevolutionTruth::round_again).
  int cycles_cut = 0;
  int longest_cycle_revolutions = 0;  ///< as played (at most kMaxCycleRevolutions)
  /// Slots that did not repeat within model::kMaxSlotRevolutions (their state there is
  /// played), the most in one evaluation, and the slots of that evaluation.
  int unsettled_slots = 0;
  int slots = 0;
};

class CutSimulator {
 public:
  /// @throws config::ConfigError / std::invalid_argument for an inconsistent scenario.
  explicit CutSimulator(const Scenario& scenario);

  [[nodiscard]] std::int64_t total_samples() const { return total_samples_; }
  [[nodiscard]] std::int64_t samples_done() const { return next_sample_; }

  /// Fills up to out.size() samples of each channel (dynamometer reading, N) and their times;
  /// returns how many (0 at the end of the record).
  std::size_t next_block(std::span<double> time_s, std::span<double> fx_N, std::span<double> fy_N,
                         std::span<double> fz_N);

  /// One entry per revolution (index = revolution number), including the one prepared ahead.
  [[nodiscard]] const std::vector<RevolutionTruth>& truth() const { return truth_; }

  /// The noise-free force on the tool (model frame) of the last sample produced, for tests.
  [[nodiscard]] const std::array<double, 3>& last_clean_force_N() const { return last_clean_; }
  /// Statistics of the noise-free force on the tool over every sample produced so far.
  [[nodiscard]] const ChannelStats& clean_stats() const { return clean_stats_; }
  /// The model's steady states played so far.
  [[nodiscard]] const PlayedSteadyStates& played_steady_states() const { return played_; }

 private:
  /// Sets the configuration to the conditions at start_s (speed, feed, runout, wear, drift).
  RevolutionTruth configure_revolution(double start_s);
  /// Whether the conditions differ from those of the last evaluation.
  [[nodiscard]] bool conditions_changed() const;
  void advance_revolution(double start_s);
  std::array<double, 3> clean_force(double revolutions) const;
  std::array<double, 3> measure(const std::array<double, 3>& force_N, double time_s);

  Scenario scenario_;
  SpindleProfile spindle_;
  model::ModelConfig config_;  // the current revolution's conditions
  model::SteadyStateWorkspace workspace_;
  PlayedSteadyStates played_;
  model::ModelConfig evaluated_;  // the conditions of the workspace's result
  // Coefficient drift: the current factor, and the one the workspace's result holds. Without
  // deflection the force is linear in the coefficients (the chips, the min-chip regime and the
  // accumulation depend on h alone; the dynamometer is linear): the result at factor 1 is scaled.
  // With deflection (which depends on the force) the coefficients are scaled and re-evaluated.
  double factor_ = 1.0;
  double evaluated_factor_ = 1.0;
  bool scale_result_ = true;
  bool has_result_ = false;
  double feed_rate_um_per_min_ = 0.0;  // f_t·N_z·n_cmd
  std::int64_t total_samples_ = 0;
  std::int64_t next_sample_ = 0;

  // Force waveforms of the current revolution and the next (for interpolation across the
  // boundary), index k at spindle angle 2πk/steps.
  std::array<std::vector<double>, 3> current_, next_;
  long current_revolution_ = -1;
  bool current_cutting_ = true;
  bool next_cutting_ = true;

  std::mt19937_64 rng_;
  std::normal_distribution<double> gauss_{0.0, 1.0};
  std::array<double, 3> hum_phase_rad_{};
  std::array<double, 3> last_clean_{};
  ChannelStats clean_stats_;
  std::vector<RevolutionTruth> truth_;
};

}  // namespace millwatch::sim
