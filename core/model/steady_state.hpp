#pragma once
// The model's periodic steady state, evaluated directly: one revolution (or one cycle of a few
// revolutions) of force on the tool for a configuration, with no time marching, no warm-up and
// no hidden history. What identification fits, what the lockstep monitor compares with and what
// the simulator plays.
//
// Same physics as the time-marching MillingModel (milling_model.hpp, [000] Fig. 9 flow: rigid
// chip against the nearest previous pass plus its deficit, deflection [000] eqs 21-24, regimes
// [000] eq 5 / [002] eqs 17-18, accumulation [002] eqs 11-12 / [000] eq 25, projection [000]
// eq 7, discs [000] eqs 1-4, 6, 8), organised differently:
//
//   Slots. Disc i (of K, lag_i = (i + ½)·β/K, [000] eqs 2-4) has immersion slots
//   θ_{i,b} = 2πb/S − lag_i, b = 0..S−1 (S = steps per revolution). Every flute passes every slot
//   once per revolution, in pitch order; flute j's pass of slot b happens at spindle angle
//   φ = 2πb/S + ψ_j (without memory: see "No snapping"). A slot's pass memory (how far each of the
//   last P passes left the surface behind its rigid path: the deflection leftover δh, or "did not
//   cut") is touched by nothing but the passes of that slot, so each slot is solved on its own:
//     from the state of a fresh cut (every earlier pass cut along its rigid path, as
//     MillingModel::reset), its passes are iterated revolution by revolution until the state
//     repeats: after one revolution (a fixed point) or after p revolutions (a cycle: accumulation
//     skipping passes, [002]; deflection against the jump of [000] eq 5 at h_min). With
//     deflection the leftover converges geometrically (factor F_n'/(k + F_n') per pass, close to
//     1 for thin chips), so after the first revolution, and again whenever the pattern of
//     choices (nearest pass, regime, cut or not) repeats, Newton's method on the p-revolution map
//     looks for the exact periodic state (the Jacobian by the chain rule through
//     dh/dh_r = 1/(1 + F_n'(h)/k)); its last step is a plain run from that state with the same
//     pattern, so a success proves itself. Slots without memory (no deflection, no accumulation)
//     need one pass per flute. Converged slots stop; nothing depends on a warm-up.
//   Deflection balance ([000] eq 22 with the flank-wear normal force F_w): the cut chip h of
//     h + (F_n(h) + F_w)/k = h_r. With [000] Table 2's coefficients F_n falls at h_min
//     (K_np·h_min^a_np > K_nc·h_min^a_nc), so near h_min two roots can exist; the evaluator takes
//     the smallest (the tool stops at the first balance it meets going in), whatever a starting
//     guess says. MillingModel takes whichever root its Newton start (the neighbouring step)
//     leads to, so the two differ there; with a single root they agree to its solver tolerance.
//   Cycles. Slot s repeats every p_s revolutions from revolution r_s on; revolution R ≥ r_s of
//   the cut is its phase (R − r_s) mod p_s, counting revolutions from the fresh cut — the same
//   convention as MillingModel's revolutions after reset(), so the evaluator's revolution m of
//   the cycle equals MillingModel's revolution K·L + m for every large enough K. The whole force
//   repeats every L = lcm(p_s) revolutions: the cycle. When L exceeds kMaxCycleRevolutions the
//   cycle holds the first kMaxCycleRevolutions revolutions and `cycle_exact` is false (each is
//   exactly that revolution of the cut; only playing them round again is not). The mean
//   revolution is exact either way: each slot's mean over its own cycle. Skipped passes put
//   frequencies between the spindle harmonics (k·f/L) into the cycle, none into the mean.
//   No snapping. Flute pitches ψ_j (tool.pitch_deg) and runout are used exactly: the geometric
//   chip comes from the same chip tables as MillingModel (chip_geometry.hpp), read at the exact
//   spindle angle less the lag by linear interpolation. Without pass memory (no deflection, no
//   accumulation: the lockstep's and most fits' model) each flute's passes are independent, and
//   each flute gets its own immersion grid, shifted by (ψ_j/Δφ) mod 1 steps so that its passes
//   land exactly on the output grid: exact for any pitch. With memory the flutes must share the
//   slots; flute j's force, computed at the slot immersions, lands at 2πb/S + ψ_j and is linearly
//   interpolated onto the grid (weights (ψ_j/Δφ) mod 1; error O(Δφ²) where the force is smooth,
//   a step smeared over one Δφ at entry and exit). A pitch on the grid (every uniform pitch with
//   S a multiple of N_z) is exact either way, and the force moves continuously with ψ_j.
//   Ploughed area ([001] eqs 14-17, linear law with ploughing "area"): A_c(θ) integrated along
//   each flute's pass by the trapezoidal rule on the rigid chip (eq 14); chip ≥ h_min: A_pMAX,
//   the area at the pass's first crossing of h_min, interpolated between passes (eq 16); below
//   h_min before the pass's largest chip (θ_MAX): A_c(θ) (eq 15); after it: A_c(π) − A_c(θ) with
//   the pass's own total (eq 17). Continuous in every parameter. MillingModel sums rectangles,
//   switches on grid steps and takes the previous contact's total after the first shearing: the
//   same for a rising-falling chip up to O(Δφ), but not under accumulation, whose irregular
//   chips cross h_min early in a pass. With deflection the area and the chips depend on each
//   other: the slots are solved again, each pass's balance using its slot's mean area over the
//   cycle of the previous solution, until the areas settle (at most 6 solutions;
//   SteadyStateStats::area_converged says whether they did).
//   Dynamometer ([001]/[003] resonance, effects.dynamometer): a linear filter, applied as its
//   periodic steady state: harmonic k of the spindle frequency f times H(k·f) (the
//   continuous-time resonance_response(), dynamometer.hpp) by FFT (periodic_response.hpp) — on
//   the mean revolution with f, on the cycle with f/L.
//
// Frame, signs and units: model_config.hpp (forces on the tool, N; x feed, y cross-feed, z tool
// axis). Output index k is spindle angle φ_k = 2πk/S; flute 0's immersion is φ − lag.
//
// Cost and allocation: the workspace is sized once (constructor or reserve(); sizes follow the
// configuration's shape: flutes, discs, passes looked back, steps, which effects have memory).
// evaluate_steady_state() then allocates nothing for a configuration of that shape, except
// (a) the first time a cycle of a given length L > 1 meets the dynamometer (its FFT plan is made
// then and kept), (b) when the slots' cycles together outgrow the record pool reserved for them
// (accumulation with long cycles; the pool keeps its capacity). Configurations without pass
// memory never hit either. What only the configuration's shape and grid fix is kept between
// evaluations: the chip tables while the path (feed, runout, pitch, window) is the same, and the
// immersion grid (cos θ, sin θ and engagement of every disc, flute and slot) while the flutes'
// offsets, the helix lag and the engaged arc are — a fit's trials change runout and
// coefficients, a lockstep rebuild the speed, and neither remakes it.

