#include "core/diagnose/diagnosis.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>
#include <exception>
#include <limits>
#include <memory>
#include <mutex>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <thread>
#include <unsupported/Eigen/FFT>

#include "core/diagnose/catalogue.hpp"
#include "core/diagnose/record_spectrum.hpp"
#include "core/diagnose/speed_scatter.hpp"
#include "core/identify/window_fit.hpp"
#include "core/model/steady_state.hpp"

namespace millwatch::diagnose {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kTwoPi = 2.0 * kPi;
constexpr std::array<double, 3> kHumHarmonics = {1.0, 3.0, 5.0};
/// spindle_speed_error searches the actual speed within this fraction of the commanded one.
constexpr double kSpeedSearchFraction = 0.025;
// The range of h_min's profile, over f_t (its grid ends at the first point below the least:
// 0.0185·f_t). Its least is 2 steps of the default angle grid
// (720 a revolution) at the entry of a slot, where h ≈ f_t·φ: the preset's cp-Ti h_min,
// 0.2 µm at 4 µm a tooth, is 0.05·f_t, and a larger feed puts a like h_min lower.
constexpr double kHMinLowestPerFeed = 0.02;
constexpr double kHMinHighestPerFeed = 1.6;
// The profile's grid steps by this factor; refine_h_min() searches between a point's
// neighbours.
constexpr double kHMinGridRatio = 1.5;
/// Revolutions beyond which the speed search's first grid runs on a leading part of the record
/// (find_speed()): the records of a diagnosis are seconds long, rarely more than a thousand
/// revolutions, and a longer one's search then takes time in proportion to its length.
constexpr double kSpeedSearchRevolutions = 1000.0;

std::string format(const char* fmt, double a, double b = 0.0, double c = 0.0, double d = 0.0) {
  char buf[512];
  std::snprintf(buf, sizeof buf, fmt, a, b, c, d);
  return buf;
}

/// A candidate that brings h_min with it: scored on h_min's profile, refined at its step.
bool profiles_h_min(const std::string& name) {
  return name == "min_chip_thickness" || name == "chip_accumulation" || name == "ploughing_area";
}

/// [001]'s ploughed-area law in effect (the flag counts for the linear law only).
bool area_law_on(const model::ModelConfig& c) {
  return c.material.law == model::ForceLawKind::kLinearEdge &&
         c.material.linear_edge.ploughing_area;
}

/// A ploughing regime's coefficient (k_tp_Nmm, k_np_N_per_mm3, …).
bool is_ploughing_coefficient(const std::string& name) {
  return name.rfind("k_tp_", 0) == 0 || name.rfind("k_np_", 0) == 0 || name.rfind("k_ap_", 0) == 0;
}

/// "; X gained ΔBIC g but …" for each candidate that gained without showing its effect.
std::string unshown_gains(const std::vector<CandidateScore>& scores) {
  std::string text;
  for (const auto& c : scores) {
    if (c.ok && !c.shown && c.gain > 0.0) {
      text += "; " + c.name + format(" gained ΔBIC %.1f but ", c.gain) + c.message;
    }
  }
  return text;
}

/// The model the diagnosis fits: effects and their free parameters, the time base, the chain.
struct State {
  model::ModelConfig config;  // commanded speed; fitted values in place
  bool fit_runout = false;
  std::vector<std::string> extra;  // the fitter's extra nonlinear parameters
  double rpm = 0.0;                // the time base's speed
  double rpm_sigma = 0.0;
  bool speed_fitted = false;
  int drift_degree = 0;         // polynomial terms beyond the constant
  double hum_hz = 0.0;          // 0: no hum
  double h_min_sigma_um = 0.0;  // h_min's σ from its profile (when profiled)
  // h_min's profile ended on an end of its range: "upper" (h_min is at most its value: the
  // lowest tried), "lower" (at least: the highest); "" inside.
  std::string h_min_bound;
  std::array<double, 2> h_min_bracket_um{};  // the grid's neighbours of the best (profile_h_min)
  // Scored at the model's own h_min from the current fit (evaluate_at_h_min): its refinement
  // starts there too, and its bracket is not known to hold the minimum.
  bool h_min_from_current = false;
  double change_s = 0.0;  // the runout changed at this time (0: it did not)
  double change_sigma_s = 0.0;
  bool wear_trend = false;  // flank wear's rubbing, growing linearly over the record
  // The parameters of `extra` the last accepted fit held at a physical bound: name →
  // "lower"/"upper" (still counted in the criterion: the fit chose the bound). The fits that
  // score candidates keep them there; the refit of each accepted step frees them
  // (`release_held`) and holds them again only where they cross (Engine::fit_segment): a bound
  // chosen early, where the model lacked what a later step adds, need not stay. Held for good,
  // the dynamometer's damping on x stayed at 0.1 from the third step of the cp-Ti preset's cut
  // on, and the search ended 4.7× above the noise floor with the seven effects of the truth;
  // freed, 0.060 ± 0.001 (truth 0.06), at the floor.
  std::vector<std::pair<std::string, std::string>> held;
  bool release_held = false;

  /// Records what an accepted evaluation left on a bound (its value is in config already).
  void hold(const std::vector<std::pair<std::string, std::string>>& at_bound) { held = at_bound; }

  /// Takes a parameter out of the fit, free or held (an effect taken out).
  void drop(const std::string& name) {
    extra.erase(std::remove(extra.begin(), extra.end(), name), extra.end());
    held.erase(
        std::remove_if(held.begin(), held.end(), [&](const auto& h) { return h.first == name; }),
        held.end());
  }
};

/// The ploughed area beside an h_min the model (state `s`) has estimated: scored at that h_min,
/// refined at its step. Its profile there would cost twelve fits of the area law over the
/// accumulation's whole cycle (the AlSi10Mg preset's diagnosis: 43 s → 6.8 min). (An h_min the
/// search estimated: a configured one has no σ and may be far off.)
bool at_model_h_min(const std::string& name, const State& s) {
  return name == "ploughing_area" && s.config.effects.min_chip.enabled && s.h_min_bound.empty() &&
         s.h_min_sigma_um > 0.0;
}

/// One fit of a state to the record.
struct Evaluation {
  bool ok = false;
  std::string message;
  identify::FitResult fit;
  int cycle_revolutions = 1;
  double alignment_rad = 0.0;  // the model's angle minus the time base's (a cycle may turn it)
  std::array<std::vector<double>, 2> model_N, chain_N;
  std::array<Eigen::VectorXd, 2> chain_coefficients;
  std::array<Eigen::VectorXd, 2> chain_sigma;
  std::array<std::vector<std::complex<double>>, 2> residual_bins;  // 0..last
  std::array<double, 2> mean_square{};
  double criterion = 0.0;
  int free_parameters = 0;
  identify::FitResult fit_before;  // the fit before a runout change (ok: there was one)
  double alignment_before_rad = 0.0;
  double wear_slope_um = 0.0;  // VB's change per unit of τ = 2t/T − 1
  double wear_slope_sigma_um = 0.0;
  double wear_normal = 1.0;
  /// Damping ratios held at a physical bound (name → "lower"/"upper"), from the last segment.
  std::vector<std::pair<std::string, std::string>> at_bound;
  /// The model's steady state as synthesize() laid it on the record (over the segments): the
  /// record's revolutions that play a cycle cut at model::kMaxCycleRevolutions round again,
  /// and the most slots that did not repeat within model::kMaxSlotRevolutions, of `slots`.
  double revolutions_round_again = 0.0;
  int unsettled_slots = 0;
  int slots = 0;
};

/// One round of the search: every candidate not in the model added to it and refitted.
struct Round {
  std::vector<CandidateScore> scores;
  std::vector<State> states;  // each candidate's state, as scored
  Evaluation leader;          // the best's evaluation (only it is kept)
  int best = -1;              // index into scores of the lowest criterion (-1: none fitted)
  int second = -1;
};

class Engine {
 public:
  Engine(const CutRecord& record, const DiagnoseOptions& options)
      : rec_(record), opt_(options), fs_(record.sample_rate_hz), n_(record.force_N[0].size()) {
    n_fft_ = smooth_length(n_);
    band_ = opt_.band_hz > 0.0 ? opt_.band_hz : std::min(0.4 * fs_, 10000.0);
    last_ = last_band_bin(n_fft_, fs_, band_);
    const std::size_t first = std::max<std::size_t>(
        1, last_band_bin(n_fft_, fs_, 20.0));  // the median skips the drift's lowest bins
    for (std::size_t a = 0; a < 2; ++a) {
      const std::span<const double> y(rec_.force_N[a].data(), n_fft_);
      floor_[a] = noise_floor_rms(y, first, last_);
      const auto s = spectrum(y, last_ + 1);
      measured_rms_[a] = std::sqrt(band_mean_square(s, n_fft_, last_));
    }
  }

  [[nodiscard]] double band() const { return band_; }
  [[nodiscard]] std::size_t last() const { return last_; }
  [[nodiscard]] int effective() const { return 2 * static_cast<int>(last_); }
  [[nodiscard]] const std::array<double, 2>& floor() const { return floor_; }

  /// The noise floor again from a model's residual: where the record is dense with lines (an
  /// accumulation cycle's sub-harmonics every few bins) the measurement's median is above the
  /// noise; once a model explains them its residual's median is the noise. The floor is the
  /// lowest estimate so far.
  void refine_floor(const Evaluation& ev) {
    const std::size_t first = std::max<std::size_t>(1, last_band_bin(n_fft_, fs_, 20.0));
    for (std::size_t a = 0; a < 2; ++a) {
      std::vector<double> r(n_fft_);
      for (std::size_t i = 0; i < n_fft_; ++i) {
        r[i] = rec_.force_N[a][i] - ev.model_N[a][i] - ev.chain_N[a][i];
      }
      const double f = noise_floor_rms(r, first, last_);
      if (f > 0.0 && f < floor_[a]) {
        floor_[a] = f;
      }
    }
  }
  /// The noise floor `other` has refined (an engine of another thread's).
  void take_floor(const Engine& other) { floor_ = other.floor_; }
  [[nodiscard]] const std::array<double, 2>& measured_rms() const { return measured_rms_; }
  [[nodiscard]] double duration() const { return static_cast<double>(n_) / fs_; }

  [[nodiscard]] int harmonics(double rpm) const {
    return std::max(1, static_cast<int>(std::floor(band_ / (rpm / 60.0) + 1e-9)));
  }

  /// Fits a state; `seed` (optional) starts the fitter from an earlier fit.
  Evaluation evaluate(const State& s, const Evaluation* previous, bool systematic,
                      const Evaluation* seed) {
    Evaluation ev;
    const int k_max = harmonics(s.rpm);
    // The chain first from what the previous model leaves, then the model on the rest.
    std::array<std::vector<double>, 2> target;
    for (std::size_t a = 0; a < 2; ++a) {
      target[a] = rec_.force_N[a];
      if (previous != nullptr) {
        for (std::size_t i = 0; i < n_; ++i) {
          target[a][i] -= previous->model_N[a][i];
        }
      }
      std::vector<double> c0;
      Eigen::VectorXd sigma;
      chain_fit(s, target[a], c0, sigma);
      for (std::size_t i = 0; i < n_; ++i) {
        target[a][i] = rec_.force_N[a][i] - c0[i];
      }
    }
    // The model part: one fit over the record, or one per segment when the runout changed.
    const std::size_t split =
        s.change_s > 0.0 ? std::min(n_, static_cast<std::size_t>(s.change_s * fs_)) : 0;
    const std::vector<std::pair<std::size_t, std::size_t>> segments =
        split > 0 ? std::vector<std::pair<std::size_t, std::size_t>>{{0, split}, {split, n_}}
                  : std::vector<std::pair<std::size_t, std::size_t>>{{0, n_}};
    ev.model_N[0].assign(n_, 0.0);
    ev.model_N[1].assign(n_, 0.0);
    for (std::size_t sg = 0; sg < segments.size(); ++sg) {
      const auto [i0, i1] = segments[sg];
      identify::FitResult fit;
      const identify::FitResult* seed_fit = nullptr;
      if (seed != nullptr && seed->ok) {
        seed_fit =
            sg == 0 && segments.size() > 1 && seed->fit_before.ok ? &seed->fit_before : &seed->fit;
      }
      if (!fit_segment(s, target, i0, i1, k_max, systematic, seed_fit, fit, ev.message,
                       ev.at_bound)) {
        return ev;
      }
      if (!synthesize(fit.config, s.rpm, fit.alignment_rad.value, ev, i0, i1)) {
        return ev;
      }
      if (sg + 1 < segments.size()) {
        ev.fit_before = fit;
        ev.alignment_before_rad = ev.alignment_rad;
      } else {
        ev.fit = fit;
      }
    }
    // The wear's rubbing force (flank_wear with 1 µm of wear, less none) at the final fit.
    std::array<std::vector<double>, 2> rubbing;
    if (s.wear_trend && !rubbing_series(ev.fit.config, s.rpm, ev.alignment_rad, rubbing)) {
      ev.message = "the rubbing force of the wear could not be evaluated";
      return ev;
    }
    // The chain per axis, and the wear's rubbing (its mean and its trend over the record, one
    // wear for both axes) by alternating linear least squares.
    std::array<std::vector<double>, 2> rest;
    for (std::size_t a = 0; a < 2; ++a) {
      rest[a].resize(n_);
      for (std::size_t i = 0; i < n_; ++i) {
        rest[a][i] = rec_.force_N[a][i] - ev.model_N[a][i];
      }
    }
    std::array<std::vector<double>, 2> wear_part;
    wear_part[0].assign(n_, 0.0);
    wear_part[1].assign(n_, 0.0);
    for (int it = 0; it < (s.wear_trend ? 3 : 1); ++it) {
      for (std::size_t a = 0; a < 2; ++a) {
        std::vector<double> t(n_);
        for (std::size_t i = 0; i < n_; ++i) {
          t[i] = rest[a][i] - wear_part[a][i];
        }
        chain_fit(s, t, ev.chain_N[a], ev.chain_coefficients[a]);
      }
      if (s.wear_trend) {
        fit_wear(rubbing, rest, ev.chain_N, wear_part, ev);
      }
    }
    for (std::size_t a = 0; a < 2; ++a) {
      for (std::size_t i = 0; i < n_; ++i) {
        ev.model_N[a][i] += wear_part[a][i];
      }
      std::vector<double> r(n_fft_);
      for (std::size_t i = 0; i < n_fft_; ++i) {
        r[i] = rest[a][i] - wear_part[a][i] - ev.chain_N[a][i];
      }
      ev.residual_bins[a] = spectrum(r, last_ + 1);
      ev.mean_square[a] = band_mean_square(ev.residual_bins[a], n_fft_, last_);
    }
    if (!std::isfinite(ev.mean_square[0]) || !std::isfinite(ev.mean_square[1])) {
      ev.message = "the model's force is not finite";
      return ev;
    }
    if (s.wear_trend) {
      // σ of (VB mean, VB slope): the residual's per-sample variance over (AᵀA)⁻¹.
      const double var = 0.5 * (ev.mean_square[0] + ev.mean_square[1]) *
                         static_cast<double>(n_fft_) / (2.0 * static_cast<double>(last_));
      ev.wear_slope_sigma_um = std::sqrt(var / std::max(ev.wear_normal, 1e-300));
    }
    // σ of the chain's coefficients: the residual's per-sample variance (full band, white).
    for (std::size_t a = 0; a < 2; ++a) {
      const double var = ev.mean_square[a] * static_cast<double>(n_fft_) / (2.0 * last_);
      ev.chain_sigma[a] = chain_sigma(s, var);
    }
    int p = 1;  // alignment
    p += static_cast<int>(ev.fit.coefficients.size());
    p += s.fit_runout ? 2 : 0;
    p += static_cast<int>(s.extra.size());  // those held at a bound too: the fit chose it
    if (split > 0) {  // the segment before the change: its own fit, and the change's time
      p += 2 + static_cast<int>(ev.fit_before.coefficients.size()) + (s.fit_runout ? 2 : 0) +
           static_cast<int>(s.extra.size());
    }
    p += s.wear_trend ? 1 : 0;  // the growth (the mid-record wear is an extra parameter)
    p += s.speed_fitted ? 1 : 0;
    p += s.config.effects.min_chip.enabled ? 1 : 0;  // h_min, profiled
    p += 2 * static_cast<int>(ev.chain_coefficients[0].size());
    ev.free_parameters = p;
    const double neff = effective();
    ev.criterion = neff * (std::log(std::max(ev.mean_square[0], 1e-300)) +
                           std::log(std::max(ev.mean_square[1], 1e-300))) +
                   p * std::log(2.0 * neff);
    ev.ok = true;
    return ev;
  }

