#include "core/model/flute_positions.hpp"

#include <cmath>
#include <numbers>

namespace millwatch::model {

void flute_positions(double tool_radius_um, std::span<const double> pitch_rad, double offset_um,
                     double offset_angle_rad, std::vector<FlutePosition>& out) {
  out.resize(pitch_rad.size());
  for (std::size_t j = 0; j < pitch_rad.size(); ++j) {
    const double c = std::cos(offset_angle_rad + pitch_rad[j]);
    const double s = std::sin(offset_angle_rad + pitch_rad[j]);
    const double along = tool_radius_um + offset_um * c;  // component along the flute direction
    const double across = offset_um * s;                  // component in the rotation direction
    out[j] = {std::hypot(along, across), std::atan2(across, along)};
  }
}

std::vector<FlutePosition> flute_positions(double tool_radius_um, std::span<const double> pitch_rad,
                                           double offset_um, double offset_angle_rad) {
  std::vector<FlutePosition> out;
  flute_positions(tool_radius_um, pitch_rad, offset_um, offset_angle_rad, out);
  return out;
}

double flute_spacing_rad(std::span<const double> pitch_rad, std::span<const FlutePosition> flutes,
                         int prev, int next) {
  const auto p = static_cast<std::size_t>(prev);
  const auto n = static_cast<std::size_t>(next);
  double spacing =
      pitch_rad[n] - pitch_rad[p] - flutes[n].angle_offset_rad + flutes[p].angle_offset_rad;
  const double two_pi = 2.0 * std::numbers::pi;
  spacing = std::fmod(spacing, two_pi);
  if (spacing <= 0.0) {
    spacing += two_pi;
  }
  return spacing;
}

}  // namespace millwatch::model
