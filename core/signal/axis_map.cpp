#include "core/signal/axis_map.hpp"

#include "core/config/json_reader.hpp"

namespace millwatch::signal {
namespace {

constexpr std::array<const char*, 3> kAxes = {"x", "y", "z"};
constexpr std::array<const char*, 3> kChannels = {"fx", "fy", "fz"};

}  // namespace

AxisMap axis_map_from_json(const nlohmann::json& j, const std::string& path) {
  config::ObjectReader r(j, path);
  AxisMap map;
  std::array<bool, 3> used{};
  for (std::size_t a = 0; a < 3; ++a) {
    const std::string fallback = std::string("-") + kChannels[a];
    const std::string entry =
        r.choice(kAxes[a], fallback, {"+fx", "-fx", "+fy", "-fy", "+fz", "-fz", "fx", "fy", "fz"});
    const bool negative = entry[0] == '-';
    const std::string channel = entry[0] == '+' || negative ? entry.substr(1) : entry;
    const int source = channel == "fx" ? 0 : channel == "fy" ? 1 : 2;
    if (used[static_cast<std::size_t>(source)]) {
      config::fail(r.path_of(kAxes[a]),
                   "channel \"" + channel + "\" is already mapped to another axis");
    }
    used[static_cast<std::size_t>(source)] = true;
    map.source[a] = source;
    map.sign[a] = negative ? -1.0 : 1.0;
  }
  r.finish();
  return map;
}

nlohmann::json to_json(const AxisMap& map) {
  nlohmann::json j;
  for (std::size_t a = 0; a < 3; ++a) {
    j[kAxes[a]] = std::string(map.sign[a] < 0 ? "-" : "+") +
                  kChannels[static_cast<std::size_t>(map.source[a])];
  }
  return j;
}

}  // namespace millwatch::signal