  /// Fits the model part to the synchronous harmonics of target over samples [i0, i1).
  bool fit_segment(const State& s, const std::array<std::vector<double>, 2>& target, std::size_t i0,
                   std::size_t i1, int k_max, bool systematic, const identify::FitResult* seed,
                   identify::FitResult& fit, std::string& message,
                   std::vector<std::pair<std::string, std::string>>& at_bound) {
    const double f = s.rpm / 60.0;
    identify::MeasuredRevolution m;
    const int bins = std::max(64, 4 * (k_max + 2));
    std::size_t used = 0;
    const double phase0 = kTwoPi * f / fs_ * static_cast<double>(i0);
    for (std::size_t a = 0; a < 2; ++a) {
      std::vector<std::complex<double>> x;
      used = synchronous_harmonics(std::span<const double>(target[a]).subspan(i0, i1 - i0), fs_, f,
                                   k_max, x, phase0);
      m.force_N[a].assign(static_cast<std::size_t>(bins), x[0].real());
      for (int b = 0; b < bins; ++b) {
        double v = x[0].real();
        for (int k = 1; k <= k_max; ++k) {
          v += std::real(x[static_cast<std::size_t>(k)] *
                         std::polar(1.0, kTwoPi * k * b / static_cast<double>(bins)));
        }
        m.force_N[a][static_cast<std::size_t>(b)] = v;
      }
    }
    if (used == 0) {
      message = "the record (or a segment of it) is shorter than one revolution";
      return false;
    }
    m.force_N[2].assign(static_cast<std::size_t>(bins), 0.0);
    m.use_axis = {true, true, false};
    m.spindle_rpm = s.rpm;
    m.revolutions = static_cast<int>(std::lround(static_cast<double>(used) * f / fs_));
    m.shared_bins = false;
    identify::FitOptions fo;
    fo.steps_per_rev = opt_.steps_per_rev;
    fo.fit_runout = s.fit_runout;
    fo.extra_parameters = s.extra;
    at_bound.clear();
    if (!s.release_held) {  // at their bound in s.config
      for (const auto& h : s.held) {
        fo.extra_parameters.erase(
            std::remove(fo.extra_parameters.begin(), fo.extra_parameters.end(), h.first),
            fo.extra_parameters.end());
        at_bound.push_back(h);
      }
    }
    fo.systematic = systematic;
    const double band = band_;
    const auto filter = [band](double hz) { return hz <= band * (1.0 + 1e-9) ? 1.0 : 0.0; };
    try {
      identify::WindowFitter fitter(s.config, filter, fo);
      fit = fitter.fit(m, seed);
    } catch (const std::exception& e) {
      message = e.what();
      return false;
    }
    if (!fit.ok) {
      message = fit.message;
      return false;
    }
    // A dynamometer parameter outside its physical range is held at the bound it crossed and
    // the other parameters refitted from there (the bound is active: the constrained optimum
    // lies on it). Held parameters stay counted as free in the criterion (the bound was chosen
    // by the fit). Twice at most: holding one may push another out.
    model::ModelConfig held = fit.config;
    for (int round = 0; round < 2; ++round) {
      bool moved = false;
      for (const auto& e : fit.extra) {
        const auto range = physical_range(e.name);
        if (range[1] == 0.0 || (e.value >= range[0] && e.value <= range[1])) {
          continue;
        }
        const bool low = e.value < range[0];
        dynamometer_parameter(held, e.name) = low ? range[0] : range[1];
        fo.extra_parameters.erase(
            std::remove(fo.extra_parameters.begin(), fo.extra_parameters.end(), e.name),
            fo.extra_parameters.end());
        at_bound.emplace_back(e.name, low ? "lower" : "upper");
        moved = true;
      }
      if (!moved) {
        break;
      }
      identify::FitResult refit;
      try {
        identify::WindowFitter fitter(held, filter, fo);
        refit = fitter.fit(m, &fit);
      } catch (const std::exception& e) {
        message = e.what();
        return false;
      }
      if (!refit.ok) {
        message = refit.message;
        return false;
      }
      fit = std::move(refit);
      held = fit.config;
    }
    return true;
  }

  /// The rubbing force of 1 µm of flank wear on every flute at the fitted model (the force with
  /// it less the force without), band-limited, at each sample's angle.
  bool rubbing_series(const model::ModelConfig& fitted, double rpm, double delta,
                      std::array<std::vector<double>, 2>& out) {
    model::ModelConfig with = model::at_actual_speed(fitted, rpm);
    with.effects.flank_wear.enabled = true;
    with.effects.flank_wear.wear_um.assign(1, 1.0);
    model::ModelConfig without = with;
    without.effects.flank_wear.wear_um.assign(1, 0.0);
    try {
      const auto& a = model::evaluate_steady_state(with, rpm, opt_.steps_per_rev, workspace_,
                                                   model::SteadyStateOutput::kMean);
      const model::ForceWaveform w1 = a.mean;
      const auto& b = model::evaluate_steady_state(without, rpm, opt_.steps_per_rev, workspace_,
                                                   model::SteadyStateOutput::kMean);
      std::array<std::vector<double>, 2> diff;
      diff[0] = w1.fx_N;
      diff[1] = w1.fy_N;
      for (std::size_t i = 0; i < diff[0].size(); ++i) {
        diff[0][i] -= b.mean.fx_N[i];
        diff[1][i] -= b.mean.fy_N[i];
      }
      sample_revolution(diff, rpm, delta, out);
    } catch (const std::exception&) {
      return false;
    }
    return true;
  }

  /// A revolution's waveform (one axis per entry, on a uniform angle grid) band-limited and
  /// read at each sample's model angle.
  void sample_revolution(const std::array<std::vector<double>, 2>& w, double rpm, double delta,
                         std::array<std::vector<double>, 2>& out) const {
    const auto length = static_cast<int>(w[0].size());
    const double f = rpm / 60.0;
    const int q_max = std::min(static_cast<int>(std::floor(band_ / f + 1e-9)), length / 2 - 1);
    constexpr int kUp = 4;
    const int fine = kUp * length;
    Eigen::FFT<double> fft;
    const double step = kTwoPi * f / fs_;
    for (std::size_t a = 0; a < 2; ++a) {
      std::vector<std::complex<double>> spec;
      fft.fwd(spec, w[a]);
      std::vector<std::complex<double>> padded(static_cast<std::size_t>(fine), {0.0, 0.0});
      padded[0] = static_cast<double>(kUp) * spec[0];  // the rubbing's mean is part of it
      for (int q = 1; q <= q_max; ++q) {
        padded[static_cast<std::size_t>(q)] =
            static_cast<double>(kUp) * spec[static_cast<std::size_t>(q)];
        padded[static_cast<std::size_t>(fine - q)] = std::conj(padded[static_cast<std::size_t>(q)]);
      }
      std::vector<std::complex<double>> inv;
      fft.inv(inv, padded);
      out[a].resize(n_);
      for (std::size_t i = 0; i < n_; ++i) {
        double u = std::fmod((step * static_cast<double>(i) + delta) / kTwoPi * fine,
                             static_cast<double>(fine));
        u = u < 0.0 ? u + fine : u;
        const auto g = std::min(static_cast<std::size_t>(u), static_cast<std::size_t>(fine - 1));
        const double t = u - static_cast<double>(g);
        const std::size_t g1 = (g + 1) % static_cast<std::size_t>(fine);
        out[a][i] = (1.0 - t) * inv[g].real() + t * inv[g1].real();
      }
    }
  }

  /// The wear's growth (VB's change per unit of τ = 2t/T − 1; its mid-record value is the
  /// fitter's) by least squares on both axes of rest − chain, its rubbing force being
  /// τ·ΔVB·rubbing(t).
  void fit_wear(const std::array<std::vector<double>, 2>& rubbing,
                const std::array<std::vector<double>, 2>& rest,
                const std::array<std::vector<double>, 2>& chain,
                std::array<std::vector<double>, 2>& wear_part, Evaluation& ev) const {
    double ata = 0.0, atb = 0.0;
    for (std::size_t a = 0; a < 2; ++a) {
      for (std::size_t i = 0; i < n_; ++i) {
        const double tau = 2.0 * static_cast<double>(i) / static_cast<double>(n_ - 1) - 1.0;
        ata += tau * rubbing[a][i] * tau * rubbing[a][i];
        atb += tau * rubbing[a][i] * (rest[a][i] - chain[a][i]);
      }
    }
    ev.wear_normal = ata;
    ev.wear_slope_um = ata > 0.0 ? atb / ata : 0.0;
    for (std::size_t a = 0; a < 2; ++a) {
      for (std::size_t i = 0; i < n_; ++i) {
        const double tau = 2.0 * static_cast<double>(i) / static_cast<double>(n_ - 1) - 1.0;
        wear_part[a][i] = tau * ev.wear_slope_um * rubbing[a][i];
      }
    }
  }

  /// When the synchronous pattern changed: the record cut into groups of revolutions, each
  /// group's synchronous harmonics; the one boundary that splits them into two groups of least
  /// scatter about their means. Returns the time and half a group (its resolution).
  std::pair<double, double> find_change(const State& s, const Evaluation& current) const {
    const double f = s.rpm / 60.0;
    const double revs = duration() * f;
    const int groups = std::max(8, std::min(48, static_cast<int>(revs / 3.0)));
    const std::size_t per = n_ / static_cast<std::size_t>(groups);
    const int k_max = std::min(harmonics(s.rpm), 4 * s.config.tool.flutes);
    std::vector<Eigen::VectorXd> x(static_cast<std::size_t>(groups));
    for (int g = 0; g < groups; ++g) {
      const std::size_t i0 = static_cast<std::size_t>(g) * per;
      Eigen::VectorXd v(4 * k_max);
      for (std::size_t a = 0; a < 2; ++a) {
        std::vector<double> y(per);
        for (std::size_t i = 0; i < per; ++i) {
          y[i] = rec_.force_N[a][i0 + i] - current.chain_N[a][i0 + i];
        }
        std::vector<std::complex<double>> h;
        synchronous_harmonics(y, fs_, f, k_max, h, kTwoPi * f / fs_ * static_cast<double>(i0));
        for (int k = 1; k <= k_max; ++k) {
          v[static_cast<Eigen::Index>(a * 2 * k_max + 2 * (k - 1))] =
              h[static_cast<std::size_t>(k)].real();
          v[static_cast<Eigen::Index>(a * 2 * k_max + 2 * (k - 1) + 1)] =
              h[static_cast<std::size_t>(k)].imag();
        }
      }
      x[static_cast<std::size_t>(g)] = v;
    }
    auto scatter = [&](int from, int to) {
      Eigen::VectorXd mean = Eigen::VectorXd::Zero(x[0].size());
      for (int g = from; g < to; ++g) {
        mean += x[static_cast<std::size_t>(g)];
      }
      mean /= std::max(1, to - from);
      double sum = 0.0;
      for (int g = from; g < to; ++g) {
        sum += (x[static_cast<std::size_t>(g)] - mean).squaredNorm();
      }
      return sum;
    };
    int best = groups / 2;
    double best_cost = 1e300;
    for (int j = 2; j <= groups - 2; ++j) {
      const double c = scatter(0, j) + scatter(j, groups);
      if (c < best_cost) {
        best_cost = c;
        best = j;
      }
    }
    const double group_s = static_cast<double>(per) / fs_;
    return {best * group_s, 0.5 * group_s};
  }

  /// What the harmonics 1..k_max at a trial speed explain of y − chain (the energy of its
  /// least-squares projection onto them and the mean, record_spectrum.hpp): what a correct time
  /// base maximises (the synchronous average is not smeared).
  double sync_energy(double rpm, const std::array<std::vector<double>, 2>& y, int k_max) {
    return harmonic_fit_energy(y, fs_, rpm / 60.0, k_max);
  }

