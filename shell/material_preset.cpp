#include "shell/material_preset.hpp"

#include <spdlog/spdlog.h>

#include <stdexcept>
#include <string>

#include "shell/json_file.hpp"

namespace millwatch::shell {
namespace {

void resolve_at(nlohmann::json& model, const std::string& field,
                const std::filesystem::path& config_path) {
  if (!model.is_object() || !model.contains("material") || !model["material"].is_string()) {
    return;
  }
  const std::filesystem::path named = model["material"].get<std::string>();
  const std::filesystem::path preset =
      named.is_absolute() ? named : config_path.parent_path() / named;
  try {
    model["material"] = read_material_preset(preset);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(config_path.string() + ": " + field + ": " + e.what());
  }
}

}  // namespace

nlohmann::json read_material_preset(const std::filesystem::path& path) {
  if (!std::filesystem::exists(path)) {
    throw std::runtime_error(path.string() + ": material preset not found");
  }
  const nlohmann::json j = read_json_file(path);
  if (!j.is_object() || !j.contains("material") || !j["material"].is_object()) {
    throw std::runtime_error(path.string() +
                             ": not a material preset (no \"material\" object; `millwatch "
                             "calibrate -o` writes one)");
  }
  // What calibrate warned of when it wrote the preset (coefficients that are not the
  // material's, minima the record did not choose between) is said again wherever it is used:
  // the coefficients themselves carry no mark.
  if (j.contains("warnings") && j["warnings"].is_array()) {
    for (const auto& w : j["warnings"]) {
      if (w.is_string()) {
        spdlog::warn("{}: material preset written with a warning: {}", path.string(),
                     w.get<std::string>());
      }
    }
  }
  return j["material"];
}

void resolve_material_presets(nlohmann::json& config, const std::filesystem::path& config_path) {
  if (!config.is_object()) {
    return;
  }
  if (config.contains("model")) {
    resolve_at(config["model"], "model.material", config_path);
  }
  if (config.contains("monitor") && config["monitor"].is_object() &&
      config["monitor"].contains("model")) {
    resolve_at(config["monitor"]["model"], "monitor.model.material", config_path);
  }
}

}  // namespace millwatch::shell
