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

/// Measures one revolution. `channel(c, n)` returns channel c (0 fx, 1 fy, 2 fz) at absolute
/// sample n for every n in [⌈boundary[0]⌉, ⌊boundary[flutes]⌋]. `m` must hold flutes, the
/// events, the boundaries and validity already; the periods and forces are filled in.
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
    // fx, fy, fz: the sample of largest magnitude and the range, in one pass per channel.
    for (int c = 0; c < 3; ++c) {
      auto value = [&](std::int64_t n) { return channel(c, n); };
      std::int64_t best = from;
      double lowest = value(from), highest = lowest;
      std::int64_t at_low = from, at_high = from;
      for (std::int64_t n = from + 1; n <= to; ++n) {
        const double v = value(n);
        if (v < lowest) {
          lowest = v;
          at_low = n;
        }
        if (v > highest) {
          highest = v;
          at_high = n;
        }
      }
      best = std::fabs(lowest) > std::fabs(highest) ? at_low : at_high;
      double peak = value(best);
      if (best > from && best < to) {
        const Extremum e = refine_extremum(value, best, 1, peak < 0.0);
        if (e.valid) {
          peak = e.value;
        }
      }
      m.peak_N[uj][static_cast<std::size_t>(c)] = peak;
      m.range_N[uj][static_cast<std::size_t>(c)] = highest - lowest;
    }
    // The in-plane resultant √(fx² + fy²), searched on its square.
    auto squared = [&](std::int64_t n) {
      const double x = channel(0, n);
      const double y = channel(1, n);
      return x * x + y * y;
    };
    std::int64_t best = from;
    for (std::int64_t n = from + 1; n <= to; ++n) {
      if (squared(n) > squared(best)) {
        best = n;
      }
    }
    double peak = std::sqrt(squared(best));
    if (best > from && best < to) {
      const Extremum e =
          refine_extremum([&](std::int64_t n) { return std::sqrt(squared(n)); }, best, 1, false);
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
