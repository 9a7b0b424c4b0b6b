#pragma once
// Simulated cuts in which an effect is hidden, for the diagnosis's tests and benchmark: the cut
// simulator with the effect on (and what a real cut has that the fitted model does not: a finer
// angle step, more helix discs, noise 0.015 N, 0.01 N quantisation), and the model the
// diagnosis starts from (the plain model at the commanded speed, coarser, coefficients off).

#include <string>
#include <vector>

#include "core/diagnose/diagnosis.hpp"
#include "core/sim/scenario.hpp"

namespace millwatch::test {

/// A cut with hidden effects (catalogue names; empty: nothing hidden).
struct HiddenEffectCut {
  sim::Scenario scenario;      ///< the truth
  model::ModelConfig start;    ///< what the diagnosis starts from
  diagnose::CutRecord record;  ///< the simulated recording, in the model frame
};

/// The base cut ([000]'s cp-Ti case, power law, 2 flutes, 25,000 rpm, f_t 4 µm) with the named
/// effects switched on in the simulator, simulated for duration_s at sample_rate_hz. `known`
/// effects are on in the simulator and in the starting model (e.g. runout, without which tool
/// deflection leaves no trace: a symmetric cut's steady chips do not depend on it).
HiddenEffectCut hidden_effect_cut(const std::vector<std::string>& hidden,
                                  const std::vector<std::string>& known = {},
                                  double duration_s = 0.4, double sample_rate_hz = 20000.0,
                                  unsigned seed = 7);

/// The same cut at another feed per tooth (a feed sweep with one tool: the hidden effects' own
/// parameters as hidden_effect_cut sets them; its accumulation recipes keep their own feed).
HiddenEffectCut hidden_effect_cut_at_feed(const std::vector<std::string>& hidden,
                                          double feed_per_tooth_um, double duration_s = 0.4,
                                          double sample_rate_hz = 20000.0, unsigned seed = 7);

/// Only simulates: the scenario as hidden_effect_cut builds it, before recording.
sim::Scenario hidden_effect_scenario(const std::vector<std::string>& hidden, double duration_s,
                                     double sample_rate_hz, unsigned seed);

/// The parameter called `name` among `ps` (a stage's or a candidate's), or nullptr.
const diagnose::Parameter* find_parameter(const std::vector<diagnose::Parameter>& ps,
                                          const std::string& name);

/// The recording of a scenario in the model frame, as a data acquisition with an anti-aliasing
/// filter records it (flat to 0.4·fs): simulated at 8× the rate, filtered, decimated, noise and
/// quantisation added at the recorder's rate.
diagnose::CutRecord record_in_model_frame(const sim::Scenario& s);

}  // namespace millwatch::test
