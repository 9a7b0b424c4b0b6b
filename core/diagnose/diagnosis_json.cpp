#include "core/diagnose/diagnosis_json.hpp"

#include "core/diagnose/catalogue.hpp"
#include "core/model/model_config.hpp"

namespace millwatch::diagnose {
namespace {

nlohmann::json axes(const std::array<double, 2>& v) {
  return {{"fx", v[0]}, {"fy", v[1]}};
}

nlohmann::json parameters(const std::vector<Parameter>& ps) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& p : ps) {
    if (!p.determined) {  // not an estimate: no σ
      j[p.name] = {{"value", p.value},
                   {"sigma", nullptr},
                   {"determined", false},
                   {"note",
                    "not determined: the record does not pin it (the force does not depend on "
                    "it there, or only together with parameters the data cannot tell apart); "
                    "the value is where the fit left it"}};
    } else if (p.at_bound.empty()) {
      j[p.name] = {{"value", p.value}, {"sigma", p.sigma}};
      if (p.lower_bound) {
        j[p.name]["lower_bound"] = true;
        j[p.name]["note"] = !p.bound_note.empty()
                                ? p.bound_note
                                : "at a flute's contact edge: a flute cuts nothing beyond it, the "
                                  "force bounds the value from below only";
      } else if (p.upper_bound) {
        j[p.name]["upper_bound"] = true;
        j[p.name]["note"] = !p.bound_note.empty()
                                ? p.bound_note
                                : "at a flute's contact edge: a flute cuts nothing beyond it, the "
                                  "force bounds the value from above only";
      }
      if ((p.lower_bound || p.upper_bound) && !(p.sigma > 0.0)) {
        j[p.name]["sigma"] = nullptr;  // a bound, not an estimate
      }
    } else {  // a bound, not an estimate: no σ
      j[p.name] = {{"value", p.value},
                   {"sigma", nullptr},
                   {"at_bound", p.at_bound},
                   {"note", "the fit sits on the " + p.at_bound +
                                " end of the physical range; held there, the rest refitted"}};
    }
  }
  return j;
}

nlohmann::json localisation(const Localisation& l) {
  nlohmann::json flutes = nlohmann::json::array();
  for (const auto& f : l.flute_rms_N) {
    flutes.push_back(axes(f));
  }
  nlohmann::json bands = nlohmann::json::array();
  for (const auto& b : l.bands) {
    bands.push_back({{"band", b.name},
                     {"holds", b.range},
                     {"rms_N", axes(b.rms_N)},
                     {"noise_rms_N", axes(b.noise_rms_N)}});
  }
  nlohmann::json segments = nlohmann::json::array();
  for (std::size_t i = 0; i < l.segment_rms_N.size(); ++i) {
    segments.push_back({{"start_s", l.segment_start_s[i]}, {"rms_N", axes(l.segment_rms_N[i])}});
  }
  return {{"summary", l.summary},
          {"by_flute_rms_N", flutes},
          {"by_angle",
           {{"entry_exit_rms_N", axes(l.entry_exit_rms_N)},
            {"middle_rms_N", axes(l.middle_rms_N)},
            {"synchronous_rms_N", axes(l.synchronous_rms_N)}}},
          {"by_frequency", bands},
          {"by_time", segments}};
}

/// Every candidate scored in one round: its criterion, gain, residual and parameters, or why it
/// was not fitted.
nlohmann::json candidates(const std::vector<CandidateScore>& scores) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& c : scores) {
    nlohmann::json cj = {{"name", c.name}, {"ok", c.ok}};
    if (c.ok) {
      cj["criterion"] = c.criterion;
      cj["gain"] = c.gain;
      cj["residual_rms_N"] = axes(c.residual_rms_N);
      cj["parameters"] = parameters(c.parameters);
      cj["free_parameters"] = c.free_parameters;
      cj["shown"] = c.shown;
      if (!c.shown) {
        cj["message"] = c.message;
      }
    } else {
      cj["message"] = c.message;
    }
    out.push_back(cj);
  }
  return out;
}

}  // namespace

nlohmann::json to_json(const Stage& s) {
  nlohmann::json j = {
      {"added", s.added.empty() ? nlohmann::json(nullptr) : nlohmann::json(s.added)},
      {"parameters", parameters(s.parameters)},
      {"coefficients", parameters(s.coefficients)},
      {"residual_rms_N", axes(s.residual_rms_N)},
      {"residual_percent", axes(s.residual_percent)},
      {"criterion", s.criterion},
      {"free_parameters", s.free_parameters},
      {"candidates", candidates(s.candidates)},
      {"localisation", localisation(s.localisation)}};
  if (!s.added.empty()) {
    j["gain"] = s.gain;
    j["sigma_statistical_only"] = s.sigma_statistical_only;
    j["newly_held"] = parameters(s.newly_held);
    j["runner_up"] = s.runner_up.empty() ? nlohmann::json(nullptr) : nlohmann::json(s.runner_up);
    j["margin_over_runner_up"] = s.margin_over_runner_up;
    j["removed"] = s.removed.empty() ? nlohmann::json(nullptr) : nlohmann::json(s.removed);
    if (!s.removed.empty()) {
      j["exchange_gain"] = s.exchange_gain;
      j["exchange_steps"] = s.exchange_steps;
      j["candidates_before_exchange"] = candidates(s.candidates_before_exchange);
    }
  }
  return j;
}