  /// The actual speed: the synchronous energy's maximum within ±2.5 % of the commanded speed,
  /// with σ from its curvature. Coarse to fine: harmonic k's peak is 1/(k·revolutions) wide, so
  /// the search runs on the tooth-passing fundamental first (a grid of a quarter of its width),
  /// then on 4× more harmonics around the best, then on all of them, then a golden section. On
  /// a record of more than kSpeedSearchRevolutions revolutions the first grid runs on its leading
  /// quarter, sixteenth, … of at most that many, and each grid after it on a part 4× longer
  /// around the best of the last, up to the whole record: the first grid's trials grow with the
  /// revolutions it spans and each runs over every sample it holds, so on the whole of a long
  /// record it took time as the square of the record's length.
  std::pair<double, double> find_speed(double commanded_rpm, const Evaluation& current,
                                       int flutes) {
    std::array<std::vector<double>, 2> y;
    for (std::size_t a = 0; a < 2; ++a) {
      y[a].resize(n_);
      for (std::size_t i = 0; i < n_; ++i) {
        y[a][i] = rec_.force_N[a][i] - current.chain_N[a][i];
      }
    }
    const double revs = duration() * commanded_rpm / 60.0;
    // The same harmonics at every trial speed, all in the band at the fastest: were the top one
    // dropped above some speed, the energy would fall in a step there, which the search would
    // take for the maximum (and the curvature for a sharp one) when the speed lies beside it.
    const int k_all = harmonics(commanded_rpm * (1.0 + kSpeedSearchFraction));
    double best = commanded_rpm;
    double lo_rel = -kSpeedSearchFraction, hi_rel = kSpeedSearchFraction;
    int k = std::min(k_all, std::max(1, flutes));
    double step = 0.0;
    // A grid of trial speeds a quarter of harmonic k's peak width apart over [lo_rel, hi_rel]
    // around the best so far, on signals spanning `span_revs` revolutions.
    const auto grid = [&](const std::array<std::vector<double>, 2>& signals, double span_revs) {
      step = 0.25 / (k * span_revs);
      double best_p = -1.0;
      const double centre = best;
      for (double rel = lo_rel; rel <= hi_rel + 1e-12; rel += step) {
        const double rpm = centre * (1.0 + rel);
        const double p = sync_energy(rpm, signals, k);
        if (p > best_p) {
          best_p = p;
          best = rpm;
        }
      }
      lo_rel = -1.5 * step;
      hi_rel = 1.5 * step;
    };
    int quarters = 0;  // the first grid on the record's leading 4^−quarters
    while (revs / std::pow(4.0, quarters) > kSpeedSearchRevolutions) {
      ++quarters;
    }
    for (int q = quarters; q > 0; --q) {
      const auto length = static_cast<std::size_t>(static_cast<double>(n_) / std::pow(4.0, q));
      const std::array<std::vector<double>, 2> part = {
          std::vector<double>(y[0].begin(), y[0].begin() + static_cast<std::ptrdiff_t>(length)),
          std::vector<double>(y[1].begin(), y[1].begin() + static_cast<std::ptrdiff_t>(length))};
      grid(part, revs * static_cast<double>(length) / static_cast<double>(n_));
    }
    while (true) {
      grid(y, revs);
      if (k >= k_all) {
        break;
      }
      k = std::min(k_all, 4 * k);
    }
    // Golden section on ±one step.
    double lo = best * (1.0 - step), hi = best * (1.0 + step);
    const double g = 0.5 * (std::sqrt(5.0) - 1.0);
    double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
    double p1 = sync_energy(x1, y, k_all), p2 = sync_energy(x2, y, k_all);
    const auto narrow = [&](double width_rpm) {
      for (int it = 0; it < 60 && hi - lo > width_rpm; ++it) {
        if (p1 > p2) {
          hi = x2;
          x2 = x1;
          p2 = p1;
          x1 = hi - g * (hi - lo);
          p1 = sync_energy(x1, y, k_all);
        } else {
          lo = x1;
          x1 = x2;
          p1 = p2;
          x2 = lo + g * (hi - lo);
          p2 = sync_energy(x2, y, k_all);
        }
      }
    };
    // RSS(n) = Σy² − E(n): σ_n² = 2σ²/RSS''(n), σ² the per-sample noise variance.
    const double var = 0.5 * (floor_[0] * floor_[0] + floor_[1] * floor_[1]) *
                       static_cast<double>(n_fft_) / (2.0 * static_cast<double>(last_));
    const auto sigma_at = [&](double rpm) {
      const double h = 0.05 * step * commanded_rpm;
      const double d2 = (sync_energy(rpm + h, y, k_all) - 2.0 * sync_energy(rpm, y, k_all) +
                         sync_energy(rpm - h, y, k_all)) /
                        (h * h);
      const double curvature = std::fabs(d2);
      return curvature > 0.0 ? std::sqrt(2.0 * var / curvature) : rpm;
    };
    narrow(1e-9 * commanded_rpm);
    double rpm = 0.5 * (lo + hi);
    double sigma = sigma_at(rpm);
    // σ falls as the record's length to the power −3/2, below ten times the 1e-9 of the speed
    // from about 5 s of cutting (below 1e-9 from about 20 s): the search goes on to a tenth of
    // it there, so that the speed errs by its σ and not by the search's last interval.
    if (sigma > 0.0 && hi - lo > 0.1 * sigma) {
      narrow(std::max(0.1 * sigma, 1e-13 * commanded_rpm));
      rpm = 0.5 * (lo + hi);
      sigma = sigma_at(rpm);
    }
    // Not below what the record's own scatter says (speed_scatter.hpp): the curvature's σ takes
    // what the harmonics leave for the white noise of the floor, while on a real cut the
    // revolutions differ by more (PHM 2010 c1_cut315: ±0.0084 rpm from the curvature, ±0.051 rpm
    // from the scatter of its segments' delays).
    sigma = std::max(sigma, rpm * segment_speed_sigma_rel(y, fs_, rpm / 60.0, k_all));
    // Not below what the search resolved (a noise floor of 0 gives σ 0, a clean record's
    // rounding can stop the search short of a tenth of σ): the last interval's RMS.
    sigma = std::max(sigma, (hi - lo) / std::sqrt(12.0));
    return {rpm, sigma};
  }

  /// The model part's samples from a fitted configuration: the steady state at the time base's
  /// speed (its accumulation cycle, phased to the record), band-limited, aligned by δ.
  bool synthesize(const model::ModelConfig& fitted, double rpm, double delta, Evaluation& ev,
                  std::size_t i0, std::size_t i1) {
    const model::ModelConfig c = model::at_actual_speed(fitted, rpm);
    const model::SteadyState* st = nullptr;
    try {
      st = &model::evaluate_steady_state(c, rpm, opt_.steps_per_rev, workspace_,
                                         model::SteadyStateOutput::kMeanAndCycle);
    } catch (const std::exception& e) {
      ev.message = e.what();
      return false;
    }
    const int steps = st->steps_per_rev;
    const int cycle = st->cycle_revolutions > 1 && !st->cycle.fx_N.empty()
                          ? static_cast<int>(st->cycle.fx_N.size()) / steps
                          : 1;
    ev.cycle_revolutions = cycle;
    const double f = rpm / 60.0;
    if (st->stats.unconverged_slots >= ev.unsettled_slots) {
      ev.unsettled_slots = st->stats.unconverged_slots;
      ev.slots = st->stats.slots;
    }
    const int length = cycle * steps;  // the cycle's grid
    const int q_max =
        std::min(static_cast<int>(std::floor(band_ * cycle / f + 1e-9)), length / 2 - 1);
    // The band-limited cycle on a grid 4× finer than the model's (linear interpolation between
    // its points then errs by ~(πΔ/λ)²/2 of the shortest wave in the band: 0.03 % at the band's
    // edge with 720 steps), from the model's spectrum zero-padded.
    constexpr int kUp = 4;
    const int fine = kUp * length;
    std::array<std::vector<double>, 2> wave;
    Eigen::FFT<double> fft;
    for (std::size_t a = 0; a < 2; ++a) {
      const model::ForceWaveform& w = cycle > 1 ? st->cycle : st->mean;
      const std::vector<double>& v = a == 0 ? w.fx_N : w.fy_N;
      std::vector<std::complex<double>> spec;
      fft.fwd(spec, v);
      std::vector<std::complex<double>> padded(static_cast<std::size_t>(fine), {0.0, 0.0});
      for (int q = 1; q <= q_max; ++q) {
        // inv() divides by the length: kUp·X_q keeps the amplitude 2|X_q|/length.
        padded[static_cast<std::size_t>(q)] =
            static_cast<double>(kUp) * spec[static_cast<std::size_t>(q)];
        padded[static_cast<std::size_t>(fine - q)] = std::conj(padded[static_cast<std::size_t>(q)]);
      }
      std::vector<std::complex<double>> out;
      fft.inv(out, padded);
      wave[a].resize(static_cast<std::size_t>(fine) + 1);
      for (int g = 0; g < fine; ++g) {
        wave[a][static_cast<std::size_t>(g)] = out[static_cast<std::size_t>(g)].real();
      }
      wave[a][static_cast<std::size_t>(fine)] = wave[a][0];  // wraps for the interpolation
    }
    const double step = kTwoPi * f / fs_;  // spindle angle per sample
    // Grid position (fine points) of sample i with the model angle δ, in [0, fine).
    auto position = [&](std::size_t i, double d) {
      double u = (step * static_cast<double>(i) + d) / (kTwoPi * cycle) * fine;
      u = std::fmod(u, static_cast<double>(fine));
      return u < 0.0 ? u + fine : u;
    };
    // The cycle's phase: revolution m0 of the cycle at the record's revolution 0, and which
    // flute is flute 0 (the mean revolution the fitter aligned may be nearly the same turned by
    // a pitch, the cycle is not): the shift whose model correlates best with the record
    // (RSS = Σy² − 2·Σy·p + Σp², Σp² the same for every shift). The record is binned on the
    // cycle's grid once; each shift is then a sum over the grid.
    int m0 = 0;
    if (cycle > 1) {
      std::array<std::vector<double>, 2> binned;
      for (std::size_t a = 0; a < 2; ++a) {
        binned[a].assign(static_cast<std::size_t>(length), 0.0);
        for (std::size_t i = i0; i < i1; ++i) {
          const auto b = static_cast<std::size_t>(std::lround(position(i, delta) / kUp)) %
                         static_cast<std::size_t>(length);
          binned[a][b] += rec_.force_N[a][i];
        }
      }
      const bool uniform = fitted.tool.pitch_deg.empty();
      const int shifts = uniform ? fitted.tool.flutes : 1;
      double best = -1e300;
      int best_j = 0;
      for (int j = 0; j < shifts; ++j) {
        for (int m = 0; m < cycle; ++m) {
          const auto shift = static_cast<std::size_t>(m * steps + (j * steps) / shifts);
          double score = 0.0;
          for (std::size_t a = 0; a < 2; ++a) {
            for (std::size_t b = 0; b < static_cast<std::size_t>(length); ++b) {
              score +=
                  binned[a][b] * wave[a][kUp * ((b + shift) % static_cast<std::size_t>(length))];
            }
          }
          if (score > best) {
            best = score;
            m0 = m;
            best_j = j;
          }
        }
      }
      delta += kTwoPi * best_j / shifts;
    }
    ev.alignment_rad = delta;
    const double d0 = delta + kTwoPi * m0;
    if (!st->cycle_exact) {  // the cycle's revolution at the segment's first sample, then on
      ev.revolutions_round_again += revolutions_round_again(
          position(i0, d0) / (kUp * steps), static_cast<double>(i1 - i0) * f / fs_, cycle);
    }
    for (std::size_t a = 0; a < 2; ++a) {
      ev.model_N[a].resize(n_);
      for (std::size_t i = i0; i < i1; ++i) {
        const double u = position(i, d0);
        const auto g = static_cast<std::size_t>(u);
        const double t = u - static_cast<double>(g);
        const std::size_t g0 = std::min(g, static_cast<std::size_t>(fine - 1));
        ev.model_N[a][i] = (1.0 - t) * wave[a][g0] + t * wave[a][g0 + 1];
      }
    }
    return true;
  }

  /// The chain's basis at sample i: 1, Legendre P1, P2 of the time (drift), the mains' odd
  /// harmonics (hum) within the band.
  void chain_row(const State& s, std::size_t i, Eigen::Ref<Eigen::RowVectorXd> row) const {
    int c = 0;
    row[c++] = 1.0;
    const double tau =
        n_ > 1 ? 2.0 * static_cast<double>(i) / static_cast<double>(n_ - 1) - 1.0 : 0.0;
    if (s.drift_degree >= 1) {
      row[c++] = tau;
    }
    if (s.drift_degree >= 2) {
      row[c++] = 0.5 * (3.0 * tau * tau - 1.0);
    }
    if (s.hum_hz > 0.0) {
      const double t = static_cast<double>(i) / fs_;
      for (const double h : kHumHarmonics) {
        if (h * s.hum_hz <= band_) {
          row[c++] = std::cos(kTwoPi * h * s.hum_hz * t);
          row[c++] = std::sin(kTwoPi * h * s.hum_hz * t);
        }
      }
    }
  }

  [[nodiscard]] int chain_columns(const State& s) const {
    int c = 1 + s.drift_degree;
    if (s.hum_hz > 0.0) {
      for (const double h : kHumHarmonics) {
        c += h * s.hum_hz <= band_ ? 2 : 0;
      }
    }
    return c;
  }

  Eigen::MatrixXd chain_normal(const State& s) const {
    const int p = chain_columns(s);
    Eigen::MatrixXd ata = Eigen::MatrixXd::Zero(p, p);
    Eigen::RowVectorXd row(p);
    for (std::size_t i = 0; i < n_; ++i) {
      chain_row(s, i, row);
      ata.noalias() += row.transpose() * row;
    }
    return ata;
  }

  void chain_fit(const State& s, const std::vector<double>& y, std::vector<double>& fitted,
                 Eigen::VectorXd& coefficients) const {
    const int p = chain_columns(s);
    Eigen::VectorXd atb = Eigen::VectorXd::Zero(p);
    Eigen::RowVectorXd row(p);
    for (std::size_t i = 0; i < n_; ++i) {
      chain_row(s, i, row);
      atb += row.transpose() * y[i];
    }
    coefficients = chain_normal(s).ldlt().solve(atb);
    fitted.resize(n_);
    for (std::size_t i = 0; i < n_; ++i) {
      chain_row(s, i, row);
      fitted[i] = row.dot(coefficients);
    }
  }

  Eigen::VectorXd chain_sigma(const State& s, double variance) const {
    const Eigen::MatrixXd inv = chain_normal(s).inverse();
    return (variance * inv.diagonal()).cwiseSqrt();
  }

 private:
  const CutRecord& rec_;
  const DiagnoseOptions& opt_;
  double fs_ = 0.0;
  std::size_t n_ = 0;
  std::size_t n_fft_ = 0;
  std::size_t last_ = 0;
  double band_ = 0.0;
  std::array<double, 2> floor_{};
  std::array<double, 2> measured_rms_{};
  model::SteadyStateWorkspace workspace_;

