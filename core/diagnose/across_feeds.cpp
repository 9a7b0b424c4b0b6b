#include "core/diagnose/across_feeds.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace millwatch::diagnose {
namespace {

/// An excess of 0.46× the floor is a residual of 1.1× the floor: the diagnosis's own "at the
/// noise floor" (DiagnoseOptions::floor_tolerance).
constexpr double kAboveFloor = 0.46;

ResidualByBand by_band(const Stage& s, const std::array<double, 2>& floor) {
  ResidualByBand r;
  r.total_N = s.residual_rms_N;
  std::array<double, 2> rest_sq{};
  for (const auto& b : s.localisation.bands) {
    for (std::size_t a = 0; a < 2; ++a) {
      if (b.name == "spindle_harmonics") {
        r.spindle_harmonics_N[a] = b.rms_N[a];
      } else if (b.name == "tooth_passing_harmonics") {
        r.tooth_harmonics_N[a] = b.rms_N[a];
      } else {
        rest_sq[a] += b.rms_N[a] * b.rms_N[a];
      }
    }
  }
  double excess_sq = 0.0;
  for (std::size_t a = 0; a < 2; ++a) {
    r.rest_N[a] = std::sqrt(rest_sq[a]);
    excess_sq += std::max(0.0, r.total_N[a] * r.total_N[a] - floor[a] * floor[a]);
  }
  r.excess_N = std::sqrt(excess_sq);
  return r;
}

std::string format(const char* fmt, double a, double b = 0.0, double c = 0.0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, fmt, a, b, c);
  return buf;
}

/// The band with the largest excess over the noise, summed over the cuts.
std::string dominant_band(const std::vector<CutAcrossFeeds>& cuts, bool after) {
  std::array<double, 3> sum{};
  for (const auto& c : cuts) {
    const ResidualByBand& r = after ? c.after : c.before;
    for (std::size_t a = 0; a < 2; ++a) {
      sum[0] += r.spindle_harmonics_N[a] * r.spindle_harmonics_N[a];
      sum[1] += r.tooth_harmonics_N[a] * r.tooth_harmonics_N[a];
      // The rest holds the broadband noise: only its excess over the floor counts.
      sum[2] += std::max(0.0, r.rest_N[a] * r.rest_N[a] - c.noise_floor_N[a] * c.noise_floor_N[a]);
    }
  }
  const auto i = std::max_element(sum.begin(), sum.end()) - sum.begin();
  return i == 0 ? "spindle_harmonics" : i == 1 ? "tooth_passing_harmonics" : "rest";
}

}  // namespace

FeedTrend feed_trend(const std::vector<double>& feed_um, const std::vector<double>& excess_N,
                     const std::vector<double>& floor_N, const std::vector<double>& measured_N,
                     const std::string& band) {
  FeedTrend t;
  t.band = band;
  std::vector<double> distinct = feed_um;
  std::sort(distinct.begin(), distinct.end());
  distinct.erase(std::unique(distinct.begin(), distinct.end(),
                             [](double a, double b) { return std::fabs(a - b) <= 1e-9 * b; }),
                 distinct.end());
  bool above = false;
  for (std::size_t i = 0; i < excess_N.size(); ++i) {
    above = above || excess_N[i] > kAboveFloor * floor_N[i];
  }
  if (!above) {
    t.name = "at_noise_floor";
    t.suggests = "nothing: the model explains every cut to its noise";
    t.sentence = "No cut's residual stands above its noise floor: no trend with the feed to read.";
    return t;
  }
  if (distinct.size() < 2) {
    t.name = "one_feed";
    t.suggests = "cuts at two or more feeds";
    t.sentence = "All cuts are at one feed: the residual's trend with the feed cannot be read.";
    return t;
  }
  // ln e = c + n·ln f, e floored at a tenth of the noise floor (a cut at the floor carries no
  // excess, and its logarithm must stay finite).
  const auto m = static_cast<double>(feed_um.size());
  double sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0;
  std::vector<double> x(feed_um.size()), y(feed_um.size());
  for (std::size_t i = 0; i < feed_um.size(); ++i) {
    x[i] = std::log(feed_um[i]);
    y[i] = std::log(std::max(excess_N[i], 0.1 * floor_N[i]));  // finite at the floor
    sx += x[i];
    sy += y[i];
    sxx += x[i] * x[i];
    sxy += x[i] * y[i];
  }
  const double sxx_c = sxx - sx * sx / m;
  t.exponent = (sxy - sx * sy / m) / sxx_c;
  t.has_exponent = true;
  {
    double sr = 0.0, sxr = 0.0;  // ln(measured) against ln f: the relative exponent is n − that
    for (std::size_t i = 0; i < x.size(); ++i) {
      const double r = std::log(std::max(measured_N[i], 1e-12));
      sr += r;
      sxr += x[i] * r;
    }
    t.relative_exponent = t.exponent - (sxr - sx * sr / m) / sxx_c;
  }
  if (feed_um.size() >= 3) {
    const double c = (sy - t.exponent * sx) / m;
    double rss = 0.0;
    for (std::size_t i = 0; i < x.size(); ++i) {
      const double d = y[i] - c - t.exponent * x[i];
      rss += d * d;
    }
    t.exponent_sigma = std::sqrt(rss / (m - 2.0) / sxx_c);
    t.has_sigma = true;
  }
  if (t.exponent >= 0.6) {
    t.name = "proportional_to_feed";
    // The exact path departs from f_t·sin θ by ~f_t/(2R) of the chip: its share of the force
    // grows as the feed (relative exponent ~1), where an effect riding on the force keeps it.
    t.suggests =
        t.relative_exponent >= 0.6
            ? "an error whose share of the force grows with the feed: the tooth path "
              "(trochoidal_path: ~f_t/(2R) of the chip), or the force law's size effect"
            : "an error that keeps its share of the force: the force law's coefficients or size "
              "effect, or an effect riding on the force (dynamometer_dynamics, helix_lag)";
  } else if (t.exponent <= -0.4) {
    t.name = "grows_as_feed_falls";
    t.suggests =
        "more of the engagement below h_min as the feed falls: min_chip_thickness, "
        "chip_accumulation, ploughing_area";
  } else {
    t.name = "independent_of_feed";
    t.suggests =
        band == "spindle_harmonics"
            ? "an error of fixed size in the spindle harmonics: runout (a fixed cutting-radius "
              "difference), runout_change"
        : band == "tooth_passing_harmonics"
            ? "an error of fixed size at every tooth pass: ploughing and rubbing of the edge "
              "(min_chip_thickness, ploughing_area), tool_wear"
            : "an error of fixed size outside the harmonics: the measurement chain "
              "(amplifier_drift, mains_hum)";
  }
  t.sentence = format("The residual above the noise varies as f_t^%.2f", t.exponent) +
               (t.has_sigma ? format(" ± %.2f", t.exponent_sigma)
                            : std::string(" (no σ: two cuts are a line through two points; a "
                                          "third cut gives one)")) +
               format(" over %.3g–%.3g µm per tooth: ", distinct.front(), distinct.back()) +
               t.name + " (mostly in " + band +
               format("; relative to the force f_t^%.2f) — ", t.relative_exponent) + t.suggests +
               ".";
  return t;
}

