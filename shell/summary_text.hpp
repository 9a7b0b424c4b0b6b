#pragma once
// The run summary as a person reads it on a terminal: speed, revolutions measured of those
// turned, α, each flute's period and peak forces, ΔFy, residuals, alerts and warnings, in a
// dozen lines. The JSON (RunSummary's keys, plus the replay's input, input_format, filter,
// bad_lines) is the source; nothing here is computed that the JSON does not hold.

#include <nlohmann/json.hpp>
#include <string>

namespace millwatch::shell {

std::string summary_text(const nlohmann::json& summary);

}  // namespace millwatch::shell