  friend class Diagnoser;
};

/// The radius difference r_j − r_CE1 of a flute j the fit leaves idle on a contact edge is a
/// bound, as ρ is: the idle flute's radius lies at least the largest chip below the flute's
/// before it, so r_j − r_CE1 is at most its value. (CE1 is the flute with the largest cut: never
/// the idle one.)
void bound_radius(const identify::FitResult& fit, std::size_t j, Parameter& p) {
  if (fit.runout_at_contact_edge && fit.edge_flute >= 0 &&
      static_cast<std::size_t>(fit.edge_flute) == j) {
    p.upper_bound = true;
  }
}

/// Parameters held at a physical bound (name → "lower"/"upper"), each with its value in
/// `config` (the bound) and no σ.
std::vector<Parameter> held_parameters(
    model::ModelConfig config, const std::vector<std::pair<std::string, std::string>>& held) {
  std::vector<Parameter> out;
  for (const auto& [name, side] : held) {
    out.emplace_back(name, dynamometer_parameter(config, name), 0.0, side);
  }
  return out;
}

/// The parameters a candidate added, from its evaluation.
std::vector<Parameter> added_parameters(const std::string& name, const State& s,
                                        const Evaluation& ev, double duration_s) {
  std::vector<Parameter> out;
  const auto& fit = ev.fit;
  if (name == "runout") {
    out.push_back({"rho_um", fit.rho_um.value, fit.rho_um.sigma});
    out.back().lower_bound = fit.runout_at_contact_edge;
    out.push_back(
        {"gamma_deg", fit.gamma_rad.value * 180.0 / kPi, fit.gamma_rad.sigma * 180.0 / kPi});
    for (std::size_t j = 1; j < fit.radius_from_ce1_um.size(); ++j) {
      const auto& d = fit.radius_from_ce1_um[j];
      out.push_back({d.name, d.value, d.sigma});
      bound_radius(fit, j, out.back());
    }
  } else if (profiles_h_min(name)) {
    out.push_back({"h_min_um", s.config.effects.min_chip.h_min_um, s.h_min_sigma_um});
    if (!s.h_min_bound.empty()) {
      Parameter& h = out.back();
      h.upper_bound = s.h_min_bound == "upper";
      h.lower_bound = !h.upper_bound;
      h.sigma = 0.0;
      const double per_feed = h.value / s.config.process.feed_per_tooth_um;
      h.bound_note =
          h.upper_bound
              ? format(
                    "the least the profile tries (%.3f·f_t): no larger minimum chip "
                    "thickness fits better",
                    per_feed)
              : format("the largest the profile tries (%.2f·f_t): every chip ploughs", per_feed);
    }
    for (const auto& c : fit.coefficients) {
      if (is_ploughing_coefficient(c.name)) {
        out.push_back({c.name, c.value, c.sigma});
        out.back().determined = c.determined;
      }
    }
    if (name == "chip_accumulation") {
      out.push_back({"cycle_revolutions", static_cast<double>(ev.cycle_revolutions), 0.0});
    }
  } else if (name == "tool_deflection" || name == "dynamometer_dynamics") {
    const auto wanted = [&](const std::string& n) {
      if (name == "tool_deflection") {
        return n == "stiffness_N_per_um";
      }
      if (name == "dynamometer_dynamics") {
        return n.rfind("natural_hz", 0) == 0 || n.rfind("damping_ratio", 0) == 0;
      }
      return false;
    };
    for (const auto& e : fit.extra) {
      if (wanted(e.name)) {
        out.push_back({e.name, e.value, e.sigma, ""});
        out.back().determined = e.determined;
      }
    }
    if (name == "dynamometer_dynamics") {
      for (auto& p : held_parameters(fit.config, ev.at_bound)) {
        out.push_back(std::move(p));
      }
    }
  } else if (name == "spindle_speed_error") {
    out.push_back({"spindle_rpm", s.rpm, s.rpm_sigma});
    const double cmd = s.config.process.spindle_rpm;
    out.push_back({"speed_error_percent", 100.0 * (s.rpm / cmd - 1.0), 100.0 * s.rpm_sigma / cmd});
  } else if (name == "runout_change") {
    out.push_back({"change_time_s", s.change_s, s.change_sigma_s});
    const identify::FitResult* fits[2] = {&ev.fit_before, &fit};
    const char* when[2] = {"before", "after"};
    for (int w = 0; w < 2; ++w) {
      const auto& f = *fits[w];
      out.push_back({std::string("rho_") + when[w] + "_um", f.rho_um.value, f.rho_um.sigma});
      out.back().lower_bound = f.runout_at_contact_edge;
      out.push_back({std::string("gamma_") + when[w] + "_deg", f.gamma_rad.value * 180.0 / kPi,
                     f.gamma_rad.sigma * 180.0 / kPi});
      if (f.radius_from_ce1_um.size() > 1) {
        out.push_back({std::string("r_ce2_minus_r_ce1_") + when[w] + "_um",
                       f.radius_from_ce1_um[1].value, f.radius_from_ce1_um[1].sigma});
        bound_radius(f, 1, out.back());
      }
    }
  } else if (name == "tool_wear") {
    bool mid_determined = true;
    for (const auto& e : fit.extra) {
      if (e.name == "wear_um") {
        out.push_back({"wear_mid_um", e.value, e.sigma});
        out.back().determined = e.determined;
        mid_determined = e.determined;
      }
    }
    // The growth scales the same rubbing force: where the wear land is not pinned (the rubbing
    // hardly moves the force), neither is its growth (its σ, over a rubbing norm near 0, then
    // runs to 1e150).
    const double growth = 2.0 * ev.wear_slope_um, growth_sigma = 2.0 * ev.wear_slope_sigma_um;
    const bool growth_determined =
        mid_determined && std::isfinite(growth_sigma) &&
        growth_sigma <= identify::kUndeterminedSigmaRatio * std::max(std::fabs(growth), 1.0);
    out.push_back({"wear_growth_um", growth, growth_determined ? growth_sigma : 0.0});
    out.back().determined = growth_determined;
    out.push_back({"wear_rate_um_per_s", growth / duration_s,
                   growth_determined ? growth_sigma / duration_s : 0.0});
    out.back().determined = growth_determined;
  } else if (name == "amplifier_drift") {
    const char* axis[2] = {"x", "y"};
    for (std::size_t a = 0; a < 2; ++a) {
      // c1·τ with τ = 2t/T − 1: a slope of 2·c1/T.
      out.push_back({std::string("drift_N_per_s_") + axis[a],
                     2.0 * ev.chain_coefficients[a][1] / duration_s,
                     2.0 * ev.chain_sigma[a][1] / duration_s});
      out.push_back({std::string("curvature_N_") + axis[a], ev.chain_coefficients[a][2],
                     ev.chain_sigma[a][2]});
    }
  } else if (name == "mains_hum") {
    out.push_back({"mains_hz", s.hum_hz, 0.0});
    const char* axis[2] = {"x", "y"};
    const int first = 1 + s.drift_degree;
    for (std::size_t a = 0; a < 2; ++a) {
      int c = first;
      for (const double h : kHumHarmonics) {
        if (c + 1 >= ev.chain_coefficients[a].size()) {
          break;
        }
        const double amp = std::hypot(ev.chain_coefficients[a][c], ev.chain_coefficients[a][c + 1]);
        out.push_back(
            {"amplitude_N_" + std::to_string(static_cast<int>(h * s.hum_hz)) + "hz_" + axis[a], amp,
             ev.chain_sigma[a][c]});
        c += 2;
      }
    }
  }
  return out;
}

std::vector<Parameter> coefficients_of(const Evaluation& ev) {
  std::vector<Parameter> out;
  for (const auto& e : ev.fit.coefficients) {
    out.push_back({e.name, e.value, e.sigma});
    out.back().determined = e.determined;
  }
  return out;
}

/// Engagement angles [θ_st, θ_ex] of a flute (rad), model_config.hpp's convention.
std::pair<double, double> engagement(const model::ModelConfig& c) {
  const double r = model::tool_radius_um(c) / 1000.0;
  const double ae = std::clamp(c.process.radial_depth_mm, 0.0, 2.0 * r);
  const double width = std::acos(std::clamp(1.0 - ae / r, -1.0, 1.0));
  switch (c.process.operation) {
    case model::Operation::kSlot:
      return {0.0, kPi};
    case model::Operation::kUpMilling:
      return {0.0, width};
    case model::Operation::kDownMilling:
      return {kPi - width, kPi};
  }
  return {0.0, kPi};
}

double wrap_2pi(double a) {
  a = std::fmod(a, kTwoPi);
  return a < 0.0 ? a + kTwoPi : a;
}

}  // namespace

class Diagnoser {
 public:
  Diagnoser(const CutRecord& record, const model::ModelConfig& start, const DiagnoseOptions& o)
      : rec_(record), start_(start), opt_(o), engine_(record, o) {}

  Diagnosis run();

 private:
  void progress(const std::string& line) const {
    if (opt_.progress) {
      const std::lock_guard lock(progress_mutex_);
      opt_.progress(line);
    }
  }
  /// Adds a candidate to a state; false with `why` when it does not apply (already in).
  /// `engine`: the workspace its searches (the speed's, the change's) run on.
  bool apply(Engine& engine, const std::string& name, State& s, const Evaluation& current,
             std::string& why);
  /// Takes an effect the search named out of a state; false where it cannot be taken out alone
  /// (the speed and the chain's terms, which nothing else stands in for; min_chip under
  /// chip_accumulation or ploughing_area; runout under runout_change).
  bool remove(const std::string& name, State& s, const std::vector<std::string>& named) const;
  /// Scores every candidate of `names` but the `excluded` on `state` (`current` its evaluation).
  /// Their fits run on opt_.jobs engines at once; the round is read in the order of `names`.
  Round score_round(const State& state, const Evaluation& current,
                    const std::vector<std::string>& names, const std::string& label,
                    const std::vector<std::string>& excluded);
  /// One candidate added to `s` (the round's state) and fitted on `engine`: its score, or
  /// nothing where it does not apply (in the model already); `ev` its evaluation.
  std::optional<CandidateScore> score_candidate(Engine& engine, const std::string& name, State& s,
                                                const Evaluation& current, Evaluation& ev);
  /// Calls work(engine, i) for each i of `order` (a permutation of [0, count)), started in that
  /// order, on up to opt_.jobs threads with an engine each (the calling thread's is engine_);
  /// the first exception a call throws is thrown again once all have ended.
  /// Called from a thread run_on_engines() started (a candidate's profile), it runs the calls
  /// one after the other on `caller`, that thread's engine; otherwise `caller` is engine_.
  template <typename Work>
  void run_on_engines(Engine& caller, std::size_t count, const std::vector<std::size_t>& order,
                      const Work& work);
  /// run_on_engines() in the order 0, 1, …
  template <typename Work>
  void run_on_engines(Engine& caller, std::size_t count, const Work& work) {
    std::vector<std::size_t> order(count);
    for (std::size_t i = 0; i < count; ++i) {
      order[i] = i;
    }
    run_on_engines(caller, count, order, work);
  }
  /// Takes the round's best into the model: refitted with the model's variants (where
  /// `with_variants`) if that holds `required_gain` over `current`, its stage recorded
  /// (`removed`: the effect it replaces).
  void accept(Round& round, State& state, Evaluation& current, Diagnosis& out,
              const std::string& removed, double required_gain, bool with_variants);
  /// The replacement step: each effect named taken out, the best candidate in its place and the
  /// best step after it, neither putting it back; the best such exchange taken where it gains
  /// `significance`. `trigger`: the round from the current model in which no candidate gained
  /// (kept on the exchange's stage).
  bool exchange(State& state, Evaluation& current, Diagnosis& out,
                const std::vector<std::string>& names, const std::vector<CandidateScore>& trigger);
  Stage stage_of(const std::string& added, const State& s, const Evaluation& ev);
  /// Each named effect's parameters in the final model (`s`, fitted by `ev`); the dynamometer's
  /// held ones with their bound.
  std::vector<EffectParameters> final_parameters(const std::vector<std::string>& named,
                                                 const State& s, const Evaluation& ev) const;
  /// h_min by its profile: the chip regime switches on the model's angle grid, so the force is
  /// piecewise constant in h_min on a fine scale and a derivative-based fit would not move it.
  /// The criterion on a geometric grid of h_min over (0.02, 1.6)·f_t: the best point, its
  /// neighbours, and σ the grid's resolution. Where the best is an end of the grid, h_min is a
  /// bound (State::h_min_bound), not an estimate. Candidates are scored on the grid alone.
  Evaluation profile_h_min(Engine& engine, State& s, const Evaluation& current,
                           const Evaluation* from = nullptr);
  /// Fits s at its h_min from the current fit, with the grid's neighbours as refine_h_min()'s
  /// bracket.
  Evaluation evaluate_at_h_min(Engine& engine, State& s, const Evaluation& current);
  /// A golden section between the best grid point's neighbours (`best`: its evaluation); σ
  /// from the profile's curvature (Δ(−2 ln L) = 1). For a step taken and the final model.
  Evaluation refine_h_min(Engine& engine, State& s, const Evaluation& current,
                          const Evaluation* from, Evaluation best);
  /// h_min profiled again in the final model, where min_chip_thickness, chip_accumulation or
  /// ploughing_area was named: a step profiles it in its own model, and what later steps add moves
  /// it (the cp-Ti preset's cut at 20 kHz: 0.08 µm where chip_accumulation came in before the
  /// deflection, 0.198 µm in the final model, truth 0.2).
  void final_h_min(State& state, Evaluation& current, Diagnosis& out);
  /// The stiffness from a start on a grid (0.05 to 3.2 N/µm, factors of 2, each refined from
  /// the current fit with the stiffness fixed): Levenberg–Marquardt from a far start can stall
  /// where the deflection hardly changes the force.
  Evaluation profile_stiffness(Engine& engine, State& s, const Evaluation& current);

  Localisation localise(const State& s, const Evaluation& ev, ModelView& view);

  const CutRecord& rec_;
  model::ModelConfig start_;
  const DiagnoseOptions& opt_;
  Engine engine_;
  // The engines of run_on_engines()' other threads (made when first needed): an engine's model
  // workspace is one fit's state.
  std::vector<std::unique_ptr<Engine>> helpers_;
  mutable std::mutex progress_mutex_;  // progress() from several threads
  bool engines_running_ = false;       // run_on_engines() has threads out (set by the caller's)
};

bool Diagnoser::apply(Engine& engine, const std::string& name, State& s, const Evaluation& current,
                      std::string& why) {
  auto& e = s.config.effects;
  auto add_extra = [&](const std::string& p) {
    if (std::find(s.extra.begin(), s.extra.end(), p) == s.extra.end()) {
      s.extra.push_back(p);
    }
  };
  if (name == "runout") {
    if (s.fit_runout) {
      why = "already in the model";
      return false;
    }
    s.fit_runout = true;
    e.runout.enabled = true;
  } else if (name == "min_chip_thickness") {
    if (e.min_chip.enabled) {
      why = "already in the model";
      return false;
    }
    e.min_chip.enabled = true;
  } else if (name == "chip_accumulation") {
    if (e.accumulation.enabled) {
      why = "already in the model";
      return false;
    }
    e.min_chip.enabled = true;
    e.accumulation.enabled = true;
    e.multi_pass.enabled = true;
  } else if (name == "ploughing_area") {
    if (s.config.material.law != model::ForceLawKind::kLinearEdge) {
      why = "not for this force law: the ploughed area is the linear law's ([001] eqs 18-21)";
      return false;
    }
    if (s.config.material.linear_edge.ploughing_area) {
      why = "already in the model";
      return false;
    }
    // The ploughed area is the one swept while the chip is below h_min ([001] eqs 14-17).
    s.config.material.linear_edge.ploughing_area = true;
    e.min_chip.enabled = true;
  } else if (name == "tool_deflection") {
    if (e.deflection.enabled) {
      why = "already in the model";
      return false;
    }
    e.deflection.enabled = true;
    add_extra("stiffness_N_per_um");
  } else if (name == "helix_lag") {
    if (e.helix_lag.enabled) {
      why = "already in the model";
      return false;
    }
    e.helix_lag.enabled = true;
    e.helix_lag.discs = opt_.helix_discs;
  } else if (name == "trochoidal_path") {
    if (e.trochoidal.enabled) {
      why = "already in the model";
      return false;
    }
    e.trochoidal.enabled = true;
  } else if (name == "dynamometer_dynamics") {
    if (e.dynamometer.enabled) {
      why = "already in the model";
      return false;
    }
    e.dynamometer.enabled = true;
    for (const char* p : {"natural_hz_x", "natural_hz_y", "damping_ratio_x", "damping_ratio_y"}) {
      add_extra(p);
    }
  } else if (name == "spindle_speed_error") {
    if (s.speed_fitted) {
      why = "already in the model";
      return false;
    }
    const auto [rpm, sigma] =
        engine.find_speed(s.config.process.spindle_rpm, current, s.config.tool.flutes);
    s.rpm = rpm;
    s.rpm_sigma = sigma;
    s.speed_fitted = true;
  } else if (name == "runout_change") {
    if (s.change_s > 0.0) {
      why = "already in the model";
      return false;
    }
    const auto [t, sigma] = engine.find_change(s, current);
    s.change_s = t;
    s.change_sigma_s = sigma;
    s.fit_runout = true;
    e.runout.enabled = true;
  } else if (name == "tool_wear") {
    if (s.wear_trend) {
      why = "already in the model";
      return false;
    }
    // The wear at mid-record is the fitter's (flank_wear's wear_um, fitted with the force
    // coefficients on the synchronous average: the mean rubbing in its own shape); its growth
    // over the record is a trend of that rubbing force, linear in time.
    s.wear_trend = true;
    e.flank_wear.enabled = true;
    e.flank_wear.wear_um.assign(1, 2.0);
    add_extra("wear_um");
  } else if (name == "amplifier_drift") {
    if (s.drift_degree > 0) {
      why = "already in the model";
      return false;
    }
    s.drift_degree = 2;
  } else if (name == "mains_hum") {
    if (s.hum_hz > 0.0) {
      why = "already in the model";
      return false;
    }
    s.hum_hz = 50.0;  // run() tries 60 Hz as well
  } else {
    why = "not in the catalogue";
    return false;
  }
  return true;
}