#include <array>
#include <memory>
#include <span>

#include "core/model/milling_model.hpp"
#include "core/model/model_config.hpp"

namespace millwatch::model {

/// Longest cycle (revolutions) the evaluator materialises; longer ones are cut (cycle_exact false).
inline constexpr int kMaxCycleRevolutions = 64;
/// Longest period (revolutions) one slot may have; a slot that has not repeated within
/// kMaxSlotRevolutions is taken as it stands (counted in SteadyStateStats::unconverged_slots).
inline constexpr int kMaxSlotPeriodRevolutions = 64;
inline constexpr int kMaxSlotRevolutions = 600;

/// The configuration at an actual spindle speed n with the feed rate fixed by the commanded
/// one (the control fixes f_t·N_z·n_cmd, so a spindle running fast cuts thinner chips):
///   process.spindle_rpm = n,  process.feed_per_tooth_um = f_t,cmd · n_cmd / n.
/// What Lockstep::set_spindle_hz and CutSimulator do. Writes into `out` (copy-assigned from
/// `commanded`: no allocation when `out` already holds a configuration of the same shape).
/// @param actual_rpm n > 0. @throws std::invalid_argument otherwise
void at_actual_speed(const ModelConfig& commanded, double actual_rpm, ModelConfig& out);
/// The same, returned by value.
[[nodiscard]] ModelConfig at_actual_speed(const ModelConfig& commanded, double actual_rpm);

/// What one evaluation did (for benchmarks and for judging a result).
struct SteadyStateStats {
  int slots = 0;                          ///< (disc, immersion) slots
  long passes = 0;                        ///< flute passes simulated (iterations and Newton)
  int newton_slots = 0;                   ///< slots whose periodic state Newton's method found
  int longest_transient_revolutions = 0;  ///< revolutions before the latest slot repeated
  int longest_slot_period_revolutions = 1;
  int unconverged_slots = 0;  ///< slots that did not repeat within kMaxSlotRevolutions
  int area_sweeps = 0;        ///< solutions of the slots (> 1: area ↔ deflection coupling)
  /// False when the ploughed areas and the deflection did not settle together within the
  /// sweeps allowed (the last solution is returned).
  bool area_converged = true;
};

/// The periodic steady state of one configuration at one speed.
struct SteadyState {
  double spindle_rpm = 0.0;
  int steps_per_rev = 0;  ///< S
  /// Mean revolution, force on the tool (N), index k at spindle angle 2πk/S. Equal to every
  /// revolution when cycle_revolutions = 1.
  ForceWaveform mean;
  /// L: the force repeats every L revolutions (1 unless accumulation skips passes, or a chip
  /// near h_min settles into a cycle under deflection).
  int cycle_revolutions = 1;
  /// False when the slots' periods have a least common multiple above kMaxCycleRevolutions:
  /// `cycle` then holds revolutions 0..L−1 exactly, but revolution L is not revolution 0 again
  /// (and the dynamometer, applied as if the cycle repeated, is approximate near its ends).
  bool cycle_exact = true;
  /// L·S samples per axis: revolution m of the cycle at [m·S, (m+1)·S). Empty after a
  /// SteadyStateOutput::kMean evaluation.
  ForceWaveform cycle;
  SteadyStateStats stats;

