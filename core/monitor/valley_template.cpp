#include "core/monitor/valley_template.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "core/monitor/extremum.hpp"

namespace millwatch::monitor {

ValleyTemplate find_valley_template(std::span<const double> avg, int flutes) {
  ValleyTemplate t;
  t.flutes = flutes;
  const int bins = static_cast<int>(avg.size());
  if (flutes < 1 || flutes > kMaxFlutes || bins < 8 * flutes) {
    return t;
  }
  auto at = [&](long k) { return avg[static_cast<std::size_t>(((k % bins) + bins) % bins)]; };
  // Local minima over ±a quarter pitch, deepest first, at least half a pitch apart.
  const int reach = std::max(1, bins / (4 * flutes));
  std::vector<int> candidates;
  for (int k = 0; k < bins; ++k) {
    bool lowest = true;
    for (int d = 1; d <= reach && lowest; ++d) {
      lowest = at(k) <= at(k - d) && at(k) < at(k + d);
    }
    if (lowest) {
      candidates.push_back(k);
    }
  }
  std::sort(candidates.begin(), candidates.end(), [&](int a, int b) { return at(a) < at(b); });
  std::vector<int> picked;
  const int separation = bins / (2 * flutes);
  for (int k : candidates) {
    const bool apart = std::all_of(picked.begin(), picked.end(), [&](int p) {
      const int d = std::abs(k - p);
      return std::min(d, bins - d) >= separation;
    });
    if (apart) {
      picked.push_back(k);
    }
    if (static_cast<int>(picked.size()) == flutes) {
      break;
    }
  }
  if (static_cast<int>(picked.size()) < flutes) {
    return t;
  }
  std::sort(picked.begin(), picked.end());

  // Sub-bin valley angles and the peak of each period (valley i to valley i+1).
  const double bin_rad = 2.0 * std::numbers::pi / bins;
  std::array<double, kMaxFlutes> angle{};
  std::array<double, kMaxFlutes> peak{};
  for (int i = 0; i < flutes; ++i) {
    const Extremum e = refine_extremum(at, picked[static_cast<std::size_t>(i)], 1, true);
    angle[static_cast<std::size_t>(i)] =
        std::fmod(e.position * bin_rad + 2.0 * std::numbers::pi, 2.0 * std::numbers::pi);
    const int from = picked[static_cast<std::size_t>(i)];
    int to = picked[static_cast<std::size_t>((i + 1) % flutes)];
    if (to <= from) {
      to += bins;
    }
    double p = 0.0;
    for (int k = from; k <= to; ++k) {
      p = std::max(p, at(k));
    }
    peak[static_cast<std::size_t>(i)] = p;
  }
  const auto ce1 =
      static_cast<int>(std::max_element(peak.begin(), peak.begin() + flutes) - peak.begin());
  // Unwrapped in the order of rotation: angle[0] ≤ angle[1] ≤ ... < angle[0] + 2π.
  for (int j = 0; j < flutes; ++j) {
    double a = angle[static_cast<std::size_t>((ce1 + j) % flutes)];
    while (j > 0 && a < t.angle_rad[0]) {
      a += 2.0 * std::numbers::pi;
    }
    t.angle_rad[static_cast<std::size_t>(j)] = a;
  }
  t.valid = true;
  return t;
}

}  // namespace millwatch::monitor
