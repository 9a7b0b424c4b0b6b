#pragma once
// Material presets (`millwatch calibrate -o material.json`) in a configuration: a string where a
// model's "material" object goes names a preset file, read relative to the configuration file's
// folder, and its "material" takes the string's place:
//
//   {"model": {"material": "material.json", ...}, ...}                (monitor configuration)
//   {"monitor": {"model": {"material": "presets/ti.json"}}, ...}       (daemon configuration)
//
// The preset's other sections (coefficients' σ, runout, fit, provenance) are information for the
// reader; only "material" enters the model. The replay (--config) and the daemon read presets
// this way; a reload (SIGHUP) reads the preset again.

#include <filesystem>
#include <nlohmann/json.hpp>

namespace millwatch::shell {

/// The "material" object of a preset file.
/// @throws std::runtime_error "PATH: ..." for a file that cannot be read or is not a preset
nlohmann::json read_material_preset(const std::filesystem::path& path);

/// Replaces "model.material" and "monitor.model.material" strings in `config` (read from
/// `config_path`) by the presets they name.
/// @throws std::runtime_error naming the configuration file, the field and the preset
void resolve_material_presets(nlohmann::json& config, const std::filesystem::path& config_path);

}  // namespace millwatch::shell
