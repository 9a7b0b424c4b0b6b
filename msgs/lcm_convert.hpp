#pragma once
// Between the pipeline's values and the LCM message types of msgs/*.lcm. Array length fields
// are always set from the vectors' sizes here (LCM 1.3.1 reads out of bounds when they differ).
// No message carries a NaN: what does not exist is 0 with its validity flag false.

#include <cstdint>

#include "core/identify/identifier.hpp"
#include "core/monitor/pipeline.hpp"
#include "millwatch/flute_peaks2_t.hpp"
#include "millwatch/force_block_t.hpp"
#include "millwatch/force_coefficients_t.hpp"
#include "millwatch/model_residual_t.hpp"
#include "millwatch/pipeline_status5_t.hpp"
#include "millwatch/runout_estimate_t.hpp"
#include "millwatch/spindle_state2_t.hpp"
#include "millwatch/sync_average2_t.hpp"
#include "millwatch/tool_alert_t.hpp"
#include "millwatch/tooth_periods2_t.hpp"

namespace millwatch::messaging {

/// Sample block → message (copies the samples).
force_block_t to_message(const monitor::SampleBlock& block);
/// Message → sample block viewing the message's arrays (valid while `msg` lives).
monitor::SampleBlock to_block(const force_block_t& msg);

tooth_periods2_t tooth_periods(const monitor::RevolutionRecord& r);
flute_peaks2_t flute_peaks(const monitor::RevolutionRecord& r);
model_residual_t model_residual(const monitor::RevolutionRecord& r);
spindle_state2_t spindle_state(const monitor::SpindleUpdate& u);
tool_alert_t tool_alert(const monitor::Alert& a, std::int64_t seq);
/// An identified window: its runout (the monitor's flute labelling, CE1 = flute 0) and its
/// force coefficients, each with σ; `valid` false (and zeros) when the fit failed.
runout_estimate_t runout_estimate(const identify::IdentifiedWindow& w);
force_coefficients_t force_coefficients(const identify::IdentifiedWindow& w);
pipeline_status5_t pipeline_status(const monitor::PipelineStatus& s, std::int64_t seq,
                                   std::int64_t published, std::int64_t dropped);

}  // namespace millwatch::messaging
