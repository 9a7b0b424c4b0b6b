#pragma once
// What one revolution of filtered force says about the tool: tooth periods, the phase angle α,
// each flute's peak forces and ΔFy, from the revolution's tooth events.
//
// Flute j's period runs from event j to event j + 1 (event N is the next revolution's first),
// and its force window from boundary j to boundary j + 1 (the boundary is the event itself for
// valleys, the middle of the quiet stretch before the pulse for interrupted cuts):
//   T = e_N − e_0,  T_j = e_{j+1} − e_j,  α = 360°·T_1/T  ([001] eq 36, [003] eqs 4-5),
//   ΔFy = |peak Fy of CE1| − |peak Fy of CE2|  ([001] Fig. 5).
// Peaks are the signed sample of largest magnitude per channel within the flute's window,
// refined by a three-point parabola; the range (largest minus smallest sample) of each channel
// is a flute force that a slowly drifting channel offset does not change.

#include <array>
#include <cmath>
#include <cstdint>

#include "core/monitor/extremum.hpp"

namespace millwatch::monitor {

inline constexpr int kMaxFlutes = 8;

/// The instant that separates flutes (tooth_events.hpp): a valley of the force, or the centroid
/// of a tooth's pulse where the force returns to zero between teeth.
enum class ToothEventKind : std::uint8_t { kValley, kCentroid };

struct RevolutionMeasurement {
  std::int64_t sequence = 0;  ///< revolutions measured since the events were (re)started
  int flutes = 0;
  /// Fractional sample index of each tooth event (valley or pulse centroid); event[flutes] is
  /// the next revolution's first.
  std::array<double, kMaxFlutes + 1> event_sample{};
  /// Where each flute's force window starts (= event_sample for valleys).
  std::array<double, kMaxFlutes + 1> boundary_sample{};
  double period_s = 0.0;
  std::array<double, kMaxFlutes> flute_period_s{};
  double alpha_deg = 0.0;
  /// Signed peak of fx, fy, fz per flute (largest magnitude in the flute's window), N.
  std::array<std::array<double, 3>, kMaxFlutes> peak_N{};
  std::array<double, kMaxFlutes> peak_resultant_N{};
  /// Range (largest minus smallest sample) of fx, fy, fz per flute within its window, N: a
  /// measure of each flute's force that a slowly drifting channel offset does not change.
  std::array<std::array<double, 3>, kMaxFlutes> range_N{};
  double delta_fy_N = 0.0;
  bool valid = false;  ///< every event measured (a true valley, a whole pulse)
  /// The revolution's bounds (both CE1 events) were measured: its peaks and ranges per flute are
  /// meaningful even when a flute in between left no event (it did not cut: its peaks are ~0).
  bool bounded = false;
};

/// Measures one revolution. `channel(c, n)` returns channel c (0 fx, 1 fy, 2 fz, 3 the squared
/// in-plane force fx² + fy², as the pipeline's ring holds it) at absolute sample n for every n in
/// [⌈boundary[0]⌉, ⌊boundary[flutes]⌋]. `m` must hold flutes, the events, the boundaries and
/// validity already; the periods and forces are filled in. One pass over each flute's window
/// finds every channel's extremes.
template <typename Channel>
void measure_revolution(const Channel& channel, double sample_rate_hz, RevolutionMeasurement& m) {
  const int flutes = m.flutes;
  const double dt = 1.0 / sample_rate_hz;
  const auto ux = static_cast<std::size_t>(flutes);
  m.period_s = (m.event_sample[ux] - m.event_sample[0]) * dt;
  for (int j = 0; j < flutes; ++j) {
    const auto uj = static_cast<std::size_t>(j);
    m.flute_period_s[uj] = (m.event_sample[uj + 1] - m.event_sample[uj]) * dt;
    const auto from = static_cast<std::int64_t>(std::ceil(m.boundary_sample[uj]));
    const auto to = static_cast<std::int64_t>(std::floor(m.boundary_sample[uj + 1]));
    // fx, fy, fz: the sample of largest magnitude and the range; the resultant's largest square.
    std::array<double, 3> lowest{}, highest{};
    std::array<std::int64_t, 3> at_low{from, from, from}, at_high{from, from, from};
    for (std::size_t c = 0; c < 3; ++c) {
      lowest[c] = highest[c] = channel(static_cast<int>(c), from);
    }
    std::int64_t best_squared = from;
    double largest_squared = channel(3, from);
    // Written as selects, not branches: a force rising or falling through a flute's window
    // makes "a new extreme" true and false in runs the branch predictor keeps missing.
    for (std::int64_t n = from + 1; n <= to; ++n) {
      for (std::size_t c = 0; c < 3; ++c) {
        const double v = channel(static_cast<int>(c), n);
        const bool below = v < lowest[c];
        const bool above = v > highest[c];
        lowest[c] = below ? v : lowest[c];
        at_low[c] = below ? n : at_low[c];
        highest[c] = above ? v : highest[c];
        at_high[c] = above ? n : at_high[c];
      }
      const double q = channel(3, n);
      const bool larger = q > largest_squared;
      largest_squared = larger ? q : largest_squared;
      best_squared = larger ? n : best_squared;
    }
    for (std::size_t c = 0; c < 3; ++c) {
      auto value = [&](std::int64_t n) { return channel(static_cast<int>(c), n); };
      const std::int64_t best =
          std::fabs(lowest[c]) > std::fabs(highest[c]) ? at_low[c] : at_high[c];
      double peak = value(best);
      if (best > from && best < to) {
        const Extremum e = refine_extremum(value, best, 1, peak < 0.0);
        if (e.valid) {
          peak = e.value;
        }
      }
      m.peak_N[uj][c] = peak;
      m.range_N[uj][c] = highest[c] - lowest[c];
    }
    // The in-plane resultant √(fx² + fy²), searched on its square.
    double peak = std::sqrt(largest_squared);
    if (best_squared > from && best_squared < to) {
      const Extremum e = refine_extremum([&](std::int64_t n) { return std::sqrt(channel(3, n)); },
                                         best_squared, 1, false);
      if (e.valid) {
        peak = e.value;
      }
    }
    m.peak_resultant_N[uj] = peak;
  }
  m.alpha_deg = flutes >= 2 ? 360.0 * m.flute_period_s[1] / m.period_s : 360.0;
  m.delta_fy_N = flutes >= 2 ? std::fabs(m.peak_N[0][1]) - std::fabs(m.peak_N[1][1]) : 0.0;
}

}  // namespace millwatch::monitor
