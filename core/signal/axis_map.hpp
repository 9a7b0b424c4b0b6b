#pragma once
// Axis map: turns a dynamometer's channel reading into the model frame (model_config.hpp):
//   model[a] = sign[a] · reading[source[a]],  a ∈ {x, y, z}.
// The default is a dynamometer under the workpiece with its axes along the machine's: it reads
// the force on the workpiece, minus the force on the tool, so every sign is −1.
// JSON form: {"x": "-fx", "y": "-fy", "z": "-fz"}; each entry is a sign and a channel name.

#include <array>
#include <nlohmann/json.hpp>
#include <string>

namespace millwatch::signal {

struct AxisMap {
  std::array<int, 3> source = {0, 1, 2};
  std::array<double, 3> sign = {-1.0, -1.0, -1.0};

  /// Reading (channels fx, fy, fz) → force on the tool in the model frame.
  [[nodiscard]] std::array<double, 3> to_model(const std::array<double, 3>& reading) const {
    return {sign[0] * reading[static_cast<std::size_t>(source[0])],
            sign[1] * reading[static_cast<std::size_t>(source[1])],
            sign[2] * reading[static_cast<std::size_t>(source[2])]};
  }
  /// Force on the tool in the model frame → what the dynamometer reads.
  [[nodiscard]] std::array<double, 3> to_reading(const std::array<double, 3>& model) const {
    std::array<double, 3> reading{};
    for (std::size_t a = 0; a < 3; ++a) {
      reading[static_cast<std::size_t>(source[a])] = sign[a] * model[a];
    }
    return reading;
  }
};

/// Identity map: the reading already is the force on the tool in the model frame.
inline AxisMap identity_axis_map() {
  return {{0, 1, 2}, {1.0, 1.0, 1.0}};
}

/// @throws config::ConfigError naming the entry (e.g. "axis_map.y") for a bad or repeated channel.
AxisMap axis_map_from_json(const nlohmann::json& j, const std::string& path);
nlohmann::json to_json(const AxisMap& map);

}  // namespace millwatch::signal