  /// Revolution m (0 ≤ m < L) of the cycle, one axis (0 x, 1 y, 2 z).
  [[nodiscard]] std::span<const double> revolution(int m, int axis) const;
};

/// What evaluate_steady_state() computes: the mean revolution only (the lockstep monitor, a
/// fitter), or the cycle as well (the simulator; costs L revolutions of assembly and an FFT of
/// L·S points with the dynamometer).
enum class SteadyStateOutput { kMean, kMeanAndCycle };

/// Forces the model is linear in, per unit coefficient (see evaluate_force_basis()).
inline constexpr int kMaxBasisColumns = 6;

/// The coefficients the force is linear in for the configuration's law and effects, in
/// evaluate_force_basis()'s column order (parameter_map.hpp names): the law's shearing and edge
/// coefficients, or with [001]'s ploughing area or [000]'s minimum chip thickness the
/// ploughing regime's in place of (or beside) the edge's. A fitter with deflection on, where
/// there is no basis, fits the same set.
[[nodiscard]] std::span<const char* const> linear_coefficient_names(const ModelConfig& config);

struct ForceBasis {
  int columns = 0;
  /// Parameter names (parameter_map.hpp) of the coefficients, e.g. "k_tc_N_per_mm2".
  std::array<const char*, kMaxBasisColumns> names{};
  /// Mean revolution of force (N per unit of the coefficient) for each coefficient.
  std::array<ForceWaveform, kMaxBasisColumns> unit;
  /// What no listed coefficient multiplies (flank-wear rubbing, [002] eq 17's ploughing law), N.
  ForceWaveform offset;
};

/// Preallocated scratch and the last result. One per thread.
class SteadyStateWorkspace {
 public:
  SteadyStateWorkspace();
  /// Sizes the workspace for configurations shaped like `config` on `steps_per_rev` steps.
  SteadyStateWorkspace(const ModelConfig& config, int steps_per_rev);
  ~SteadyStateWorkspace();
  SteadyStateWorkspace(SteadyStateWorkspace&&) noexcept;
  SteadyStateWorkspace& operator=(SteadyStateWorkspace&&) noexcept;
  SteadyStateWorkspace(const SteadyStateWorkspace&) = delete;
  SteadyStateWorkspace& operator=(const SteadyStateWorkspace&) = delete;

  /// Grows the workspace (allocates) to fit `config` on `steps_per_rev` steps; never shrinks.
  /// @throws config::ConfigError for an invalid configuration, std::invalid_argument for steps
  void reserve(const ModelConfig& config, int steps_per_rev);

  /// The last evaluate_steady_state() (or evaluate_force_basis()) result.
  [[nodiscard]] const SteadyState& result() const;

