#pragma once
// Where model and measurement disagree, which effect is missing, and the gap shrinking as it is
// added (millwatch issue 8).
//
// The record. The force on the tool (model frame) per axis, uniformly sampled, over a steady cut
// at one commanded speed. The model's time base is the spindle angle φ(t) = 2π·n·t/60 with n the
// speed the current model assumes (the commanded one until spindle_speed_error is added).
//
// One residual for every candidate. The full model of the record is
//   y_a(t) = m_a(φ(t) + δ) + c_a(t) + noise,
// m the model's periodic steady state (model::evaluate_steady_state, its accumulation cycle
// included: revolution m of an L-revolution cycle at revolution m of the record, the cycle's
// phase fitted), band-limited to [0, band], δ the alignment; c the measurement chain: a constant
// per axis always, and what the chain candidates add (drift, hum). The model part is fitted by
// identify::WindowFitter to the synchronous harmonics of y − c (in the spindle-harmonic domain,
// the fitter's own separable least squares; the filter a brick wall at the band); the chain part
// by linear least squares on y − m. The residual r = y − m − c is compared in the record's
// spectrum over (0, band] (record_spectrum.hpp): M bins, 2M real values per axis — the effective
// number of independent samples of a signal low-passed at the band, 2·f_c·T. Every candidate is
// scored on this residual, so the criteria compare.
//
// The criterion. BIC = Σ_axes n_a·ln(σ̂_a²) + p·ln(Σ n_a), n_a = 2M, σ̂_a² the residual's mean
// square over the band, p the free parameters (force coefficients, alignment, each added effect's
// parameters, the chain's terms). A candidate must lower it by `significance` (10: "very strong"
// evidence on Kass and Raftery's scale) to be added.
//
// The loop (issue 8, item 3). From the starting model: score every candidate of the catalogue
// (catalogue.hpp) not yet in the model — add it, refit, criterion —; add the best when it gains
// at least `significance` over the current model; repeat. Stop when the residual is at the noise
// floor (within floor_tolerance on every axis), when no candidate gains enough, or after
// max_steps. The winner's margin over the runner-up (ΔBIC) says how strongly the data prefer it.
//
// Time-varying candidates: tool_wear (the flank wear's rubbing force growing linearly over the
// record) and runout_change (the record cut in two where the synchronous pattern changes most,
// each side fitted on its own).
//
// Localisation (issue 8, item 1), per model along the way: by flute (the synchronous residual
// over each flute's pitch sector), by angle (entry/exit against the middle of the engagement),
// by frequency band (low frequency, mains, spindle harmonics, tooth-passing harmonics, the
// dynamometer's resonance band, lines between the spindle harmonics, broadband), by time
// (segments of the record). Each band carries the noise's share so an excess is visible.
//
// Runs offline (allocates freely); deterministic.

#include <array>
#include <functional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/model/model_config.hpp"