Evaluation Diagnoser::profile_h_min(Engine& engine, State& s, const Evaluation& current,
                                    const Evaluation* from) {
  const double ft = s.config.process.feed_per_tooth_um;
  std::vector<double> grid;  // down from the largest to the first point at or below the least
  for (double h = kHMinHighestPerFeed * ft; grid.empty() || grid.back() > kHMinLowestPerFeed * ft;
       h /= kHMinGridRatio) {
    grid.push_back(h);
  }
  std::reverse(grid.begin(), grid.end());
  // The first of the lowest criteria; only its evaluation is kept.
  std::size_t best = 0;
  Evaluation best_ev;
  std::mutex best_mutex;
  run_on_engines(engine, grid.size(), [&](Engine& on, std::size_t i) {
    State t = s;
    t.config.effects.min_chip.h_min_um = grid[i];
    Evaluation ev = on.evaluate(t, &current, false, from);
    const std::lock_guard lock(best_mutex);
    if (ev.ok && (!best_ev.ok || ev.criterion < best_ev.criterion ||
                  (ev.criterion == best_ev.criterion && i < best))) {
      best = i;
      best_ev = std::move(ev);
    }
  });
  if (!best_ev.ok) {
    return best_ev;
  }
  s.config.effects.min_chip.h_min_um = grid[best];
  // Until refine_h_min(): the grid's resolution.
  s.h_min_sigma_um = grid[best] * 0.5 * (kHMinGridRatio - 1.0);
  s.h_min_bracket_um = {grid[best > 0 ? best - 1 : 0], grid[std::min(best + 1, grid.size() - 1)]};
  // The least (largest) h of the grid the best: the minimum is not bracketed, whatever a golden
  // section finds inside the first (last) interval.
  s.h_min_bound = best == 0 ? "upper" : best + 1 == grid.size() ? "lower" : "";
  s.h_min_from_current = false;
  return best_ev;
}

Evaluation Diagnoser::evaluate_at_h_min(Engine& engine, State& s, const Evaluation& current) {
  const double h = s.config.effects.min_chip.h_min_um;
  s.h_min_bracket_um = {h / kHMinGridRatio, h * kHMinGridRatio};
  s.h_min_from_current = true;
  // From the current fit: a fresh search (its starts and alignment scan) of the area law over
  // an accumulation cycle takes ~30 s on the AlSi10Mg preset's 1.5 s record.
  return engine.evaluate(s, &current, false, &current);
}

Evaluation Diagnoser::refine_h_min(Engine& engine, State& s, const Evaluation& current,
                                   const Evaluation* from, Evaluation best_ev) {
  const double ft = s.config.process.feed_per_tooth_um;
  auto at_on = [&](Engine& on, double h) {
    State t = s;
    t.config.effects.min_chip.h_min_um = h;
    return on.evaluate(t, &current, false, from);
  };
  auto at = [&](double h) { return at_on(engine, h); };
  // Two points fitted at once (on two threads where there are).
  auto both = [&](double h1, double h2, Evaluation& first, Evaluation& second) {
    run_on_engines(engine, 2, [&](Engine& on, std::size_t i) {
      (i == 0 ? first : second) = at_on(on, i == 0 ? h1 : h2);
    });
  };
  // Golden section (in log h) between the best grid point's neighbours.
  double lo = std::log(s.h_min_bracket_um[0]);
  double hi = std::log(s.h_min_bracket_um[1]);
  double best_h = s.config.effects.min_chip.h_min_um;
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
  Evaluation e1, e2;
  both(std::exp(x1), std::exp(x2), e1, e2);
  for (int it = 0; it < 7; ++it) {
    const double c1 = e1.ok ? e1.criterion : 1e300, c2 = e2.ok ? e2.criterion : 1e300;
    if (c1 < best_ev.criterion) {
      best_ev = e1;
      best_h = std::exp(x1);
    }
    if (c2 < best_ev.criterion) {
      best_ev = e2;
      best_h = std::exp(x2);
    }
    if (c1 < c2) {
      hi = x2;
      x2 = x1;
      e2 = std::move(e1);
      x1 = hi - g * (hi - lo);
      e1 = at(std::exp(x1));
    } else {
      lo = x1;
      x1 = x2;
      e1 = std::move(e2);
      x2 = lo + g * (hi - lo);
      e2 = at(std::exp(x2));
    }
  }
  // σ: the criterion's (−2 ln L + const) curvature at the optimum, from ±5 %.
  const double d = 0.05 * best_h;
  Evaluation ep, em;
  both(best_h + d, best_h - d, ep, em);
  double sigma = best_h;  // unpinned unless the profile says otherwise
  if (ep.ok && em.ok) {
    const double curvature = (ep.criterion - 2.0 * best_ev.criterion + em.criterion) / (d * d);
    if (curvature > 0.0) {
      sigma = std::min(best_h, std::sqrt(2.0 / curvature));
    }
  }
  // Not below the grid's resolution of h (a step of the angle grid at the entry, f_t·Δφ).
  s.h_min_sigma_um = std::max(sigma, ft * kTwoPi / opt_.steps_per_rev);
  s.config.effects.min_chip.h_min_um = best_h;
  return best_ev;
}

void Diagnoser::final_h_min(State& state, Evaluation& current, Diagnosis& out) {
  if (!state.config.effects.min_chip.enabled ||
      std::none_of(out.named_effects.begin(), out.named_effects.end(), profiles_h_min)) {
    return;
  }
  progress("h_min profiled again in the final model");
  const double before_um = state.config.effects.min_chip.h_min_um;
  State t = state;
  Evaluation ev = profile_h_min(engine_, t, current, &current);
  if (ev.ok) {
    ev = refine_h_min(engine_, t, current, &current, std::move(ev));
  }
  if (!ev.ok || !(ev.criterion < current.criterion)) {
    out.final_notes.push_back(format(
        "h_min profiled again in the final model: no value fits better than %.3f µm", before_um));
    return;
  }
  // Its σ with the model's variants, as every accepted step's: that refit stands where it
  // still beats the model before (it may end a little above the profile's fit, whose σ would
  // be the statistical one alone).
  Evaluation sys = engine_.evaluate(t, &current, opt_.uncertainties, &ev);
  const bool systematic = opt_.uncertainties && sys.ok && sys.criterion < current.criterion;
  Evaluation& taken = systematic ? sys : ev;
  const double gain = current.criterion - taken.criterion;
  t.config = taken.fit.config;
  current = std::move(taken);
  state = t;
  const double after_um = state.config.effects.min_chip.h_min_um;
  out.final_notes.push_back(
      (format("%.3f", after_um) == format("%.3f", before_um)  // the same to the digits shown
           ? format("h_min profiled again in the final model: %.3f µm, as its step had found "
                    "(ΔBIC %.1f from the refit)",
                    after_um, gain)
           : format("h_min profiled again in the final model: %.3f µm, where its step had found "
                    "%.3f µm in the model of the time (ΔBIC %.1f)",
                    after_um, before_um, gain)) +
      (state.h_min_bound == "upper" ? "; the least the profile tries: the record shows no "
                                      "minimum chip thickness above it"
                                    : "") +
      (systematic || !opt_.uncertainties
           ? ""
           : "; every σ statistical only (the refit with the model's variants did not hold)"));
}

Evaluation Diagnoser::profile_stiffness(Engine& engine, State& s, const Evaluation& current) {
  State fixed = s;
  fixed.extra.erase(std::remove(fixed.extra.begin(), fixed.extra.end(), "stiffness_N_per_um"),
                    fixed.extra.end());
  Evaluation best;
  double best_k = s.config.effects.deflection.stiffness_N_per_um;
  for (double k = 0.05; k <= 3.3; k *= 2.0) {
    fixed.config.effects.deflection.stiffness_N_per_um = k;
    Evaluation ev = engine.evaluate(fixed, &current, false, &current);
    if (ev.ok && (!best.ok || ev.criterion < best.criterion)) {
      best = std::move(ev);
      best_k = k;
    }
  }
  s.config.effects.deflection.stiffness_N_per_um = best_k;
  if (best.ok) {
    s.config = best.fit.config;
    s.config.effects.deflection.stiffness_N_per_um = best_k;
  }
  Evaluation ev = engine.evaluate(s, &current, false, best.ok ? &best : nullptr);
  return ev.ok || !best.ok ? ev : best;
}

