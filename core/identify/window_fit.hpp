#pragma once
// Identification of runout and force coefficients from the measured force alone.
//
// What is fitted: the revolution-synchronous average of the measured force over a window of
// revolutions (each revolution mapped to the spindle angle through its own tooth events), in the
// tracker's angle frame. What fits it: the model's periodic steady state at the window's speed
// (model::evaluate_steady_state, feed rate fixed by the commanded speed), through the same
// low-pass filter as the measurement (its response H at each spindle harmonic), rotated by an
// alignment δ between the tracker's angle zero and the model's flute 0.
//
// In the spindle-harmonic domain. Both sides are expanded in spindle harmonics k = 1..K, K the
// last harmonic the filter passes at |H| ≥ passband_gain; the fit compares the complex harmonics
// of every axis used (2·K·axes real numbers: for a signal low-passed at f_c these are its
// independent samples, the "effective number" a low-passed signal has — not the raw sample
// count). The mean force (k = 0) is left out: the charge amplifiers' offset and drift live there.
// The alignment is then an exact phase factor e^{ikδ}.
//
// Separable least squares. With deflection off the force is linear in the force law's
// coefficients (model::evaluate_force_basis): for each trial of the nonlinear parameters θ
// (runout as u = ρ·cos γ, v = ρ·sin γ — smooth through ρ = 0, no wrap in γ —, the alignment δ,
// and any extra parameter such as h_min) the coefficients are solved by linear least squares
// (variable projection), and Levenberg–Marquardt moves θ only. With deflection on the
// coefficients join θ. Starts: runout on a grid of offsets and 8 directions, each with the best
// alignment on a fine grid of δ; the best few are refined.
//
// Flute labelling: without a once-per-revolution reference the flutes are known only modulo the
// pitch. The result is relabelled (uniform pitch) so that flute 0 — CE1 — is the flute with the
// largest cut, the monitor's convention: γ and δ move by a pitch, the force does not change.
//
// Uncertainty. Statistical: the covariance s²·(JᵀJ)⁻¹ of all parameters (θ and coefficients)
// from the Jacobian at the solution, s² = RSS/(M − p) with M the real harmonic values compared
// (the effective count above). The runout carries a weak prior, (u, v) ~ N(0, σ_p²): where the
// data pin a direction the prior does not matter; where they do not (ρ·sin γ when only the
// cutting radii see the runout) the estimate stays at 0 with σ ≈ σ_p instead of wandering along
// a flat valley to wherever the model's small errors push it. Systematic: the model is not the cut,
// and a fit can match the waveform to millinewtons while a weakly pinned parameter (ρ·sin γ: see
// physics-notes, "What the force can tell about runout") sits far from the truth. So the fit is
// repeated with the model's own approximations changed — a finer angle grid, twice the helix discs,
// fewer harmonics, the in-plane axes alone — and the spread of the estimates over these variants is
// added in quadrature. Parameters whose correlation exceeds 0.9 in magnitude are flagged.
//
// Several cuts at once (fit_cuts, the calibration's fit): the same machinery with the rows of every
// cut stacked, each cut at its own speed, feed, engagement and filter with its own alignment δ_i,
// one runout and one set of coefficients for all of them (one tool, one clamping).
//
// Runs in a worker thread (allocates; not for the sample path). One fitter per thread.

#include <array>
#include <cmath>
#include <complex>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/model/model_config.hpp"