namespace millwatch::diagnose {

/// A recorded cut: the force on the tool in the model frame (N), uniformly sampled.
struct CutRecord {
  double sample_rate_hz = 0.0;
  std::array<std::vector<double>, 2> force_N;  ///< fx, fy
};

struct DiagnoseOptions {
  /// Upper end of the compared band (Hz); 0: 0.4·fs, at most 10 kHz.
  double band_hz = 0.0;
  double significance = 10.0;    ///< ΔBIC an effect must gain to be added
  double floor_tolerance = 1.1;  ///< residual ≤ this × noise floor on every axis: at the floor
  int max_steps = 10;            ///< effects added at most
  int steps_per_rev = 720;       ///< the fitted model's angle grid
  int helix_discs = 5;           ///< discs when helix_lag is added
  bool uncertainties = true;     ///< the winner refitted with the fitter's systematic spread
  /// Exchanges the search makes at most where it stops above the floor (the replacement step:
  /// an effect named taken out, the best candidate in its place; 0: the greedy search alone).
  /// Each costs a refit and one or two rounds per effect named, and lowers the criterion by
  /// `significance` at least.
  int max_exchanges = 3;
  /// Candidates scored (catalogue names); empty: the whole catalogue.
  std::vector<std::string> candidates;
  /// Candidates of a round fitted at once, each on a model workspace of its own (threads; 0:
  /// one per core). The result is the same for any number: each candidate is fitted from the
  /// round's model alone, and the round is read in the catalogue's order.
  int jobs = 1;
  /// Called with a short line as the work progresses (a terminal's progress line).
  std::function<void(std::string_view)> progress;
};

/// One fitted parameter with its 1σ uncertainty (units in the name).
struct Parameter {
  Parameter() = default;
  Parameter(std::string n, double v, double s, std::string bound = {})
      : name(std::move(n)), value(v), sigma(s), at_bound(std::move(bound)) {}
  std::string name;
  double value = 0.0;
  double sigma = 0.0;
  /// "lower" or "upper" when the fit sits on the parameter's physical bound (the value is the
  /// bound, not an estimate: sigma 0); "" inside.
  std::string at_bound;
  /// The value is the least the force allows, not a measurement: ρ of a fit on a flute's contact
  /// edge (identify::FitResult::runout_at_contact_edge), a flute cutting nothing beyond it.
  bool lower_bound = false;
  /// The value is the most the force allows: the radius difference r_j − r_CE1 of a flute j
  /// idle at a contact edge (its radius lies at least the largest chip below the flute's before
  /// it, so r_j − r_CE1 is at most its value).
  bool upper_bound = false;
  /// Why the value is a bound (lower_bound/upper_bound), where it is not a flute's contact edge:
  /// h_min at an end of the range its profile tries.
  std::string bound_note;
  /// false: the record does not pin it (identify::Estimate::determined); the value is where the
  /// fit left it, sigma 0, not an estimate.
  bool determined = true;
};

/// The physical range of a dynamometer's damping ratio ζ: a piezoelectric dynamometer clamped
/// on a machine table rings with ζ of a few 0.1 % to a few % (e.g. [001]/[003]'s 9317C, whose
/// clamped resonances at 2145/2192 Hz stand out as sharp peaks). A fit that wants ζ outside —
/// 0.0003 on PHM 2010's c1_cut315, a line the resonance model explains by an undamped ring —
/// is held at the bound, the rest refitted, and the report says so.
inline constexpr double kDampingRatioMin = 0.002;
inline constexpr double kDampingRatioMax = 0.10;
/// The physical range of its natural frequency: Kistler's clamped dynamometers ring between
/// about 1 kHz (a 9257B under a heavy fixture) and some 20 kHz (a miniature 9109AA); 500 Hz to
/// 50 kHz leaves room on both sides. A fit that puts the resonance below the spindle frequency
/// (30 Hz on PHM 2010's c1_cut315) is explaining something else with it.
inline constexpr double kNaturalHzMin = 500.0;
inline constexpr double kNaturalHzMax = 50000.0;

/// The physical range [min, max] of a fitted dynamometer parameter by name (damping_ratio_x…,
/// natural_hz_x…), or {0, 0} for a parameter without one.
std::array<double, 2> physical_range(const std::string& name);
/// The value of a dynamometer parameter (damping_ratio_x…, natural_hz_x…) in `config`.
double& dynamometer_parameter(model::ModelConfig& config, const std::string& name);

/// A candidate added to the current model and refitted.
struct CandidateScore {
  std::string name;
  bool ok = false;
  std::string message;  ///< why not fitted (not ok), or why not shown
  double criterion = 0.0;
  /// Current model's criterion minus this one's (> 0: better).
  double gain = 0.0;
  std::array<double, 2> residual_rms_N{};
  std::vector<Parameter> parameters;
  int free_parameters = 0;
  /// Its own parameters show the effect (see not_shown_by_parameters()); when not, `message`
  /// says why, and it is not chosen whatever its gain.
  bool shown = true;
};

/// Why a candidate's fit, though it gained, does not show the effect it names, or "" when it
/// does. A time-varying candidate refits the rest of the model with it (runout_change: every
/// parameter once per segment; tool_wear: the coefficients beside the wear), so a refit that
/// lands in a better basin of the other parameters gains with an effect that is not there:
/// runout_change is shown by a runout (ρ, or r_CE2 − r_CE1) that differs across the change by
/// more than 2σ of the difference, tool_wear by a wear or a growth beyond 2σ of zero.
std::string not_shown_by_parameters(const std::string& candidate,
                                    const std::vector<Parameter>& parameters);

struct FrequencyBand {
  std::string name;
  std::string range;                    ///< what it holds, for people
  std::array<double, 2> rms_N{};        ///< the residual in it
  std::array<double, 2> noise_rms_N{};  ///< the noise floor's share of it
};

struct Localisation {
  std::vector<std::array<double, 2>> flute_rms_N;  ///< synchronous residual per flute sector
  std::array<double, 2> entry_exit_rms_N{};        ///< near entry and exit of the engagement
  std::array<double, 2> middle_rms_N{};            ///< around the middle (the peak)
  std::array<double, 2> synchronous_rms_N{};       ///< the synchronous residual over the revolution
  std::vector<FrequencyBand> bands;
  std::vector<double> segment_start_s;               ///< time segments of the record
  std::vector<std::array<double, 2>> segment_rms_N;  ///< band-limited residual per segment
  std::string summary;                               ///< one line: where the excess is
};

/// What a plot shows of one model: one revolution measured vs model, the residual's spectrum.
struct ModelView {
  std::vector<double> angle_deg;
  std::array<std::vector<double>, 2> measured_N, model_N;  ///< synchronous average (chain removed)
  std::vector<double> frequency_hz;
  std::array<std::vector<double>, 2> residual_amplitude_N;  ///< |R(f)| as a sinusoid's amplitude
};

/// The model after a step (or the starting model).
struct Stage {
  std::string added;  ///< effect added at this step ("" for the starting model)
  /// An exchange (the search's replacement step): the effect named before that `added` takes
  /// the place of ("" for a plain step). Its candidates were scored from the model without it.
  std::string removed;
  /// On an exchange: the criterion gained over the model before it by the exchange and the step
  /// taken with it (the exchange's own `gain` may be below zero where that step wins it back).
  double exchange_gain = 0.0;
  int exchange_steps = 0;  ///< on an exchange: 1, or 2 with the step taken with it
  /// On an exchange: the round scored from the model before it, in which no candidate gained
  /// enough (empty where the step limit, not the gains, stopped the search).
  std::vector<CandidateScore> candidates_before_exchange;
  std::vector<Parameter> parameters;    ///< the added effect's
  std::vector<Parameter> coefficients;  ///< the force law's, refitted
  std::array<double, 2> residual_rms_N{};
  std::array<double, 2> residual_percent{};  ///< of the measured RMS over the band
  double criterion = 0.0;
  int free_parameters = 0;
  double gain = 0.0;  ///< criterion gained over the previous model
  /// The window fit's parameters (runout, the dynamometer's, the stiffness, the wear land; and
  /// the coefficients) carry statistical σ only, without the spread over the model's variants:
  /// uncertainties off, or the winner's refit with them failed or ended on a worse optimum than
  /// the fit the choice scored, which then stands. Never set for an effect none of whose
  /// parameters the fit gives (the speed, the drift, the hum); the report says which σ it means.
  bool sigma_statistical_only = false;
  std::string runner_up;                   ///< the next best candidate ("" if none)
  double margin_over_runner_up = 0.0;      ///< its criterion minus the winner's
  std::vector<CandidateScore> candidates;  ///< every candidate scored at this step
  /// Parameters of effects added before that this step's refit pushed out of their physical
  /// range and that are held at the bound from here on (their value changed here).
  std::vector<Parameter> newly_held;
  Localisation localisation;
  ModelView view;
};

/// An effect of the final model and its parameters.
struct EffectParameters {
  std::string effect;
  std::vector<Parameter> parameters;
};

struct Diagnosis {
  bool ok = false;
  std::string message;  ///< why not, when not ok
  double band_hz = 0.0;
  int effective_samples = 0;  ///< per axis: 2·(bins in the band)
  double duration_s = 0.0;
  double commanded_rpm = 0.0;
  double spindle_rpm = 0.0;  ///< the final model's speed
  std::array<double, 2> measured_rms_N{};
  std::array<double, 2> noise_floor_N{};
  Stage initial;
  std::vector<Stage> steps;
  /// The final model's effects, in the order added (one an exchange took out is not among them).
  std::vector<std::string> named_effects;
  /// The last round: every candidate scored from the final model (none gained enough).
  std::vector<CandidateScore> final_candidates;
  std::string stop_reason;
  std::string verdict;  ///< one sentence
  /// Where the final model leaves the residual above the noise floor: that every σ is given its
  /// step's model, and what the model lacks biases its parameters beyond them ("" at the floor).
  std::string sigma_caveat;
  /// What was done to the final model after the search's last step (h_min profiled again in
  /// it), and what of its steady state, as compared with the record, is not its own revolution
  /// by revolution (a cycle longer than model::kMaxCycleRevolutions played round again, slots
  /// that did not repeat), a sentence each.
  std::vector<std::string> final_notes;
  /// The final model's residual and force coefficients (the last step's, unless final_notes
  /// changed the model after it).
  std::array<double, 2> final_residual_rms_N{};
  std::vector<Parameter> final_coefficients;
  model::ModelConfig final_model;
  /// The final model's effects (as named_effects) with their parameters as its last fit left
  /// them: a step's own parameters are its model's, and a later step's refit moves them (on the
  /// cp-Ti preset's cut r_CE2 − r_CE1 went from −1.88 µm at the runout's step, standing in for
  /// the dynamometer and ploughing still missing, to about −2.9 in the final model).
  std::vector<EffectParameters> final_parameters;
  /// The final model's parameters held at a physical bound (kDampingRatioMin/Max), with the bound.
  std::vector<Parameter> at_bound;
  double seconds = 0.0;  ///< wall-clock time
};

/// How many revolutions of a record laid along a model's cycle of `cycle_revolutions` play it
/// round again: the record starts at the cycle's revolution `first_cycle_revolution` (fractional,
/// in [0, cycle)) and spans `revolutions`; those after the cycle's first wrap replay it.
double revolutions_round_again(double first_cycle_revolution, double revolutions,
                               int cycle_revolutions);

/// Diagnosis::final_notes on the final model's steady state as laid along the record: the
/// revolutions compared with a cycle cut at model::kMaxCycleRevolutions played round again (its
/// whole ones), and its slots that did not repeat within model::kMaxSlotRevolutions (of
/// `slots`). Empty when neither.
std::vector<std::string> steady_state_notes(double revolutions_round_again, int unsettled_slots,
                                            int slots);

/// Diagnoses a record against a starting model (commanded speed in process.spindle_rpm; its
/// enabled effects are kept, the others are candidates; its values are the fit's starting point,
/// e.g. the dynamometer's nominal resonance).
/// @throws std::invalid_argument naming the problem for a record that cannot be diagnosed (too
///         short, non-finite samples, a band beyond Nyquist, an unknown candidate name)
Diagnosis diagnose(const CutRecord& record, const model::ModelConfig& start,
                   const DiagnoseOptions& options = {});

/// The plain model (issue 8: circular path, no runout, no ploughing, rigid, one disc, no
/// dynamometer) of a configuration, keeping its values as starting points.
model::ModelConfig plain_model(const model::ModelConfig& config);

}  // namespace millwatch::diagnose
