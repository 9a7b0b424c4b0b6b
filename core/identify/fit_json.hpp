#pragma once
// The identification as the run summary and the operator see it: `runout`, `coefficients` and
// `fit` (see the README, "Identification").

#include <nlohmann/json.hpp>

#include "core/identify/identifier.hpp"

namespace millwatch::identify {

/// {"runout": {...}, "coefficients": {...}, "fit": {...}} of one fitted window. Every number is
/// finite; a fit that failed gives {"fit": {"ok": false, "reason": ...}} only.
nlohmann::json to_json(const IdentifiedWindow& window);

}  // namespace millwatch::identify
