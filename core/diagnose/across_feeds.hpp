#pragma once
// The diagnosis across feeds (millwatch issue 8, item 1: "across feeds when given several
// cuts"): cuts of one tool and material at different feeds per tooth f_t, each diagnosed
// (diagnosis.hpp), then compared. Per cut: the residual of the starting model and of the final
// one, by band — spindle harmonics that are not tooth-passing ones (runout's signature),
// tooth-passing harmonics, the rest — with the noise floor's share taken out (the excess
// e = √(max(r² − n², 0)), fx and fy together).
//
// The trend names how the starting model's excess varies with the feed: e ∝ f_t^n, n by least
// squares on ln e against ln f_t (σ from the scatter about the line, with three or more feeds),
// and the band that holds most of it tells which effect:
//   proportional_to_feed (n ≥ 0.6): the error keeps its share of the force at every feed, as a
//     force coefficient or law error does (F ∝ K·h^(1−a): a wrong K is wrong by the same
//     fraction), or an effect riding on the force (dynamometer_dynamics, helix_lag).
//   independent_of_feed (−0.4 < n < 0.6): an error of fixed size, which weighs more at small
//     feeds — in the spindle harmonics runout's cutting-radius difference ρ·cos γ, the same
//     micrometres at every feed ([000] eq 9; its force error K(1−a)h^(−a)·Δh gives n ≈ −a);
//     in the tooth-passing harmonics the ploughing and rubbing of the edge below h_min, whose
//     force does not scale with the chip ([000] eq 5, [002] eq 17's edge terms, [001]'s ploughed
//     area); elsewhere the measurement chain (drift, hum do not know the feed).
//   grows_as_feed_falls (n ≤ −0.4): more of the engagement below h_min as f_t falls
//     (min_chip_thickness, chip_accumulation, ploughing_area).
//   at_noise_floor: no cut's residual stands above 1.1× its noise floor (the diagnosis's own
//     "at the floor"): nothing to read.
// The relative exponent (the excess over the measured RMS) says how the error's weight changes:
// below 0 it weighs more at small feeds.
//
// Pure computation on diagnoses already made; deterministic.

#include <array>
#include <string>
#include <vector>

#include "core/diagnose/diagnosis.hpp"

namespace millwatch::diagnose {

/// One cut's diagnosis, with its feed.
struct FeedCut {
  std::string name;                ///< e.g. the recording's file name
  double feed_per_tooth_um = 0.0;  ///< > 0
  const Diagnosis* diagnosis = nullptr;
};

/// A model's residual split by band (RMS, N, per axis fx, fy) and its excess over the noise.
struct ResidualByBand {
  std::array<double, 2> total_N{};
  std::array<double, 2> spindle_harmonics_N{};  ///< spindle harmonics, not tooth-passing ones
  std::array<double, 2> tooth_harmonics_N{};    ///< tooth-passing harmonics
  std::array<double, 2> rest_N{};               ///< every other band in quadrature
  double excess_N = 0.0;  ///< √(Σ_axes max(total² − floor², 0)): above the noise floor
};

struct CutAcrossFeeds {
  std::string name;
  double feed_per_tooth_um = 0.0;
  std::array<double, 2> measured_rms_N{};
  std::array<double, 2> noise_floor_N{};
  ResidualByBand before;  ///< the starting model (its coefficients fitted to this cut)
  ResidualByBand after;   ///< the final model of this cut's diagnosis
  std::vector<std::string> named_effects;
};

struct FeedTrend {
  std::string name;  ///< proportional_to_feed, independent_of_feed, grows_as_feed_falls,
                     ///< at_noise_floor, or one_feed (fewer than two distinct feeds)
  bool has_exponent = false;
  double exponent = 0.0;   ///< n of excess ∝ f_t^n
  bool has_sigma = false;  ///< σ needs three feeds or more
  double exponent_sigma = 0.0;
  double relative_exponent = 0.0;  ///< of excess / measured RMS (with has_exponent)
  std::string band;                ///< the band holding most of the excess over the cuts
  std::string suggests;            ///< the catalogue's effects this trend points to
  std::string sentence;            ///< for people
};

struct AcrossFeeds {
  std::vector<CutAcrossFeeds> cuts;  ///< in the order of rising feed
  FeedTrend trend;                   ///< of the starting model's excess
  FeedTrend trend_after;             ///< of the final models' excess
  /// Named in every cut's diagnosis / in some only.
  std::vector<std::string> named_in_every_cut, named_in_some_cuts;
  bool shrinks_in_every_cut = false;  ///< the final residual below the starting one in each cut
  std::string verdict;                ///< one sentence
};

/// Compares the diagnoses of cuts at different feeds.
/// @throws std::invalid_argument naming the cut with no diagnosis, a failed one or a feed ≤ 0
AcrossFeeds across_feeds(const std::vector<FeedCut>& cuts);

/// The trend of excess residuals (N, ≥ 0) at feeds f_t (µm, > 0) with noise floors and measured
/// RMS (N, |fx, fy|), the excess mostly in `band` (spindle_harmonics, tooth_passing_harmonics or
/// rest).
FeedTrend feed_trend(const std::vector<double>& feed_um, const std::vector<double>& excess_N,
                     const std::vector<double>& floor_N, const std::vector<double>& measured_N,
                     const std::string& band);

}  // namespace millwatch::diagnose
