#pragma once
// A diagnosis as JSON (report.json, millwatch issue 8 item 4): named_effects (in the order
// added; empty when nothing is missing), steps [{added, parameters {name: {value, sigma}},
// residual_rms_N {fx, fy}, residual_percent {fx, fy}, criterion, gain, runner_up,
// margin_over_runner_up, candidates, localisation}], initial (the starting model, same form),
// initial_residual_rms_N, final_residual_rms_N, noise_floor_N, measured_rms_N (each {fx, fy}),
// final_parameters {effect: {name: {value, sigma}}} (the final model's, as its last fit left
// them), verdict, stop_reason, band_hz, effective_samples_per_axis, criterion ("BIC"), the
// catalogue.

#include <nlohmann/json.hpp>

#include "core/diagnose/across_feeds.hpp"
#include "core/diagnose/diagnosis.hpp"

namespace millwatch::diagnose {

nlohmann::json to_json(const Diagnosis& d);
nlohmann::json to_json(const Stage& s);
/// across_feeds: {cuts [{cut, feed_per_tooth_um, measured_rms_N, noise_floor_N,
/// residual_rms_N {before, after}, by_band {before, after: {spindle_harmonics,
/// tooth_passing_harmonics, rest}}, excess_N {before, after}, named_effects}], trend, trend_after
/// ({name, exponent, exponent_sigma, band, suggests, sentence}; exponent and σ null with a reason
/// when they cannot be read), named_in_every_cut, named_in_some_cuts, shrinks_in_every_cut,
/// verdict}.
nlohmann::json to_json(const AcrossFeeds& a);

}  // namespace millwatch::diagnose
