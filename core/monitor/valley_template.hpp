#pragma once
// Where in the revolution the valleys between flutes sit, found on the revolution-synchronous
// average of the resultant force. The valley before flute j's cut opens flute j's period; the
// flute whose period holds the largest force is CE1 (flute 0), the main cutting edge of [001].

#include <array>
#include <span>

namespace millwatch::monitor {

inline constexpr int kMaxFlutes = 8;

struct ValleyTemplate {
  int flutes = 0;
  /// Spindle angle (tracker reference) of the valley that opens each flute's period: flute 0 =
  /// CE1 in [0, 2π), then in the order of rotation, unwrapped so that the angles increase.
  std::array<double, kMaxFlutes> angle_rad{};
  bool valid = false;
};

/// @param resultant_average the synchronous average of √(Fx² + Fy²) on a uniform angle grid
/// @param flutes number of flutes (1..kMaxFlutes)
ValleyTemplate find_valley_template(std::span<const double> resultant_average, int flutes);

}  // namespace millwatch::monitor