Localisation Diagnoser::localise(const State& s, const Evaluation& ev, ModelView& view) {
  Localisation loc;
  const double fs = rec_.sample_rate_hz;
  const std::size_t n = rec_.force_N[0].size();
  const double f = s.rpm / 60.0;
  const int k_max = engine_.harmonics(s.rpm);
  const double delta = ev.alignment_rad;
  const model::ModelConfig& c = ev.fit.config;
  const int flutes = c.tool.flutes;
  const std::vector<double> psi = model::flute_pitch_angles_rad(c.tool);
  const auto [th_st, th_ex] = engagement(c);
  constexpr int kGrid = 360;

  // Synchronous residual and measured/model averages over one revolution, in the model's frame.
  std::array<std::vector<std::complex<double>>, 2> res, meas, mod;
  for (std::size_t a = 0; a < 2; ++a) {
    std::vector<double> y(n), r(n);
    for (std::size_t i = 0; i < n; ++i) {
      y[i] = rec_.force_N[a][i] - ev.chain_N[a][i];
      r[i] = y[i] - ev.model_N[a][i];
    }
    synchronous_harmonics(y, fs, f, k_max, meas[a]);
    synchronous_harmonics(r, fs, f, k_max, res[a]);
    synchronous_harmonics(ev.model_N[a], fs, f, k_max, mod[a]);
  }
  loc.flute_rms_N.assign(static_cast<std::size_t>(flutes), {0.0, 0.0});
  std::vector<int> flute_count(static_cast<std::size_t>(flutes), 0);
  int edge_count = 0, middle_count = 0;
  view.angle_deg.resize(kGrid);
  for (std::size_t a = 0; a < 2; ++a) {
    view.measured_N[a].resize(kGrid);
    view.model_N[a].resize(kGrid);
  }
  for (int g = 0; g < kGrid; ++g) {
    const double alpha = kTwoPi * g / kGrid;  // model angle
    const double phi = alpha - delta;         // tracker angle
    view.angle_deg[static_cast<std::size_t>(g)] = alpha * 180.0 / kPi;
    std::array<double, 2> r{};
    for (std::size_t a = 0; a < 2; ++a) {
      double rv = 0.0, mv = meas[a][0].real(), dv = meas[a][0].real();
      for (int k = 1; k <= k_max; ++k) {
        const std::complex<double> e = std::polar(1.0, k * phi);
        const auto kk = static_cast<std::size_t>(k);
        rv += std::real(res[a][kk] * e);
        mv += std::real(meas[a][kk] * e);
        dv += std::real(mod[a][kk] * e);
      }
      r[a] = rv;
      view.measured_N[a][static_cast<std::size_t>(g)] = mv;
      view.model_N[a][static_cast<std::size_t>(g)] = dv;
      loc.synchronous_rms_N[a] += rv * rv;
    }
    for (int j = 0; j < flutes; ++j) {
      const double theta = wrap_2pi(alpha - psi[static_cast<std::size_t>(j)]);
      const double next = j + 1 < flutes ? psi[static_cast<std::size_t>(j + 1)] : kTwoPi;
      const double pitch = next - psi[static_cast<std::size_t>(j)];
      if (wrap_2pi(theta - th_st) < pitch) {
        for (std::size_t a = 0; a < 2; ++a) {
          loc.flute_rms_N[static_cast<std::size_t>(j)][a] += r[a] * r[a];
        }
        ++flute_count[static_cast<std::size_t>(j)];
      }
      if (theta >= th_st && theta <= th_ex) {
        const double u = (theta - th_st) / std::max(th_ex - th_st, 1e-9);
        if (u < 0.15 || u > 0.85) {
          for (std::size_t a = 0; a < 2; ++a) {
            loc.entry_exit_rms_N[a] += r[a] * r[a];
          }
          ++edge_count;
        } else if (u > 0.3 && u < 0.7) {
          for (std::size_t a = 0; a < 2; ++a) {
            loc.middle_rms_N[a] += r[a] * r[a];
          }
          ++middle_count;
        }
      }
    }
  }
  for (std::size_t a = 0; a < 2; ++a) {
    loc.synchronous_rms_N[a] = std::sqrt(loc.synchronous_rms_N[a] / kGrid);
    loc.entry_exit_rms_N[a] = std::sqrt(loc.entry_exit_rms_N[a] / std::max(1, edge_count));
    loc.middle_rms_N[a] = std::sqrt(loc.middle_rms_N[a] / std::max(1, middle_count));
    for (int j = 0; j < flutes; ++j) {
      auto& v = loc.flute_rms_N[static_cast<std::size_t>(j)][a];
      v = std::sqrt(v / std::max(1, flute_count[static_cast<std::size_t>(j)]));
    }
  }

  // Frequency bands of the residual's spectrum.
  const std::size_t nfft = smooth_length(n);
  const std::size_t last = engine_.last();
  const double df = fs / static_cast<double>(nfft);
  const double tooth = flutes * f;
  const auto& dyn = c.effects.dynamometer;
  const double res_lo = 0.85 * std::min(dyn.natural_hz[0], dyn.natural_hz[1]);
  const double res_hi = 1.15 * std::max(dyn.natural_hz[0], dyn.natural_hz[1]);
  struct Acc {
    const char* name;
    const char* range;
    std::array<double, 2> power{};
    int bins = 0;
  };
  std::array<Acc, 7> acc = {{
      {"low_frequency", "below half the spindle frequency: drift", {}, 0},
      {"mains", "50/60 Hz and odd harmonics", {}, 0},
      {"tooth_passing_harmonics", "multiples of the tooth-passing frequency", {}, 0},
      {"spindle_harmonics", "spindle harmonics that are not tooth-passing ones: runout", {}, 0},
      {"resonance_band", "within 15 % of the dynamometer's nominal resonance", {}, 0},
      {"between_harmonics_lines", "lines between the spindle harmonics: sub-harmonics", {}, 0},
      {"broadband", "the rest", {}, 0},
  }};
  // The residual's Hann-windowed spectrum: a strong line's leakage falls as 1/Δ³ instead of
  // 1/Δ and stays in its own band. Power scaled so that a band's RMS is the unwindowed one's
  // (Σw² = 3N/8). A bin is a line when it stands 10× above the noise's mean bin power.
  std::array<std::vector<std::complex<double>>, 2> hann;
  for (std::size_t a = 0; a < 2; ++a) {
    std::vector<double> r(nfft);
    for (std::size_t i = 0; i < nfft; ++i) {
      r[i] = rec_.force_N[a][i] - ev.model_N[a][i] - ev.chain_N[a][i];
    }
    hann[a] = spectrum(r, last + 1, true);
  }
  const double window_power = 0.375 * static_cast<double>(nfft);
  std::array<double, 2> noise_bin{};
  for (std::size_t a = 0; a < 2; ++a) {
    noise_bin[a] = engine_.floor()[a] * engine_.floor()[a] * static_cast<double>(nfft) *
                   window_power / (2.0 * static_cast<double>(last));
  }
  const double tol = 2.5 * df + 0.5;
  auto near_multiple = [&](double fr, double base) {
    if (base <= 0.0) {
      return false;
    }
    const double m = std::round(fr / base);
    return m >= 1.0 && std::fabs(fr - m * base) <= tol;
  };
  for (std::size_t b = 1; b <= last; ++b) {
    const double fr = static_cast<double>(b) * df;
    int cls = 6;
    bool mains = false;
    for (const double base : {50.0, 60.0}) {
      for (int h = 1; h <= 9; h += 2) {
        mains = mains || std::fabs(fr - h * base) <= tol;
      }
    }
    const bool line =
        std::norm(hann[0][b]) > 10.0 * noise_bin[0] || std::norm(hann[1][b]) > 10.0 * noise_bin[1];
    if (fr < 0.5 * f) {
      cls = 0;
    } else if (near_multiple(fr, tooth)) {
      cls = 2;
    } else if (near_multiple(fr, f)) {
      cls = 3;
    } else if (mains) {
      cls = 1;
    } else if (dyn.natural_hz[0] > 0.0 && fr >= res_lo && fr <= res_hi && !line) {
      cls = 4;
    } else if (line) {
      cls = 5;
    }
    auto& x = acc[static_cast<std::size_t>(cls)];
    ++x.bins;
    for (std::size_t a = 0; a < 2; ++a) {
      x.power[a] += std::norm(hann[a][b]);
    }
  }
  double worst_excess = 0.0;
  std::string worst_band;
  for (const auto& x : acc) {
    FrequencyBand band;
    band.name = x.name;
    band.range = x.range;
    double excess = 0.0;
    for (std::size_t a = 0; a < 2; ++a) {
      band.rms_N[a] = std::sqrt(2.0 * x.power[a] / (static_cast<double>(nfft) * window_power));
      band.noise_rms_N[a] =
          engine_.floor()[a] * std::sqrt(static_cast<double>(x.bins) / static_cast<double>(last));
      excess += band.rms_N[a] * band.rms_N[a] - band.noise_rms_N[a] * band.noise_rms_N[a];
    }
    if (excess > worst_excess) {
      worst_excess = excess;
      worst_band = x.name;
    }
    loc.bands.push_back(band);
  }

  // Time segments of the band-limited residual.
  {
    constexpr int kSegments = 8;
    std::array<std::vector<double>, 2> limited;
    Eigen::FFT<double> fft;
    for (std::size_t a = 0; a < 2; ++a) {
      std::vector<std::complex<double>> full(nfft, {0.0, 0.0});
      for (std::size_t b = 1; b <= last; ++b) {
        full[b] = ev.residual_bins[a][b];
        full[nfft - b] = std::conj(ev.residual_bins[a][b]);
      }
      std::vector<std::complex<double>> out;
      fft.inv(out, full);
      limited[a].resize(nfft);
      for (std::size_t i = 0; i < nfft; ++i) {
        limited[a][i] = out[i].real();
      }
    }
    const std::size_t per = nfft / kSegments;
    for (int sgm = 0; sgm < kSegments && per > 0; ++sgm) {
      std::array<double, 2> r{};
      for (std::size_t a = 0; a < 2; ++a) {
        double sum = 0.0;
        for (std::size_t i = sgm * per; i < (sgm + 1) * per; ++i) {
          sum += limited[a][i] * limited[a][i];
        }
        r[a] = std::sqrt(sum / static_cast<double>(per));
      }
      loc.segment_start_s.push_back(static_cast<double>(sgm * per) / fs);
      loc.segment_rms_N.push_back(r);
    }
  }

  // The residual's spectrum for the plot (at most 2000 points: the largest of each group).
  {
    const std::size_t group = std::max<std::size_t>(1, (last + 1999) / 2000);
    for (std::size_t b = 1; b <= last; b += group) {
      std::array<double, 2> m{};
      for (std::size_t i = b; i < std::min(last + 1, b + group); ++i) {
        for (std::size_t a = 0; a < 2; ++a) {
          m[a] = std::max(m[a], 2.0 * std::abs(ev.residual_bins[a][i]) / static_cast<double>(nfft));
        }
      }
      view.frequency_hz.push_back(static_cast<double>(b) * df);
      for (std::size_t a = 0; a < 2; ++a) {
        view.residual_amplitude_N[a].push_back(m[a]);
      }
    }
  }

  // One line: where the excess over the noise is.
  std::string line;
  if (worst_band.empty()) {
    line = "no band stands above the noise";
  } else {
    line = "largest excess over the noise: " + worst_band;
  }
  if (flutes > 1) {
    int jmax = 0;
    for (int j = 1; j < flutes; ++j) {
      if (std::hypot(loc.flute_rms_N[static_cast<std::size_t>(j)][0],
                     loc.flute_rms_N[static_cast<std::size_t>(j)][1]) >
          std::hypot(loc.flute_rms_N[static_cast<std::size_t>(jmax)][0],
                     loc.flute_rms_N[static_cast<std::size_t>(jmax)][1])) {
        jmax = j;
      }
    }
    line += "; synchronous residual largest on CE" + std::to_string(jmax + 1);
  }
  const double edge = std::hypot(loc.entry_exit_rms_N[0], loc.entry_exit_rms_N[1]);
  const double middle = std::hypot(loc.middle_rms_N[0], loc.middle_rms_N[1]);
  line += edge > 1.5 * middle ? ", at entry/exit" : (middle > 1.5 * edge ? ", at the peak" : "");
  loc.summary = line;
  return loc;
}

Stage Diagnoser::stage_of(const std::string& added, const State& s, const Evaluation& ev) {
  Stage st;
  st.added = added;
  st.parameters =
      added.empty() ? std::vector<Parameter>{} : added_parameters(added, s, ev, engine_.duration());
  st.coefficients = coefficients_of(ev);
  for (std::size_t a = 0; a < 2; ++a) {
    st.residual_rms_N[a] = std::sqrt(ev.mean_square[a]);
    st.residual_percent[a] = engine_.measured_rms()[a] > 0.0
                                 ? 100.0 * st.residual_rms_N[a] / engine_.measured_rms()[a]
                                 : 0.0;
  }
  st.criterion = ev.criterion;
  st.free_parameters = ev.free_parameters;
  st.localisation = localise(s, ev, st.view);
  return st;
}

std::vector<EffectParameters> Diagnoser::final_parameters(const std::vector<std::string>& named,
                                                          const State& s,
                                                          const Evaluation& ev) const {
  // The final fit holds what the state holds (State::held is its at_bound), so each effect's
  // parameters, the dynamometer's bounds among them, are that fit's.
  std::vector<EffectParameters> out;
  for (const auto& name : named) {
    out.push_back({name, added_parameters(name, s, ev, engine_.duration())});
  }
  return out;
}

/// Names as a sentence lists them: "a", "a and b", "a, b and c".
std::string joined(const std::vector<std::string>& names) {
  std::string list;
  for (std::size_t i = 0; i < names.size(); ++i) {
    list += (i == 0 ? "" : (i + 1 == names.size() ? " and " : ", ")) + names[i];
  }
  return list;
}

/// What the verdict says of the exchanges: each effect named on the way and not in the final
/// model, once, with the final model's effects that took its place ("" without exchanges).
std::string gave_way(const Diagnosis& d) {
  const auto& final_named = d.named_effects;
  const auto in_final = [&](const std::string& n) {
    return std::find(final_named.begin(), final_named.end(), n) != final_named.end();
  };
  std::vector<std::string> gone;
  std::vector<std::vector<std::string>> by;
  for (std::size_t i = 0; i < d.steps.size(); ++i) {
    const Stage& st = d.steps[i];
    if (st.removed.empty() || in_final(st.removed)) {
      continue;
    }
    const auto at = std::find(gone.begin(), gone.end(), st.removed);
    const std::size_t k = static_cast<std::size_t>(at - gone.begin());
    if (at == gone.end()) {
      gone.push_back(st.removed);
      by.emplace_back();
    }
    const std::size_t end =
        std::min(d.steps.size(), i + static_cast<std::size_t>(st.exchange_steps));
    for (std::size_t j = i; j < end; ++j) {
      const std::string& n = d.steps[j].added;
      if (in_final(n) && std::find(by[k].begin(), by[k].end(), n) == by[k].end()) {
        by[k].push_back(n);
      }
    }
  }
  std::string text;
  for (std::size_t k = 0; k < gone.size(); ++k) {
    text += " " + gone[k] + ", named on the way, " +
            (by[k].empty() ? std::string("was taken out again.")
                           : "gave way to " + joined(by[k]) + ".");
  }
  return text;
}

Round Diagnoser::score_round(const State& state, const Evaluation& current,
                             const std::vector<std::string>& names, const std::string& label,
                             const std::vector<std::string>& excluded) {
  std::vector<std::size_t> todo;  // indices into names
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (std::find(excluded.begin(), excluded.end(), names[i]) == excluded.end()) {
      todo.push_back(i);
    }
  }
  // The costliest fits first, so that the threads end together: a profile of h_min is a dozen
  // fits, the stiffness's seven, any other one or two (the ploughed area at an h_min the model
  // has estimated one). The order the fits start in does not change them.
  const auto cost = [&](std::size_t t) {
    const std::string& name = names[todo[t]];
    return at_model_h_min(name, state) ? 0
           : profiles_h_min(name)      ? 2
           : name == "tool_deflection" ? 1
                                       : 0;
  };
  std::vector<std::size_t> order(todo.size());
  for (std::size_t t = 0; t < order.size(); ++t) {
    order[t] = t;
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return cost(a) > cost(b); });
  struct Scored {
    std::optional<CandidateScore> score;
    State state;
  };
  std::vector<Scored> scored(todo.size());
  // Only the leader's evaluation is kept (its samples: ~45 bytes per sample of the record;
  // all the candidates' held 600 MB for a 30 s record at 20 kHz). The first (in the order of
  // names) of the lowest criteria among those that show their effect leads, as the choice below
  // picks it.
  Round r;
  std::size_t leader_at = 0;
  std::mutex leader_mutex;
  std::vector<std::size_t> rank(order.size());  // (k/n) in the progress line: started k-th
  for (std::size_t k = 0; k < order.size(); ++k) {
    rank[order[k]] = k;
  }
  run_on_engines(engine_, todo.size(), order, [&](Engine& engine, std::size_t t) {
    const std::string& name = names[todo[t]];
    progress(label + name + " (" + std::to_string(rank[t] + 1) + "/" + std::to_string(todo.size()) +
             ")");
    Scored& out = scored[t];
    out.state = state;
    Evaluation ev;
    out.score = score_candidate(engine, name, out.state, current, ev);
    if (!out.score || !ev.ok || !out.score->shown) {
      return;
    }
    const std::lock_guard lock(leader_mutex);
    if (!r.leader.ok || ev.criterion < r.leader.criterion ||
        (ev.criterion == r.leader.criterion && t < leader_at)) {
      r.leader = std::move(ev);
      leader_at = t;
    }
  });
  for (auto& one : scored) {
    if (one.score) {
      r.scores.push_back(std::move(*one.score));
      r.states.push_back(std::move(one.state));
    }
  }
  for (int i = 0; i < static_cast<int>(r.scores.size()); ++i) {
    if (!r.scores[static_cast<std::size_t>(i)].ok || !r.scores[static_cast<std::size_t>(i)].shown) {
      continue;
    }
    const double c = r.scores[static_cast<std::size_t>(i)].criterion;
    if (r.best < 0 || c < r.scores[static_cast<std::size_t>(r.best)].criterion) {
      r.second = r.best;
      r.best = i;
    } else if (r.second < 0 || c < r.scores[static_cast<std::size_t>(r.second)].criterion) {
      r.second = i;
    }
  }
  return r;
}

std::optional<CandidateScore> Diagnoser::score_candidate(Engine& engine, const std::string& name,
                                                         State& s, const Evaluation& current,
                                                         Evaluation& ev) {
  CandidateScore score;
  score.name = name;
  const bool at_model_h = at_model_h_min(name, s);  // the round's state, before apply()
  std::string why;
  if (!apply(engine, name, s, current, why)) {
    return std::nullopt;  // in the model already
  }
  // The fitter searches afresh (its starts and alignment scan) for every effect of the
  // model: a new effect may move the alignment by a pitch (the flute labelling) or the
  // runout to another basin, where a refinement from the current fit would stay stuck.
  // The chain's terms hardly move the model: those refine the current fit.
  const bool chain = name == "amplifier_drift" || name == "mains_hum";
  ev = at_model_h             ? evaluate_at_h_min(engine, s, current)
       : profiles_h_min(name) ? profile_h_min(engine, s, current)
       : name == "tool_deflection"
           ? profile_stiffness(engine, s, current)
           : engine.evaluate(s, &current, false, chain ? &current : nullptr);
  if (name == "mains_hum" && ev.ok) {
    State s60 = s;
    s60.hum_hz = 60.0;
    Evaluation ev60 = engine.evaluate(s60, &current, false, &current);
    if (ev60.ok && ev60.criterion < ev.criterion) {
      s = s60;
      ev = std::move(ev60);
    }
  }
  score.ok = ev.ok;
  score.message = ev.message;
  if (ev.ok) {
    score.criterion = ev.criterion;
    score.gain = current.criterion - ev.criterion;
    score.free_parameters = ev.free_parameters;
    for (std::size_t a = 0; a < 2; ++a) {
      score.residual_rms_N[a] = std::sqrt(ev.mean_square[a]);
    }
    score.parameters = added_parameters(name, s, ev, engine.duration());
    score.message = not_shown_by_parameters(name, score.parameters);
    score.shown = score.message.empty();
  }
  return score;
}

