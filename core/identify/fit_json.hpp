#pragma once
// The identification as the run summary and the operator see it: `runout`, `coefficients` and
// `fit` (see the README, "Identification").

#include <array>
#include <nlohmann/json.hpp>

#include "core/identify/identifier.hpp"

namespace millwatch::identify {

/// {"runout": {...}, "coefficients": {...}, "fit": {...}} of one fitted window. Every number is
/// finite; a fit that failed gives {"fit": {"ok": false, "reason": ...}} only.
nlohmann::json to_json(const IdentifiedWindow& window);

/// [fx, fy, fz]: each axis's value, null for an axis the fit did not compare (its RMS is 0 there,
/// which would read as "measured 0 N") or a value that is not finite.
nlohmann::json per_axis(const std::array<double, 3>& values, const std::array<bool, 3>& compared);

}  // namespace millwatch::identify