namespace millwatch::identify {

/// The measurement to fit: the revolution-synchronous average over a window.
struct MeasuredRevolution {
  /// Average force on the tool per axis (fx, fy, fz; N) on a uniform grid of the tracker's
  /// spindle angle, bin b at 2πb/B.
  std::array<std::vector<double>, 3> force_N;
  std::array<bool, 3> use_axis = {true, true, false};  ///< axes compared (fz only if measured)
  double spindle_rpm = 0.0;                            ///< the window's mean actual speed
  int revolutions = 0;                                 ///< revolutions averaged
  /// The grid was filled as monitor::SyncAverage does, each sample shared between its two nearest
  /// bins: a triangular kernel one bin wide, which scales harmonic k by sinc²(πk/B). The fit
  /// divides it out. False for a grid sampled exactly.
  bool shared_bins = true;
};

/// The measurement chain's filter, as the model must go through it: H(f) (complex).
using FilterResponse = std::function<std::complex<double>(double frequency_hz)>;

struct FitOptions {
  int steps_per_rev = 720;                    ///< the model's angle grid
  double passband_gain = 0.1;                 ///< harmonics used: |H(k·f)| ≥ this
  bool fit_runout = true;                     ///< ρ and γ free (else as configured)
  std::vector<std::string> extra_parameters;  ///< other nonlinear parameters (parameter_map names)
  int max_iterations = 30;                    ///< Levenberg–Marquardt iterations per start
  int refined_starts = 2;                     ///< best starts refined
  bool systematic = true;                     ///< estimate the model-discrepancy spread
  /// Compare the mean force (k = 0) too. Off by default: the charge amplifiers' offset and drift
  /// live there; on when the channels are known to be tared (a calibration on short cuts).
  bool use_mean = false;
  /// σ of a weak prior on ρ·cos γ and ρ·sin γ around 0 (µm; 0: none): what the data do not pin
  /// (ρ·sin γ, weakly) stays near 0 with this σ instead of wandering along a flat valley.
  double runout_prior_um = 5.0;
  /// Floor of each coefficient's systematic σ as a fraction of its value (0: none). What no
  /// model variant shows: the measurement's own systematic errors (the angle map's jitter
  /// through the synchronous average, the filter as modelled) move the coefficients by up to
  /// about 0.7 % on simulated cuts with known truth. A calibration, whose values are absolute,
  /// sets 0.005 (identify::calibrate); a window fit, watched for changes between windows of one
  /// cut, leaves it at 0.
  double coefficient_floor = 0.0;
  /// Compare the minima the refined starts reach with the best (FitResult::competing_minima):
  /// those the data cannot tell from it join the systematic σ. A calibration sets it, with
  /// more refined starts (identify::calibrate); a window fit, seeded by the last, does not.
  bool competing_minima = false;
};

/// A fit ends on a flute's contact edge (FitResult::runout_at_contact_edge) when a step of the
/// runout one way changes the residual by more than kContactEdgeRatio times the same step the
/// other way, raises the cost by more than one value's variance (RSS over the degrees of freedom:
/// the data reject the step; a weakly pinned direction of a poor fit, whose two small changes
/// differ by their second order, does not — a PHM 2010 window, 81 % unexplained, read a ratio
/// of 4.1 there) and changes it by more than kContactEdgeSignificance of the measured harmonics
/// (not the model's rounding). On the edges of simulated cuts the ratio read 9–20 (linear edge
/// law) and 10³–10⁴ (power law); at ordinary minima 1.0–1.5. Where the fitted model leaves a
/// flute idle (its chip 0 everywhere), the cost test is not asked and the significance is
/// kContactEdgeIdleSignificance: with deflection bending the flute that cuts, or a step weak
/// beside the noise, they missed fits just past the edge (ratio 75–370; a 2-flute slot stated
/// r_CE1 − r_CE2 3.84 ± 0.06 µm for 5.97).
inline constexpr double kContactEdgeRatio = 4.0;
inline constexpr double kContactEdgeSignificance = 1e-3;
/// The same where the fitted model leaves a flute idle (a fit just past the edge, deflection on,
/// read 1.1·10⁻⁴: WindowFit.AFluteIdleUnderDeflectionIsBoundedFromBelow).
inline constexpr double kContactEdgeIdleSignificance = 1e-5;
/// Nor is it an edge where every flute cuts: the least-cutting flute's largest chip must be at
/// most this share of the largest flute's. Near an edge the one flute cuts a sliver (0–5 % on
/// simulated cuts); PHM 2010's c1_cut315 (a ball-nose the model leaves 80 % unexplained), whose
/// radii lie 0.4 µm apart against chips of up to 14 µm, had passed the cost test.
inline constexpr double kContactEdgeMaxChipShare = 0.5;

/// A σ beyond this many times a parameter's magnitude says the record does not pin it
/// (Estimate::determined): the 1σ interval then spans a thousand times the value itself.
inline constexpr double kUndeterminedSigmaRatio = 1e3;

/// One estimated parameter.
struct Estimate {
  std::string name;
  double value = 0.0;
  double sigma = 0.0;       ///< total: statistical and systematic in quadrature
  double sigma_stat = 0.0;  ///< from the Jacobian and the residual
  double sigma_sys = 0.0;   ///< spread over the model variants
  /// false: the record does not pin it — the force does not depend on it there, or only
  /// together with other parameters in a way the data cannot tell apart (its σ would be many
  /// orders of magnitude beyond anything physical). The value is where the fit left it and the
  /// σs are 0: not an estimate. Set for the extra parameters and the coefficients; ρ and γ say
  /// what the data leave open their own way (γ's σ capped at π, the contact edge's bound).
  bool determined = true;
};

struct FitResult {
  bool ok = false;
  std::string message;        ///< why not, or how the fit ended
  model::ModelConfig config;  ///< the configuration with every fitted value in place
  /// Tool-centre offset ρ ([000] eq 9), at the tool tip. Two flutes, one idle (edge_flute):
  /// the least ρ the fitted radii allow, |r_CE1 − r_CE2|/2, at γ 0 ± 90° (ρ·sin γ is not
  /// pinned there); the model's own runout is in `config`.
  Estimate rho_um;
  Estimate gamma_rad;      ///< its direction relative to flute 0 (CE1), in (−π, π]
  Estimate alignment_rad;  ///< model angle minus tracker angle
  /// The fit ended on a flute's contact edge: at the runout found a flute just stops cutting.
  /// Towards less runout that flute cuts and the force changes steeply with the runout (its
  /// edge force and chip start at once); beyond, the flute idle, the force hardly changes, and
  /// nothing but the weak prior holds the fit back. The force then bounds the runout from one
  /// side only: the idle flute's radius lies at least the largest chip below the flute's before
  /// it (exactly), and ρ is about the least runout the force allows (the edge is a line in
  /// (u, v), the truth beyond it; with two flutes stated as exactly that, rho_um); their σ are
  /// the steep side's. Told from an ordinary minimum by the runout's one-sided differences and
  /// an idle flute in the fitted model (kContactEdgeRatio and below).
  bool runout_at_contact_edge = false;
  /// On a contact edge, the flute the fitted model leaves idle (0-based, 0 = CE1): its radius
  /// lies at least a chip below the flute's before it (for two flutes, r_CE1 − r_CE2 is bounded
  /// from below). −1 off an edge, or on one whose flute still cuts a little.
  int edge_flute = -1;
  /// Each flute's cutting radius r_j = |O→edge j| (µm) and r_j − r_0, with σ.
  std::vector<Estimate> cutting_radius_um;
  std::vector<Estimate> radius_from_ce1_um;
  /// The geometric cutting-edge phase angle: the rotation (deg) by which the edge after CE2
  /// follows CE2 ([001]'s α, 360°·T₂/T without the force), with σ; 0 and σ 0 for one flute.
  Estimate alpha_deg;
  std::vector<Estimate> coefficients;  ///< force-law coefficients fitted (parameter_map names)
  std::vector<Estimate> extra;         ///< extra nonlinear parameters
  std::vector<std::pair<std::string, std::string>> correlated;  ///< |correlation| > 0.9
  std::array<double, 3> residual_rms_N{};  ///< per axis, over the harmonics compared
  std::array<double, 3> measured_rms_N{};  ///< the measurement's, same harmonics
  std::array<bool, 3> compared{};          ///< the axes compared (the others' RMS are 0)
  int harmonics = 0;                       ///< K
  int effective_samples = 0;               ///< M: real harmonic values compared
  int iterations = 0;
  long evaluations = 0;  ///< model evaluations (each: the force basis at one runout)
  /// Other minima as good within the noise (FitOptions::competing_minima: ΔRSS within the 95 %
  /// profile threshold of one parameter, χ²₁·s², and apart by more than some parameter's σ):
  /// the record does not choose between them; their distance from the solution is in the
  /// systematic σ's.
  int competing_minima = 0;
  std::string flute_labelling =
      "flute 0 = CE1, the flute with the largest cut (no once-per-revolution reference)";
};

/// The share of the measured force's variance a fit leaves unexplained, over the harmonics
/// compared: Σ residual² / Σ measured² over the axes (1 when nothing was measured). What the
/// model in lockstep tests against identification.max_unexplained.
double unexplained_variance(const std::array<double, 3>& residual_rms_N,
                            const std::array<double, 3>& measured_rms_N);

/// The same as a share of the force's RMS: √unexplained_variance (the summaries'
/// "unexplained_fraction").
inline double unexplained_fraction(const std::array<double, 3>& residual_rms_N,
                                   const std::array<double, 3>& measured_rms_N) {
  return std::sqrt(unexplained_variance(residual_rms_N, measured_rms_N));
}

/// One cut of a joint fit (fit_cuts): the cut as commanded (its own feed per tooth, speed and
/// engagement; the tool, the force law and the effects shared with the other cuts), the filter
/// its measurement went through, and its revolution-synchronous average.
struct FitCut {
  std::string name;  ///< for messages (e.g. the recording's file name)
  model::ModelConfig model;
  FilterResponse filter;
  MeasuredRevolution measured;
};

/// What a joint fit says about one of its cuts.
struct CutFitQuality {
  Estimate alignment_rad;                  ///< this cut's model angle minus tracker angle
  std::array<double, 3> residual_rms_N{};  ///< per axis, over the harmonics compared
  std::array<double, 3> measured_rms_N{};  ///< the measurement's, same harmonics
  std::array<bool, 3> compared{};          ///< the axes compared (the others' RMS are 0)
  int harmonics = 0;                       ///< K of this cut
  int effective_samples = 0;               ///< real harmonic values compared
};

struct JointFitResult {
  /// The shared estimates: runout, radii, coefficients, correlations (the alignments named
  /// "alignment_rad[i]"), iterations; `config` is the first cut's with the fitted values,
  /// `alignment_rad` the first cut's, residual and measured RMS over all cuts together.
  FitResult fit;
  std::vector<CutFitQuality> cuts;  ///< per cut, in the order given
};

class WindowFitter {
 public:
  /// @param model the cut as commanded (process.spindle_rpm is the commanded speed); its effects
  ///        and force law are the model fitted; its values are the starting point
  /// @param filter the measurement's filter response (causal H, or |H|² for zero phase)
  WindowFitter(const model::ModelConfig& model, FilterResponse filter, FitOptions options = {});
  ~WindowFitter();
  WindowFitter(WindowFitter&&) noexcept;
  WindowFitter& operator=(WindowFitter&&) noexcept;
  WindowFitter(const WindowFitter&) = delete;
  WindowFitter& operator=(const WindowFitter&) = delete;