template <typename Work>
void Diagnoser::run_on_engines(Engine& caller, std::size_t count,
                               const std::vector<std::size_t>& order, const Work& work) {
  if (engines_running_) {  // inside one of its own threads: serially on that thread's engine
    for (std::size_t k = 0; k < count; ++k) {
      work(caller, order[k]);
    }
    return;
  }
  const int jobs = opt_.jobs > 0
                       ? opt_.jobs
                       : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const std::size_t threads = std::min(count, static_cast<std::size_t>(std::max(1, jobs)));
  while (helpers_.size() + 1 < threads) {
    helpers_.push_back(std::make_unique<Engine>(rec_, opt_));
  }
  std::atomic<std::size_t> next{0};
  // Every call runs, whatever another throws: the first in `order` of those that threw is
  // thrown again, the same one on any number of threads.
  std::exception_ptr failure;
  std::size_t failed_at = count;
  std::mutex failure_mutex;
  const auto loop = [&](Engine& engine) {
    for (std::size_t k = next++; k < count; k = next++) {
      try {
        work(engine, order[k]);
      } catch (...) {
        const std::lock_guard lock(failure_mutex);
        if (k < failed_at) {
          failed_at = k;
          failure = std::current_exception();
        }
      }
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(threads - 1);
  engines_running_ = threads > 1;  // before the threads start: they read it
  for (std::size_t w = 0; w + 1 < threads; ++w) {
    Engine& helper = *helpers_[w];
    helper.take_floor(engine_);  // refined as the search goes (the speed's σ reads it)
    try {
      pool.emplace_back([&loop, &helper] { loop(helper); });
    } catch (...) {
      break;  // no thread to be had: the ones started and this one do the rest
    }
  }
  loop(caller);
  for (auto& t : pool) {
    t.join();
  }
  engines_running_ = false;
  if (failure) {
    std::rethrow_exception(failure);
  }
}

void Diagnoser::accept(Round& round, State& state, Evaluation& current, Diagnosis& out,
                       const std::string& removed, double required_gain, bool with_variants) {
  const auto& win = round.scores[static_cast<std::size_t>(round.best)];
  State next = round.states[static_cast<std::size_t>(round.best)];
  progress("step " + std::to_string(out.steps.size() + 1) + ": adding " + win.name);
  Evaluation final_ev = std::move(round.leader);  // the best's (the same rule chose both)
  if (profiles_h_min(win.name) && next.h_min_bracket_um[0] > 0.0) {
    // Scored on h_min's grid; its step refines it, before the refit with the model's variants
    // (after it, a refined fit would replace that refit's σ with the statistical one alone).
    const Evaluation* seed = next.h_min_from_current ? &current : nullptr;
    Evaluation refined = refine_h_min(engine_, next, current, seed, final_ev);
    if (refined.ok && refined.criterion < final_ev.criterion) {
      final_ev = std::move(refined);
    }
    const double h = next.config.effects.min_chip.h_min_um;
    const auto at_end = [&](double end) { return std::fabs(std::log(h / end)) < 0.01; };
    if (next.h_min_from_current &&
        (at_end(next.h_min_bracket_um[0]) || at_end(next.h_min_bracket_um[1]))) {
      // Not bracketed by the model's h_min's neighbours: its whole profile.
      State whole = next;
      Evaluation profiled = profile_h_min(engine_, whole, current, seed);
      if (profiled.ok && whole.h_min_bound.empty()) {
        profiled = refine_h_min(engine_, whole, current, seed, std::move(profiled));
      }
      if (profiled.ok && profiled.criterion < final_ev.criterion) {
        next = whole;
        final_ev = std::move(profiled);
      }
    }
  }
  bool systematic = false;
  if (opt_.uncertainties && with_variants) {
    // The refit with the model's variants starts from the scored fit. Where it ends on a worse
    // optimum (beyond 0.5 of the criterion) or below the gain an effect must make (PHM
    // c1_cut158's helix_lag: 9.3 where the choice had scored 11.1, stated below the 10), the
    // scored fit stands — what the choice tested — with its statistical σ, and the step says
    // so. Either way the gain stated is one the choice's test passes.
    Evaluation with_sys = engine_.evaluate(next, &current, true, &final_ev);
    if (with_sys.ok && with_sys.criterion <= final_ev.criterion + 0.5 &&
        current.criterion - with_sys.criterion >= required_gain) {
      final_ev = std::move(with_sys);
      systematic = true;
    }
  }
  if (!next.held.empty()) {
    // The parameters held at a bound, freed: where the effect added lets them back inside the
    // range, they go back (State::held).
    State freed = next;
    freed.config = final_ev.fit.config;
    freed.release_held = true;
    Evaluation ev = engine_.evaluate(freed, &current, systematic, &final_ev);
    if (ev.ok && ev.criterion < final_ev.criterion) {
      final_ev = std::move(ev);
    }
  }
  next.config = final_ev.fit.config;
  // The dynamometer's own step lists its held parameters; a later one says what it moved.
  std::vector<Parameter> newly_held;
  if (win.name != "dynamometer_dynamics") {
    std::vector<std::pair<std::string, std::string>> moved;
    for (const auto& h : final_ev.at_bound) {
      if (std::find(state.held.begin(), state.held.end(), h) == state.held.end()) {
        moved.push_back(h);
      }
    }
    newly_held = held_parameters(next.config, moved);
  }
  next.hold(final_ev.at_bound);
  Stage st = stage_of(win.name, next, final_ev);
  st.removed = removed;
  st.gain = current.criterion - final_ev.criterion;
  // The speed's σ and the chain's are their own (find_speed(), chain_fit()), not the fit's.
  const bool from_fit =
      win.name != "spindle_speed_error" && win.name != "amplifier_drift" && win.name != "mains_hum";
  st.sigma_statistical_only = from_fit && !systematic;
  if (round.second >= 0) {
    const auto& runner_up = round.scores[static_cast<std::size_t>(round.second)];
    st.runner_up = runner_up.name;
    st.margin_over_runner_up = runner_up.criterion - win.criterion;
  }
  st.candidates = round.scores;
  st.newly_held = std::move(newly_held);
  out.steps.push_back(std::move(st));
  if (!removed.empty()) {
    out.named_effects.erase(
        std::remove(out.named_effects.begin(), out.named_effects.end(), removed),
        out.named_effects.end());
  }
  out.named_effects.push_back(win.name);
  state = next;
  current = std::move(final_ev);
  engine_.refine_floor(current);
}

bool Diagnoser::remove(const std::string& name, State& s,
                       const std::vector<std::string>& named) const {
  auto& e = s.config.effects;
  const auto& started = start_.effects;
  const auto is_named = [&](const char* effect) {
    return std::find(named.begin(), named.end(), effect) != named.end();
  };
  if (name == "runout") {
    if (s.change_s > 0.0) {
      return false;
    }
    s.fit_runout = false;
    e.runout.enabled = false;
    e.runout.offset_um = 0.0;
  } else if (name == "min_chip_thickness") {
    if (e.accumulation.enabled || area_law_on(s.config)) {
      return false;  // they need h_min
    }
    e.min_chip.enabled = false;
  } else if (name == "chip_accumulation") {
    e.accumulation.enabled = false;
    e.multi_pass.enabled = started.multi_pass.enabled;
    e.min_chip.enabled =
        started.min_chip.enabled || is_named("min_chip_thickness") || area_law_on(s.config);
  } else if (name == "ploughing_area") {
    s.config.material.linear_edge.ploughing_area = start_.material.linear_edge.ploughing_area;
    e.min_chip.enabled =
        started.min_chip.enabled || is_named("min_chip_thickness") || e.accumulation.enabled;
  } else if (name == "tool_deflection") {
    e.deflection.enabled = false;
    s.drop("stiffness_N_per_um");
  } else if (name == "helix_lag") {
    e.helix_lag = started.helix_lag;
  } else if (name == "trochoidal_path") {
    e.trochoidal = started.trochoidal;
  } else if (name == "dynamometer_dynamics") {
    e.dynamometer = started.dynamometer;
    for (const char* p : {"natural_hz_x", "natural_hz_y", "damping_ratio_x", "damping_ratio_y"}) {
      s.drop(p);
    }
  } else if (name == "tool_wear") {
    s.wear_trend = false;
    e.flank_wear = started.flank_wear;
    s.drop("wear_um");
  } else {
    return false;
  }
  return true;
}

bool Diagnoser::exchange(State& state, Evaluation& current, Diagnosis& out,
                         const std::vector<std::string>& names,
                         const std::vector<CandidateScore>& trigger) {
  struct Branch {
    std::string removed;
    Round first, second;
    bool two_steps = false;
    double criterion = 0.0;
  };
  // A step of an exchange gains `significance` and the record pins what it adds: a fit that
  // lands in a better basin of the other parameters can gain with an effect that does nothing
  // (the cp-Ti preset's cut at 333.3 kHz: helix_lag taken out for a tool_deflection of
  // 7,244 N/µm, "not determined", ΔBIC −4,364 against the model before).
  const auto pins_it = [&](const CandidateScore& c) {
    return c.gain >= opt_.significance && c.shown &&
           std::all_of(c.parameters.begin(), c.parameters.end(),
                       [](const Parameter& p) { return p.determined; });
  };
  std::optional<Branch> chosen;
  // A second step adds an effect: run() asks for exchanges below the step limit only.
  const std::vector<std::string> named = out.named_effects;
  for (const auto& e : named) {
    State without = state;
    if (!remove(e, without, named)) {
      continue;
    }
    // The model without it, refitted: what takes its place must gain `significance` over that,
    // as a step of the search would (not merely free a step for the one after it: on the cp-Ti
    // preset's cut at 20 kHz, helix_lag had made way for a rigid tool_deflection, ΔBIC −28
    // where it stood, and chip_accumulation after it).
    progress("exchange: the model without " + e);
    const Evaluation bare = engine_.evaluate(without, &current, false, nullptr);
    if (!bare.ok) {
      continue;
    }
    without.config = bare.fit.config;
    without.hold(bare.at_bound);
    Branch b;
    b.removed = e;
    // Neither step puts the effect back: back, it makes the branch one step that the search's
    // round had scored below `significance`, now gaining by a refit from elsewhere (on the cp-Ti
    // preset's cut: runout out for runout_change, which puts it back with a change the truth
    // has not, ΔBIC 17; trochoidal_path out for tool_wear and back in, ΔBIC 105).
    const std::vector<std::string> excluded =
        e == "runout" ? std::vector<std::string>{e, "runout_change"} : std::vector<std::string>{e};
    b.first = score_round(without, bare, names, "exchange for " + e + ": ", excluded);
    if (b.first.best < 0 || !pins_it(b.first.scores[static_cast<std::size_t>(b.first.best)])) {
      continue;
    }
    b.criterion = b.first.scores[static_cast<std::size_t>(b.first.best)].criterion;
    // The step after it, scored against the first's scored fit, which accept() therefore takes
    // without the variants' refit (below); each candidate's fit is whole, its own held parameters
    // its own.
    b.second = score_round(b.first.states[static_cast<std::size_t>(b.first.best)], b.first.leader,
                           names, "exchange for " + e + ", then: ", excluded);
    if (b.second.best >= 0) {
      const auto& next = b.second.scores[static_cast<std::size_t>(b.second.best)];
      if (pins_it(next) && next.criterion < b.criterion) {
        b.criterion = next.criterion;
        b.two_steps = true;
      }
    }
    if (!chosen || b.criterion < chosen->criterion) {
      chosen = std::move(b);
    }
  }
  if (!chosen || chosen->criterion > current.criterion - opt_.significance) {
    return false;
  }
  const double before = current.criterion;
  // The exchange's own step may lose what the step after it more than wins back; the step after
  // it was scored from its scored fit, which therefore stands (statistical σ only). The last
  // step's refit with the variants stands only where the exchange keeps its `significance`.
  const std::size_t at = out.steps.size();
  if (chosen->two_steps) {
    accept(chosen->first, state, current, out, chosen->removed,
           -std::numeric_limits<double>::infinity(), false);
    accept(chosen->second, state, current, out, "",
           std::max(opt_.significance, opt_.significance - (before - current.criterion)), true);
  } else {
    accept(chosen->first, state, current, out, chosen->removed, opt_.significance, true);
  }
  out.steps[at].exchange_gain = before - current.criterion;
  out.steps[at].exchange_steps = chosen->two_steps ? 2 : 1;
  out.steps[at].candidates_before_exchange = trigger;
  return true;
}

Diagnosis Diagnoser::run() {
  const auto t0 = std::chrono::steady_clock::now();
  Diagnosis out;
  out.band_hz = engine_.band();
  out.effective_samples = engine_.effective();
  out.duration_s = engine_.duration();
  out.commanded_rpm = start_.process.spindle_rpm;
  out.measured_rms_N = engine_.measured_rms();
  if (!(out.measured_rms_N[0] > 0.0 || out.measured_rms_N[1] > 0.0)) {
    out.message = "the record holds no force in the band compared (every sample the same)";
    return out;
  }

  std::vector<std::string> names;
  if (opt_.candidates.empty()) {
    for (const auto& c : catalogue()) {
      names.emplace_back(c.name);
    }
  } else {
    names = opt_.candidates;
  }

  // The starting model: its effects on stay, with their parameters free.
  State state;
  state.config = start_;
  state.rpm = start_.process.spindle_rpm;
  {
    const auto& e = start_.effects;
    state.fit_runout = e.runout.enabled;
    if (e.deflection.enabled) {
      state.extra.push_back("stiffness_N_per_um");
    }
    if (e.dynamometer.enabled) {
      for (const char* p : {"natural_hz_x", "natural_hz_y", "damping_ratio_x", "damping_ratio_y"}) {
        state.extra.push_back(p);
      }
    }
    if (!e.runout.enabled) {
      state.config.effects.runout.offset_um = 0.0;
    }
  }
  progress("fitting the starting model");
  Evaluation current = engine_.evaluate(state, nullptr, opt_.uncertainties, nullptr);
  if (!current.ok) {
    out.message = "the starting model could not be fitted: " + current.message;
    return out;
  }
  state.config = current.fit.config;
  state.hold(current.at_bound);
  engine_.refine_floor(current);
  out.initial = stage_of("", state, current);
  auto at_floor = [&](const Evaluation& ev) {
    for (std::size_t a = 0; a < 2; ++a) {
      if (std::sqrt(ev.mean_square[a]) > opt_.floor_tolerance * engine_.floor()[a]) {
        return false;
      }
    }
    return true;
  };
  out.stop_reason = "";
  int exchanges = 0;
  for (;;) {
    if (at_floor(current)) {
      out.stop_reason = "the residual is at the noise floor";
      break;
    }
    if (static_cast<int>(out.named_effects.size()) >= opt_.max_steps) {
      // The step limit. No exchange here: one for one (a step beyond the limit is none) had, on
      // the cp-Ti preset's cut at 20 kHz and six steps, traded the helix lag the cut has for a
      // wear trend it has not, which stood in for more (ΔBIC 1308).
      break;
    }
    Round round = score_round(state, current, names,
                              "step " + std::to_string(out.steps.size() + 1) + ": ", {});
    if (round.best < 0) {
      const bool any_fitted = std::any_of(round.scores.begin(), round.scores.end(),
                                          [](const CandidateScore& c) { return c.ok; });
      out.stop_reason = round.scores.empty() ? "every candidate is in the model"
                        : any_fitted         ? "no candidate fitted shows its effect"
                                             : "no candidate could be fitted";
      out.stop_reason += unshown_gains(round.scores);
      out.final_candidates = round.scores;
      break;
    }
    const auto& win = round.scores[static_cast<std::size_t>(round.best)];
    if (win.gain < opt_.significance) {
      if (exchanges < opt_.max_exchanges && exchange(state, current, out, names, round.scores)) {
        ++exchanges;
        continue;
      }
      out.final_candidates = round.scores;  // scored from the final model, not the last step's
      if (out.steps.empty()) {              // the starting model's round
        out.initial.candidates = round.scores;
      }
      out.stop_reason =
          format("no candidate improves the criterion by %.0f or more (best: ", opt_.significance) +
          win.name + format(", ΔBIC %.1f)", win.gain) + unshown_gains(round.scores);
      break;
    }
    accept(round, state, current, out, "", opt_.significance, true);
  }
  if (out.stop_reason.empty()) {
    out.stop_reason =
        at_floor(current) ? "the residual is at the noise floor" : "the step limit was reached";
  }
  const bool step_limited = out.stop_reason == "the step limit was reached";
  const bool search_at_floor = at_floor(current);
  final_h_min(state, current, out);
  for (auto& note : steady_state_notes(current.revolutions_round_again, current.unsettled_slots,
                                       current.slots)) {
    out.final_notes.push_back(std::move(note));
  }
  if (!search_at_floor && at_floor(current)) {
    // The search stopped above the floor; the verdict, on the final model, says it is there.
    out.stop_reason +=
        "; then h_min, profiled again in the final model, took the residual to "
        "the noise floor";
  }
  out.noise_floor_N = engine_.floor();
  for (std::size_t a = 0; a < 2; ++a) {
    out.final_residual_rms_N[a] = std::sqrt(current.mean_square[a]);
  }
  out.final_coefficients = coefficients_of(current);
  out.final_model = current.fit.config;
  out.final_model.effects.runout.enabled = state.fit_runout;
  out.at_bound = held_parameters(out.final_model, state.held);
  out.spindle_rpm = state.rpm;
  out.final_parameters = final_parameters(out.named_effects, state, current);

  const auto& last_rms = out.final_residual_rms_N;
  const double ratio = std::max(last_rms[0] / std::max(out.noise_floor_N[0], 1e-300),
                                last_rms[1] / std::max(out.noise_floor_N[1], 1e-300));
  // "Look outside the catalogue" only when the whole catalogue was scored and none gained.
  const bool whole_catalogue = names.size() >= catalogue().size();
  const std::string unexplained =
      step_limited ? format("the step limit (%.0f) stopped the search", opt_.max_steps)
      : whole_catalogue
          ? std::string("look outside the catalogue")
          : format("only %.0f of the catalogue's %.0f candidates were tried",
                   static_cast<double>(names.size()), static_cast<double>(catalogue().size()));
  if (out.named_effects.empty()) {
    out.verdict =
        at_floor(current)
            ? format(
                  "The model lacks nothing the data can show: its residual (%.4f, %.4f N) is "
                  "at the noise floor (%.4f, %.4f N).",
                  last_rms[0], last_rms[1], out.noise_floor_N[0], out.noise_floor_N[1])
        : step_limited
            ? format("No effect was added (%.1f× the noise floor): ", ratio) + unexplained + "."
            : format("No effect tried explains the residual (%.1f× the noise floor): ", ratio) +
                  unexplained + ".";
  } else {
    const std::string list = joined(out.named_effects);
    // "Brought down" only where both axes fell: the criterion weighs them together, and one may
    // rise while the other falls (PHM c1_cut158: fx 9.29 → 3.78 N, fy 5.58 → 5.72 N).
    const auto& first_rms = out.initial.residual_rms_N;
    const bool both_fell = last_rms[0] <= first_rms[0] && last_rms[1] <= first_rms[1];
    const std::string change =
        both_fell ? format(
                        ": adding it brought the residual from fx %.4f, fy %.4f N to fx %.4f, "
                        "fy %.4f N",
                        first_rms[0], first_rms[1], last_rms[0], last_rms[1])
                  : format(
                        ": adding it took the residual from fx %.4f, fy %.4f N to fx %.4f, "
                        "fy %.4f N",
                        first_rms[0], first_rms[1], last_rms[0], last_rms[1]) +
                        format(" (fx %+.1f %%, fy %+.1f %%: one axis rose)",
                               100.0 * (last_rms[0] / std::max(first_rms[0], 1e-300) - 1.0),
                               100.0 * (last_rms[1] / std::max(first_rms[1], 1e-300) - 1.0));
    // The ratio is the axis further from its floor's.
    out.verdict = "The model lacked " + list + change +
                  format(" (%.2f× the noise floor on the axis further from it)", ratio) +
                  (at_floor(current) ? "." : "; something else remains (" + unexplained + ").");
    if (out.named_effects.size() > 1) {
      out.verdict.replace(out.verdict.find("adding it"), 9, "adding them");
    }
    out.verdict += gave_way(out);
  }
  if (!at_floor(current)) {
    // A σ is the spread the noise gives a parameter of a model that describes the record; one
    // that leaves this much (PHM c1_cut158: 34× the floor; a simulated cut with seven effects
    // stopped at five: h_min 2.485 ± 0.035 µm for a truth of 0.2) puts what it lacks into its
    // parameters beyond that.
    out.sigma_caveat = format(
        "Every σ is given its step's model; the final one leaves %.1f× the noise floor, so "
        "what it lacks can move its parameters beyond their σ (a parameter standing in "
        "for a missing effect).",
        ratio);
  }
  out.ok = true;
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

model::ModelConfig plain_model(const model::ModelConfig& config) {
  return model::without_effects(config);
}

double revolutions_round_again(double first_cycle_revolution, double revolutions,
                               int cycle_revolutions) {
  // The cycle wraps after its remaining revolutions; every revolution after that is one played
  // again.
  return std::max(0.0, revolutions - (static_cast<double>(cycle_revolutions) -
                                      std::clamp(first_cycle_revolution, 0.0,
                                                 static_cast<double>(cycle_revolutions))));
}

std::vector<std::string> steady_state_notes(double revolutions_round_again, int unsettled_slots,
                                            int slots) {
  std::vector<std::string> notes;
  const double round_again = std::floor(revolutions_round_again);
  if (round_again > 0.0) {
    notes.push_back(
        format("The final model's cycle (the least common multiple of its slots' periods) "
               "outgrew %.0f revolutions: %.0f revolutions of the record are compared with its "
               "first %.0f played round again, each exact away from the seams between rounds",
               static_cast<double>(model::kMaxCycleRevolutions), round_again,
               static_cast<double>(model::kMaxCycleRevolutions)));
  }
  if (unsettled_slots > 0) {
    notes.push_back(
        format("%.0f of the final model's %.0f slots (disc, immersion) did not repeat within "
               "%.0f revolutions (accumulation without a period): their state at the last of "
               "them stands in its cycle, which is approximate there",
               static_cast<double>(unsettled_slots), static_cast<double>(slots),
               static_cast<double>(model::kMaxSlotRevolutions)));
  }
  return notes;
}

Diagnosis diagnose(const CutRecord& record, const model::ModelConfig& start,
                   const DiagnoseOptions& options) {
  const double fs = record.sample_rate_hz;
  if (!(fs > 0.0) || !std::isfinite(fs)) {
    throw std::invalid_argument("diagnose: the sample rate must be a positive number (got " +
                                std::to_string(fs) + ")");
  }
  if (record.force_N[0].size() != record.force_N[1].size()) {
    throw std::invalid_argument("diagnose: fx and fy have different lengths (" +
                                std::to_string(record.force_N[0].size()) + " and " +
                                std::to_string(record.force_N[1].size()) + " samples)");
  }
  for (std::size_t a = 0; a < 2; ++a) {
    for (std::size_t i = 0; i < record.force_N[a].size(); ++i) {
      if (!std::isfinite(record.force_N[a][i])) {
        throw std::invalid_argument(std::string("diagnose: sample ") + std::to_string(i) + " of " +
                                    (a == 0 ? "fx" : "fy") + " is not a finite number");
      }
    }
  }
  model::validate(start);
  const double rev_s = 60.0 / start.process.spindle_rpm;
  const double duration = static_cast<double>(record.force_N[0].size()) / fs;
  if (duration < 10.0 * rev_s) {
    throw std::invalid_argument(
        format("diagnose: the record lasts %.4f s, less than 10 revolutions at %.0f rpm (%.4f s)",
               duration, start.process.spindle_rpm, 10.0 * rev_s));
  }
  const double band = options.band_hz > 0.0 ? options.band_hz : std::min(0.4 * fs, 10000.0);
  if (!(band < 0.5 * fs)) {
    throw std::invalid_argument(
        format("diagnose: the band (%.0f Hz) must lie below Nyquist (%.0f Hz)", band, 0.5 * fs));
  }
  // The speed search reaches 2.5 % above the commanded speed, with the tooth-passing harmonic.
  const double tooth_hz = model::tooth_passing_hz(start);
  if (band < (1.0 + kSpeedSearchFraction) * tooth_hz) {
    throw std::invalid_argument(format(
        "diagnose: the band (%.0f Hz) must hold the tooth-passing frequency 2.5 %% above the "
        "commanded speed (%.0f Hz)",
        band, (1.0 + kSpeedSearchFraction) * tooth_hz));
  }
  if (options.jobs < 0) {
    throw std::invalid_argument("diagnose: jobs must be 0 (one per core) or more (got " +
                                std::to_string(options.jobs) + ")");
  }
  for (const auto& name : options.candidates) {
    if (find_candidate(name) == nullptr) {
      std::string known;
      for (const auto& c : catalogue()) {
        known += (known.empty() ? "" : ", ") + std::string(c.name);
      }
      throw std::invalid_argument("diagnose: unknown candidate '" + name + "' (known: " + known +
                                  ")");
    }
  }
  Diagnoser d(record, start, options);
  return d.run();
}

std::string not_shown_by_parameters(const std::string& candidate,
                                    const std::vector<Parameter>& parameters) {
  constexpr double kShown = 2.0;  // σ: the criterion already chose; this asks only for a sign
  const auto find = [&](const std::string& name) -> const Parameter* {
    for (const auto& p : parameters) {
      if (p.name == name) {
        return &p;
      }
    }
    return nullptr;
  };
  // Only an estimate can show an effect: a value the record does not pin, or one that sits on
  // a bound, has σ 0 or a one-sided meaning, and would pass |v| > 2σ whatever it is.
  const auto not_estimated = [](const Parameter& p) -> const char* {
    if (!p.determined) {
      return "not pinned by the record";
    }
    if (!p.at_bound.empty()) {
      return "at its physical bound";
    }
    if (p.lower_bound || p.upper_bound) {
      return p.bound_note.empty() ? "a bound the force allows, not a measurement"
                                  : p.bound_note.c_str();
    }
    if (!(std::isfinite(p.sigma) && p.sigma > 0.0)) {
      return "without a standard error";
    }
    return nullptr;
  };
  const auto describe = [&](const Parameter& p, const char* what) {
    const char* why = not_estimated(p);
    return why == nullptr ? format("%.3f ± %.3f µm", p.value, p.sigma) + what
                          : format("%.3f µm", p.value) + what + ", " + why;
  };
  if (candidate == "runout_change") {
    std::string text;
    bool estimated = true;  // the quantity the text shows
    for (const char* q : {"r_ce2_minus_r_ce1", "rho"}) {
      const Parameter* b = find(std::string(q) + "_before_um");
      const Parameter* a = find(std::string(q) + "_after_um");
      if (b == nullptr || a == nullptr) {
        continue;
      }
      const bool both = not_estimated(*b) == nullptr && not_estimated(*a) == nullptr;
      if (both && std::fabs(a->value - b->value) > kShown * std::hypot(b->sigma, a->sigma)) {
        return "";
      }
      if (text.empty()) {
        text = std::string(q) + " " + describe(*b, " before") + ", " + describe(*a, " after");
        estimated = both;
      }
    }
    return std::string(estimated ? "the runout before and after the change agree within 2σ ("
                                 : "the runout before and after the change is not estimated (") +
           text + "): the gain is the rest of the model refitted per segment, not a change";
  }
  if (candidate == "tool_wear") {
    const Parameter* mid = find("wear_mid_um");
    const Parameter* growth = find("wear_growth_um");
    for (const Parameter* p : {mid, growth}) {
      if (p != nullptr && not_estimated(*p) == nullptr && std::fabs(p->value) > kShown * p->sigma) {
        return "";
      }
    }
    return "neither the wear nor its growth differs from zero by 2σ of an estimate" +
           (mid != nullptr && growth != nullptr
                ? " (" + describe(*mid, "") + "; growing " + describe(*growth, "") + ")"
                : std::string()) +
           ": the gain is the coefficients refitted beside it, not wear";
  }
  if (profiles_h_min(candidate)) {
    // Ploughing pushes against the edge's motion and away from the surface: a tangential or
    // normal ploughing coefficient below zero by 2σ is a fit standing in for something else
    // (the AlSi10Mg preset's plain start: ploughing_area's K_tp −3,821 ± 1,400 N/mm³).
    for (const auto& p : parameters) {
      const bool tangential_or_normal =
          p.name.rfind("k_tp_", 0) == 0 || p.name.rfind("k_np_", 0) == 0;
      if (tangential_or_normal && not_estimated(p) == nullptr && p.value < -kShown * p.sigma) {
        return "a negative ploughing coefficient (" + p.name +
               format(" = %.4g ± %.2g", p.value, p.sigma) +
               "): the gain is a fit standing in for another effect, not ploughing";
      }
    }
    const Parameter* h = find("h_min_um");
    if (h == nullptr || not_estimated(*h) == nullptr) {
      return "";
    }
    return "h_min is not estimated (" + describe(*h, "") +
           "): the gain is the ploughing coefficients fitted on the chips below it, not " +
           (candidate == "ploughing_area" ? "an area ploughed below a minimum chip thickness"
                                          : "a minimum chip thickness");
  }
  return "";
}

std::array<double, 2> physical_range(const std::string& name) {
  if (name.rfind("damping_ratio_", 0) == 0) {
    return {kDampingRatioMin, kDampingRatioMax};
  }
  if (name.rfind("natural_hz_", 0) == 0) {
    return {kNaturalHzMin, kNaturalHzMax};
  }
  return {0.0, 0.0};
}

double& dynamometer_parameter(model::ModelConfig& config, const std::string& name) {
  const char axis = name.empty() ? 'x' : name.back();
  const std::size_t a = axis == 'x' ? 0 : axis == 'y' ? 1 : 2;
  auto& d = config.effects.dynamometer;
  if (name.rfind("natural_hz_", 0) == 0) {
    return d.natural_hz[a];
  }
  if (name.rfind("damping_ratio_", 0) == 0) {
    return d.damping_ratio[a];
  }
  throw std::invalid_argument("not a dynamometer parameter: " + name);
}

}  // namespace millwatch::diagnose