nlohmann::json to_json(const Diagnosis& d) {
  nlohmann::json steps = nlohmann::json::array();
  for (const auto& s : d.steps) {
    steps.push_back(to_json(s));
  }
  nlohmann::json cat = nlohmann::json::array();
  for (const auto& c : catalogue()) {
    cat.push_back({{"name", c.name},
                   {"signature", c.signature},
                   {"extension", c.extension},
                   {"parameters", c.parameters}});
  }
  nlohmann::json final = nlohmann::json::object();
  for (const auto& e : d.final_parameters) {
    final[e.effect] = parameters(e.parameters);
  }
  return {{"named_effects", d.named_effects},
          {"steps", steps},
          {"final_candidates", candidates(d.final_candidates)},
          {"initial", to_json(d.initial)},
          {"initial_residual_rms_N", axes(d.initial.residual_rms_N)},
          {"final_residual_rms_N", axes(d.final_residual_rms_N)},
          {"noise_floor_N", axes(d.noise_floor_N)},
          {"measured_rms_N", axes(d.measured_rms_N)},
          {"verdict", d.verdict},
          {"final_notes", d.final_notes},
          {"sigma_caveat",
           d.sigma_caveat.empty() ? nlohmann::json(nullptr) : nlohmann::json(d.sigma_caveat)},
          {"final_parameters", final},
          // The final model as a configuration (model_config_from_json reads it): the commanded
          // speed, the fitted values in place; the time base's speed is spindle_rpm.
          {"final_model", model::to_json(d.final_model)},
          {"parameters_at_bound", parameters(d.at_bound)},
          {"damping_ratio_range", {kDampingRatioMin, kDampingRatioMax}},
          {"natural_hz_range", {kNaturalHzMin, kNaturalHzMax}},
          {"stop_reason", d.stop_reason},
          {"criterion", "BIC: sum over fx, fy of n_eff*ln(mean square) + p*ln(2*n_eff)"},
          {"band_hz", d.band_hz},
          {"effective_samples_per_axis", d.effective_samples},
          {"duration_s", d.duration_s},
          {"commanded_rpm", d.commanded_rpm},
          {"spindle_rpm", d.spindle_rpm},
          {"seconds", d.seconds},
          {"catalogue", cat}};
}

namespace {

nlohmann::json bands(const ResidualByBand& r) {
  return {{"spindle_harmonics", axes(r.spindle_harmonics_N)},
          {"tooth_passing_harmonics", axes(r.tooth_harmonics_N)},
          {"rest", axes(r.rest_N)}};
}

nlohmann::json trend(const FeedTrend& t) {
  nlohmann::json j = {{"name", t.name},
                      {"band", t.band},
                      {"suggests", t.suggests},
                      {"sentence", t.sentence},
                      {"law", "excess over the noise floor ~ feed_per_tooth^exponent"}};
  j["exponent"] = t.has_exponent ? nlohmann::json(t.exponent) : nlohmann::json(nullptr);
  j["exponent_sigma"] = t.has_sigma ? nlohmann::json(t.exponent_sigma) : nlohmann::json(nullptr);
  // The excess's share of the measured force against the feed (the sentence states it too).
  j["relative_exponent"] =
      t.has_exponent ? nlohmann::json(t.relative_exponent) : nlohmann::json(nullptr);
  if (!t.has_exponent) {
    j["exponent_absent"] = t.name == "one_feed" ? "fewer than two distinct feeds"
                                                : "no cut stands above its noise floor";
  } else if (!t.has_sigma) {
    j["exponent_sigma_absent"] = "two cuts fit a line exactly: sigma needs three or more";
  }
  return j;
}

}  // namespace

nlohmann::json to_json(const AcrossFeeds& a) {
  nlohmann::json cuts = nlohmann::json::array();
  for (const auto& c : a.cuts) {
    cuts.push_back(
        {{"cut", c.name},
         {"feed_per_tooth_um", c.feed_per_tooth_um},
         {"measured_rms_N", axes(c.measured_rms_N)},
         {"noise_floor_N", axes(c.noise_floor_N)},
         {"residual_rms_N", {{"before", axes(c.before.total_N)}, {"after", axes(c.after.total_N)}}},
         {"by_band", {{"before", bands(c.before)}, {"after", bands(c.after)}}},
         {"excess_N", {{"before", c.before.excess_N}, {"after", c.after.excess_N}}},
         {"named_effects", c.named_effects}});
  }
  return {{"cuts", cuts},
          {"trend", trend(a.trend)},
          {"trend_after", trend(a.trend_after)},
          {"named_in_every_cut", a.named_in_every_cut},
          {"named_in_some_cuts", a.named_in_some_cuts},
          {"shrinks_in_every_cut", a.shrinks_in_every_cut},
          {"verdict", a.verdict}};
}

}  // namespace millwatch::diagnose