  /// Fits one window. `previous` (optional) seeds the search with an earlier result.
  /// `variants` false: no systematic variants this time even if options().systematic (the
  /// σ's are statistical only; the caller carries the systematic part of an earlier fit).
  FitResult fit(const MeasuredRevolution& measured, const FitResult* previous = nullptr,
                bool variants = true);

  [[nodiscard]] const FitOptions& options() const;

  struct Impl;  ///< the fitting machinery; fit_cuts uses it with several cuts

 private:
  std::unique_ptr<Impl> impl_;
};

/// Joint fit over several cuts with the same tool and clamping ([000] Sect. 5, [001] Table 4: a
/// feed sweep): one set of force-law coefficients and one runout (u, v) for all cuts, one
/// alignment δ per cut (each cut has its own tracker zero). Each cut is fitted in its own
/// spindle harmonics through its own filter, at its own speed and feed; the coefficients are
/// solved by linear least squares over the stacked harmonics of every cut. The same starts,
/// σ treatment (statistical with the effective number of harmonic values, systematic spread over
/// the model variants, the floor), correlation flags and CE1 relabelling as WindowFitter, which
/// is this fit with one cut.
/// @throws std::invalid_argument naming the cut when there is none, or when a cut's tool, force
///         law or effects differ from the first cut's (one tool, one clamping)
JointFitResult fit_cuts(const std::vector<FitCut>& cuts, const FitOptions& options = {});

/// The spindle harmonics k = 1..count of a revolution on a uniform grid: X[k] = (2/B)·Σ_b x[b]·
/// e^{−2πikb/B} (amplitude convention: x ≈ mean + Σ Re(X[k]·e^{ikφ})).
std::vector<std::complex<double>> revolution_harmonics(const std::vector<double>& x, int count);

}  // namespace millwatch::identify
