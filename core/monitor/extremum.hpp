#pragma once
// Sub-sample location of a valley or peak from a least-squares polynomial through the 2h+1
// samples around the discrete extreme (u in samples from it).

#include <array>
#include <cmath>
#include <cstdint>

#include "core/monitor/nearest_integer.hpp"

namespace millwatch::monitor {

struct Extremum {
  double position = 0.0;  ///< absolute sample index, fractional
  double value = 0.0;     ///< the parabola's value there
  bool valid = false;     ///< false when the fit is not curved the right way
};

/// The sample nearest a fractional sample position, halves away from zero (std::llround()).
inline std::int64_t nearest_sample(double position) {
  return nearest_integer(position);
}

/// The centred fit's moments s_k = Σ u^k over u = −h..h and the reciprocals of its normal
/// equations' determinants: a fit multiplies by them (its four divisions, each waiting ~13
/// cycles, were most of its latency after the sums). A reciprocal of 0 stands for a zero
/// determinant (h < 2 for the odd one, h = 0 for the even one: no fit).
struct FitMoments {
  double s0 = 0.0, s2 = 0.0, s4 = 0.0, s6 = 0.0;
  double per_s2 = 0.0;        ///< 1/s2 (h = 1: the slope's normal equation alone)
  double per_det_even = 0.0;  ///< 1/(s0·s4 − s2²)
  double per_det_odd = 0.0;   ///< 1/(s2·s6 − s4²)
};

/// The moments in closed form (Faulhaber's sums, doubled): exact while they stay below 2⁵³ (h up
/// to ~100), within rounding beyond, like the sums themselves.
inline FitMoments fit_moments(int half_width) {
  const auto h = static_cast<double>(half_width);
  const double base = h * (h + 1.0) * (2.0 * h + 1.0);
  FitMoments m;
  m.s0 = 2.0 * h + 1.0;
  m.s2 = base / 3.0;
  m.s4 = base * (3.0 * h * h + 3.0 * h - 1.0) / 15.0;
  m.s6 = base * (((3.0 * h + 6.0) * h * h - 3.0) * h + 1.0) / 21.0;
  const double det_even = m.s0 * m.s4 - m.s2 * m.s2;
  const double det_odd = m.s2 * m.s6 - m.s4 * m.s4;
  m.per_s2 = m.s2 != 0.0 ? 1.0 / m.s2 : 0.0;
  m.per_det_even = det_even != 0.0 ? 1.0 / det_even : 0.0;
  m.per_det_odd = det_odd != 0.0 ? 1.0 / det_odd : 0.0;
  return m;
}

/// fit_moments(h), from a table for the usual widths (the same values: computed by it once).
inline FitMoments usual_fit_moments(int half_width) {
  constexpr int kTabled = 64;
  static const std::array<FitMoments, kTabled + 1> table = [] {
    std::array<FitMoments, kTabled + 1> t{};
    for (int h = 0; h <= kTabled; ++h) {
      t[static_cast<std::size_t>(h)] = fit_moments(h);
    }
    return t;
  }();
  return half_width >= 0 && half_width <= kTabled ? table[static_cast<std::size_t>(half_width)]
                                                  : fit_moments(half_width);
}

/// `signal(n)` returns the sample at absolute index n for n in [center − h, center + h].
/// h = 1: three-point parabola. h ≥ 2: least-squares cubic a + b·u + c·u² + d·u³, whose
/// stationary point nearest the centre is the extreme — the cubic term absorbs the asymmetry of
/// a valley between a long and a short flute, which biases a parabola.
template <typename Signal>
Extremum refine_extremum(const Signal& signal, std::int64_t center, int half_width, bool minimum) {
  // Normal equations of the centred fit decouple (odd moments vanish by symmetry):
  //   [s0 s2; s2 s4]·[a c] = [y0 y2],  [s2 s4; s4 s6]·[b d] = [y1 y3].
  const FitMoments m = usual_fit_moments(half_width);
  const double s0 = m.s0, s2 = m.s2, s4 = m.s4, s6 = m.s6;
  // y_k = Σ u^k·y(u) over the pairs ±u: even k take y(u) + y(−u), odd k y(u) − y(−u). Two
  // sets of sums (odd and even u) so that the additions do not wait on one another.
  const double y_centre = signal(center);
  std::array<double, 4> odd{y_centre, 0.0, 0.0, 0.0}, even{};
  const auto add_pair = [&](int u, std::array<double, 4>& sums) {
    const double above = signal(center + u), below = signal(center - u);
    const double sum = above + below, difference = above - below;
    const double u1 = u;
    const double u2 = u1 * u1;
    sums[0] += sum;
    sums[1] += u1 * difference;
    sums[2] += u2 * sum;
    sums[3] += u2 * u1 * difference;
  };
  int k = 1;
  for (; k < half_width; k += 2) {
    add_pair(k, odd);
    add_pair(k + 1, even);
  }
  if (k == half_width) {
    add_pair(k, odd);
  }
  const double y0 = odd[0] + even[0], y1 = odd[1] + even[1];
  const double y2 = odd[2] + even[2], y3 = odd[3] + even[3];
  const double a = (s4 * y0 - s2 * y2) * m.per_det_even;
  const double c = (s0 * y2 - s2 * y0) * m.per_det_even;
  double b = y1 * m.per_s2;
  double d = 0.0;
  if (half_width >= 2) {
    b = (s6 * y1 - s4 * y3) * m.per_det_odd;
    d = (s2 * y3 - s4 * y1) * m.per_det_odd;
  }
  Extremum e;
  e.position = static_cast<double>(center);
  e.value = y_centre;
  // Stationary points: 3d·u² + 2c·u + b = 0; the extreme needs curvature 2c + 6d·u of the
  // right sign.
  double u = 0.0;
  if (std::fabs(d) < 1e-12 * (std::fabs(c) + 1e-300)) {
    if (c == 0.0) {
      return e;
    }
    u = -b / (2.0 * c);
  } else {
    const double disc = c * c - 3.0 * d * b;
    if (disc < 0.0) {
      return e;
    }
    const double r = std::sqrt(disc);
    // The two roots, computed without cancellation; take the one nearest the centre.
    const double q = -(c + std::copysign(r, c));
    const double u1 = q / (3.0 * d);
    const double u2 = q != 0.0 ? b / q : u1;
    u = std::fabs(u1) < std::fabs(u2) ? u1 : u2;
  }
  const double curvature = 2.0 * c + 6.0 * d * u;
  if ((minimum && curvature <= 0.0) || (!minimum && curvature >= 0.0) || u < -half_width ||
      u > half_width) {
    return e;
  }
  e.position = static_cast<double>(center) + u;
  e.value = a + u * (b + u * (c + u * d));
  e.valid = true;
  return e;
}

}  // namespace millwatch::monitor