  /// Chip h (µm, after deflection; 0 out of contact) that flute j cut at slot b of the bottom
  /// disc (see "Slots" and "No snapping": with a pitch on the grid, flute j is there at spindle
  /// step b + ψ_j/Δφ, which is MillingModel::chip_um's step) in revolution R ≥ 0
  /// of the steady cut (R counted as in the file comment: revolution m < L is that of the
  /// cycle; every slot repeats with its own period, so any R is defined).
  /// @throws std::out_of_range for a flute or slot outside the last result, or R < 0
  [[nodiscard]] double chip_um(int flute, int slot, long revolution = 0) const;
  /// The rigid chip h_r (µm) of the same pass: against the nearest previous pass plus its
  /// deficit, before deflection (equal to chip_um() without deflection).
  [[nodiscard]] double rigid_chip_um(int flute, int slot, long revolution = 0) const;
  /// Whether that pass removed material (false while it only ploughed, with accumulation).
  [[nodiscard]] bool removed(int flute, int slot, long revolution = 0) const;
  /// Period (revolutions) of slot b of disc i in the last result.
  [[nodiscard]] int slot_period_revolutions(int disc, int slot) const;

 private:
  friend const SteadyState& evaluate_steady_state(const ModelConfig&, double, int,
                                                  SteadyStateWorkspace&, SteadyStateOutput);
  friend const ForceBasis& evaluate_force_basis(const ModelConfig&, double, int,
                                                SteadyStateWorkspace&, bool);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The periodic steady state (see the file comment) of `config` at `spindle_rpm` on a grid of
/// `steps_per_rev` spindle-angle steps. Pure: the result depends on the arguments only.
/// config.process.spindle_rpm and config.resolution are not used (the speed and the grid are
/// the arguments); the feed per tooth is config.process.feed_per_tooth_um as given (use
/// at_actual_speed() for the fixed-feed-rate coupling).
/// @param spindle_rpm n > 0: sets the time scale (dynamometer harmonics at k·n/60 Hz)
/// @param steps_per_rev S ∈ [36, 36000]; any S (a non-uniform pitch need not fall on the grid)
/// @param output the mean revolution only, or the cycle as well
/// @return the workspace's result, valid until its next evaluation
/// @throws config::ConfigError for an invalid configuration (model_config.hpp validate()),
///         std::invalid_argument for a bad speed or step count
const SteadyState& evaluate_steady_state(
    const ModelConfig& config, double spindle_rpm, int steps_per_rev,
    SteadyStateWorkspace& workspace, SteadyStateOutput output = SteadyStateOutput::kMeanAndCycle);

/// Basis waveforms for separable least squares: with the chips fixed, the force is linear in
/// the force law's coefficients,
///   F(φ) = Σ_c K_c·B_c(φ) + B_0(φ)        (mean revolution, dynamometer included, N)
/// linear edge ([002] eq 18): K_tc, K_nc, K_ac, K_te, K_ne, K_ae ("k_tc_N_per_mm2" …
///   "k_ae_N_per_mm"); with ploughing "area" ([001] eqs 18-21) K_tc, K_nc, K_ac, K_tp, K_np,
///   K_ap ("k_tp_N_per_mm3" …). [002] eq 17's ploughing power law below h_min goes to B_0.
/// power law ([000] eq 5): K_tc, K_nc, K_ac, and with min_chip K_tp, K_np, K_ap ("k_tc_Nmm" …),
///   for the exponents in the configuration (each regime its own coefficients).
/// Kronenberg ([003] eqs 7-8): K_s0 ("k_s0_N_per_mm2") for the given m and ratios.
/// B_0 holds flank-wear rubbing and anything else no coefficient multiplies.
/// Valid only when the chips do not depend on the coefficients, i.e. with deflection off (the
/// deflection balance [000] eq 22 makes the chip a function of F_n): a fitter then solves for
/// the coefficients by linear least squares for each trial of the other parameters (variable
/// projection) instead of iterating on them.
/// @throws std::invalid_argument when effects.deflection is on; otherwise as
///         evaluate_steady_state(). With `with_force`, also leaves that evaluation's result
///         (the force at the configured coefficients) in the workspace; without it (a fitter,
///         which needs the basis alone) the result's force is left empty.
const ForceBasis& evaluate_force_basis(const ModelConfig& config, double spindle_rpm,
                                       int steps_per_rev, SteadyStateWorkspace& workspace,
                                       bool with_force = true);

}  // namespace millwatch::model