AcrossFeeds across_feeds(const std::vector<FeedCut>& cuts) {
  AcrossFeeds out;
  for (std::size_t i = 0; i < cuts.size(); ++i) {
    const FeedCut& c = cuts[i];
    const std::string where = "cut " + std::to_string(i + 1) + " (" + c.name + ")";
    if (c.diagnosis == nullptr || !c.diagnosis->ok) {
      throw std::invalid_argument("across_feeds: " + where + " has no diagnosis" +
                                  (c.diagnosis != nullptr ? ": " + c.diagnosis->message : ""));
    }
    if (!(c.feed_per_tooth_um > 0.0) || !std::isfinite(c.feed_per_tooth_um)) {
      throw std::invalid_argument("across_feeds: " + where + " has feed per tooth " +
                                  std::to_string(c.feed_per_tooth_um) + " um: must be > 0");
    }
    const Diagnosis& d = *c.diagnosis;
    CutAcrossFeeds r;
    r.name = c.name;
    r.feed_per_tooth_um = c.feed_per_tooth_um;
    r.measured_rms_N = d.measured_rms_N;
    r.noise_floor_N = d.noise_floor_N;
    r.before = by_band(d.initial, d.noise_floor_N);
    r.after = by_band(d.steps.empty() ? d.initial : d.steps.back(), d.noise_floor_N);
    r.named_effects = d.named_effects;
    out.cuts.push_back(std::move(r));
  }
  if (out.cuts.empty()) {
    throw std::invalid_argument("across_feeds: no cut");
  }
  std::stable_sort(out.cuts.begin(), out.cuts.end(), [](const auto& a, const auto& b) {
    return a.feed_per_tooth_um < b.feed_per_tooth_um;
  });
  std::vector<double> feeds, before, after, floors, measured;
  out.shrinks_in_every_cut = true;
  for (const auto& c : out.cuts) {
    feeds.push_back(c.feed_per_tooth_um);
    before.push_back(c.before.excess_N);
    after.push_back(c.after.excess_N);
    floors.push_back(std::hypot(c.noise_floor_N[0], c.noise_floor_N[1]));
    measured.push_back(std::hypot(c.measured_rms_N[0], c.measured_rms_N[1]));
    out.shrinks_in_every_cut = out.shrinks_in_every_cut &&
                               c.after.total_N[0] <= c.before.total_N[0] &&
                               c.after.total_N[1] <= c.before.total_N[1] &&
                               std::hypot(c.after.total_N[0], c.after.total_N[1]) <
                                   std::hypot(c.before.total_N[0], c.before.total_N[1]);
  }
  out.trend = feed_trend(feeds, before, floors, measured, dominant_band(out.cuts, false));
  out.trend_after = feed_trend(feeds, after, floors, measured, dominant_band(out.cuts, true));
  // Effects named in every cut (in the first cut's order), and in some only.
  for (const auto& c : out.cuts) {
    for (const auto& e : c.named_effects) {
      const bool every = std::all_of(out.cuts.begin(), out.cuts.end(), [&](const auto& o) {
        return std::find(o.named_effects.begin(), o.named_effects.end(), e) !=
               o.named_effects.end();
      });
      auto& list = every ? out.named_in_every_cut : out.named_in_some_cuts;
      if (std::find(list.begin(), list.end(), e) == list.end()) {
        list.push_back(e);
      }
    }
  }
  std::string named;
  for (std::size_t i = 0; i < out.named_in_every_cut.size(); ++i) {
    named += (i == 0 ? "" : ", ") + out.named_in_every_cut[i];
  }
  out.verdict = "Across " + std::to_string(out.cuts.size()) +
                " cuts: the starting model's residual is " + out.trend.name + " (mostly in " +
                out.trend.band + ")" +
                (named.empty() ? std::string("; no effect is named in every cut")
                               : "; named in every cut: " + named) +
                (out.shrinks_in_every_cut ? "; the residual shrinks in every cut."
                                          : "; the residual does not shrink in every cut.");
  return out;
}

}  // namespace millwatch::diagnose
