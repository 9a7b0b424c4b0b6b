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
#include <limits>

#include "core/monitor/extremum.hpp"
#include "core/signal/cpu_features.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
// The extremes' pass keeps all four channels in one 256-bit register: an AVX kernel, compiled
// for AVX alone (target attribute) and run only where the CPU has it.
#if defined(__SSE2__) && defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#define MILLWATCH_ROW_EXTREMES_AVX 1
#include <immintrin.h>
#endif

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

/// Extremes of the four channels of a row (fx, fy, fz, fx² + fy²) over samples [from, to], and
/// where each channel's peak is first reached: fx, fy and fz's extreme of largest magnitude (the
/// highest where the two magnitudes are equal), the resultant's square's highest.
struct RowExtremes {
  std::array<double, 4> lowest{};
  std::array<double, 4> highest{};
  std::array<std::int64_t, 4> peak_at{};
};

/// Whether channel c's peak (see RowExtremes::peak_at) is its lowest value, not its highest.
inline bool peak_is_lowest(const RowExtremes& x, std::size_t c) {
  return c < 3 && std::fabs(x.lowest[c]) > std::fabs(x.highest[c]);
}

/// Channel c's peak among its extremes.
inline double row_peak(const RowExtremes& x, std::size_t c) {
  return peak_is_lowest(x, c) ? x.lowest[c] : x.highest[c];
}

/// For each channel c, the first sample in [from, to] whose value equals target[c] (from if none:
/// a NaN), in one pass that ends when all four are found.
template <typename Rows>
std::array<std::int64_t, 4> first_equal(const Rows& row, std::int64_t from, std::int64_t to,
                                        const std::array<double, 4>& target) {
  std::array<std::int64_t, 4> at{from, from, from, from};
  unsigned found = 0;  // bit c: channel c's sample is known
#if defined(__SSE2__)
  const __m128d t_xy = _mm_loadu_pd(&target[0]);
  const __m128d t_zq = _mm_loadu_pd(&target[2]);
  for (std::int64_t n = from; n <= to && found != 0xFU; ++n) {
    const double* r = row(n);
    const auto equal =
        static_cast<unsigned>(_mm_movemask_pd(_mm_cmpeq_pd(_mm_loadu_pd(r), t_xy)) |
                              (_mm_movemask_pd(_mm_cmpeq_pd(_mm_loadu_pd(r + 2), t_zq)) << 2));
#else
  for (std::int64_t n = from; n <= to && found != 0xFU; ++n) {
    const double* r = row(n);
    unsigned equal = 0;
    for (unsigned c = 0; c < 4; ++c) {
      equal |= r[c] == target[c] ? 1U << c : 0U;
    }
#endif
    unsigned fresh = equal & ~found;
    found |= fresh;
    for (std::size_t c = 0; fresh != 0; ++c, fresh >>= 1) {
      if ((fresh & 1U) != 0) {
        at[c] = n;
      }
    }
  }
  return at;
}

/// `row(n)` returns the four channels of absolute sample n side by side. One pass of
/// minimum/maximum (two channels per SSE2 register: the same comparisons as `v < lowest ? v :
/// lowest`, so the same values, bit for bit), then a short scan for the first sample at each
/// peak.
template <typename Rows>
RowExtremes row_extremes_sse2(const Rows& row, std::int64_t from, std::int64_t to) {
  RowExtremes e;
#if defined(__SSE2__)
  const double* r = row(from);
  __m128d low_xy = _mm_loadu_pd(r), high_xy = low_xy;
  __m128d low_zq = _mm_loadu_pd(r + 2), high_zq = low_zq;
  for (std::int64_t n = from + 1; n <= to; ++n) {
    r = row(n);
    const __m128d xy = _mm_loadu_pd(r);
    const __m128d zq = _mm_loadu_pd(r + 2);
    // minpd(v, low) is v < low ? v : low; maxpd(v, high) is v > high ? v : high.
    low_xy = _mm_min_pd(xy, low_xy);
    high_xy = _mm_max_pd(xy, high_xy);
    low_zq = _mm_min_pd(zq, low_zq);
    high_zq = _mm_max_pd(zq, high_zq);
  }
  _mm_storeu_pd(&e.lowest[0], low_xy);
  _mm_storeu_pd(&e.lowest[2], low_zq);
  _mm_storeu_pd(&e.highest[0], high_xy);
  _mm_storeu_pd(&e.highest[2], high_zq);
#else
  const double* r = row(from);
  for (std::size_t c = 0; c < 4; ++c) {
    e.lowest[c] = e.highest[c] = r[c];
  }
  for (std::int64_t n = from + 1; n <= to; ++n) {
    r = row(n);
    for (std::size_t c = 0; c < 4; ++c) {
      e.lowest[c] = r[c] < e.lowest[c] ? r[c] : e.lowest[c];
      e.highest[c] = r[c] > e.highest[c] ? r[c] : e.highest[c];
    }
  }
#endif
  e.peak_at =
      first_equal(row, from, to, {row_peak(e, 0), row_peak(e, 1), row_peak(e, 2), row_peak(e, 3)});
  return e;
}

#if defined(MILLWATCH_ROW_EXTREMES_AVX)
/// One chain of row_extremes_avx(): the four channels' extremes in one register each, and with
/// each extreme the sample it was last replaced at (a strict new extreme), which is the first
/// sample at it. Sample numbers ride as doubles (exact below 2⁵³).
struct ExtremesChain {
  __m256d low, high, low_at, high_at;

  __attribute__((target("avx"), always_inline)) inline void take(const double* r, double n) {
    const __m256d v = _mm256_loadu_pd(r);
    const __m256d at = _mm256_set1_pd(n);
    // minpd(v, low) is v < low ? v : low; maxpd(v, high) is v > high ? v : high. The sample
    // numbers are picked by the masks bit by bit (a blend instruction, GCC 12 turns into a branch
    // per lane).
    const __m256d lower = _mm256_cmp_pd(v, low, _CMP_LT_OQ);
    const __m256d higher = _mm256_cmp_pd(v, high, _CMP_GT_OQ);
    low_at = _mm256_or_pd(_mm256_and_pd(lower, at), _mm256_andnot_pd(lower, low_at));
    high_at = _mm256_or_pd(_mm256_and_pd(higher, at), _mm256_andnot_pd(higher, high_at));
    low = _mm256_min_pd(v, low);
    high = _mm256_max_pd(v, high);
  }
};

/// `mask ? a : b` bit by bit.
__attribute__((target("avx"), always_inline)) inline __m256d pick(__m256d mask, __m256d a,
                                                                  __m256d b) {
  return _mm256_or_pd(_mm256_and_pd(mask, a), _mm256_andnot_pd(mask, b));
}

/// row_extremes_sse2() in one pass: what one chain of strict comparisons from `from` finds,
/// found by two interleaved chains, the even and the odd samples after `from` (each comparison
/// waits on its chain's last extreme: two chains, half as long), then on each lane the more
/// extreme of the two, the earlier sample on a tie. The odd chain starts at ±∞ and never takes
/// ±∞ (nor does one chain after its first sample); a NaN at `from` wins both comparisons of the
/// merge for the even chain, as it stays in one chain. The same values and samples, bit for bit.
template <typename Rows>
__attribute__((target("avx"))) RowExtremes row_extremes_avx(const Rows& row, std::int64_t from,
                                                            std::int64_t to) {
  const __m256d first = _mm256_loadu_pd(row(from));
  const __m256d first_at = _mm256_set1_pd(static_cast<double>(from));
  const __m256d none_at = _mm256_set1_pd(static_cast<double>(to + 1));
  const double inf = std::numeric_limits<double>::infinity();
  ExtremesChain even{first, first, first_at, first_at};
  ExtremesChain odd{_mm256_set1_pd(inf), _mm256_set1_pd(-inf), none_at, none_at};
  double n_d = static_cast<double>(from);
  std::int64_t n = from + 1;
  for (; n + 1 <= to; n += 2) {
    odd.take(row(n), n_d + 1.0);
    even.take(row(n + 1), n_d + 2.0);
    n_d += 2.0;
  }
  if (n <= to) {
    odd.take(row(n), n_d + 1.0);
  }
  const __m256d odd_lower =
      _mm256_or_pd(_mm256_cmp_pd(odd.low, even.low, _CMP_LT_OQ),
                   _mm256_and_pd(_mm256_cmp_pd(odd.low, even.low, _CMP_EQ_OQ),
                                 _mm256_cmp_pd(odd.low_at, even.low_at, _CMP_LT_OQ)));
  const __m256d odd_higher =
      _mm256_or_pd(_mm256_cmp_pd(odd.high, even.high, _CMP_GT_OQ),
                   _mm256_and_pd(_mm256_cmp_pd(odd.high, even.high, _CMP_EQ_OQ),
                                 _mm256_cmp_pd(odd.high_at, even.high_at, _CMP_LT_OQ)));
  RowExtremes e;
  std::array<double, 4> lowest_at{}, highest_at{};
  _mm256_storeu_pd(e.lowest.data(), pick(odd_lower, odd.low, even.low));
  _mm256_storeu_pd(e.highest.data(), pick(odd_higher, odd.high, even.high));
  _mm256_storeu_pd(lowest_at.data(), pick(odd_lower, odd.low_at, even.low_at));
  _mm256_storeu_pd(highest_at.data(), pick(odd_higher, odd.high_at, even.high_at));
  for (std::size_t c = 0; c < 4; ++c) {
    e.peak_at[c] = static_cast<std::int64_t>(peak_is_lowest(e, c) ? lowest_at[c] : highest_at[c]);
  }
  return e;
}
#endif

/// The extremes and peak samples of [from, to]: row_extremes_avx() where the CPU has AVX (and
/// `allow_avx`: the tests compare the two), else row_extremes_sse2().
template <typename Rows>
RowExtremes row_extremes(const Rows& row, std::int64_t from, std::int64_t to,
                         bool allow_avx = true) {
#if defined(MILLWATCH_ROW_EXTREMES_AVX)
  if (allow_avx && signal::cpu_has_avx()) {
    return row_extremes_avx(row, from, to);
  }
#endif
  (void)allow_avx;
  return row_extremes_sse2(row, from, to);
}

/// The revolution's and each flute's tooth period from its events, and α = 360°·T_1/T ([001]
/// eq 36): `m` must hold flutes and the events.
inline void measure_periods(double sample_rate_hz, RevolutionMeasurement& m) {
  const double dt = 1.0 / sample_rate_hz;
  const auto ux = static_cast<std::size_t>(m.flutes);
  m.period_s = (m.event_sample[ux] - m.event_sample[0]) * dt;
  for (std::size_t j = 0; j < ux; ++j) {
    m.flute_period_s[j] = (m.event_sample[j + 1] - m.event_sample[j]) * dt;
  }
  m.alpha_deg = m.flutes >= 2 ? 360.0 * m.flute_period_s[1] / m.period_s : 360.0;
}

/// Measures one revolution. `row(n)` returns the four channels of absolute sample n side by side
/// (fx, fy, fz and the squared in-plane force fx² + fy², as the pipeline's ring holds them) for
/// every n in [⌈boundary[0]⌉, ⌊boundary[flutes]⌋]. `m` must hold flutes, the events, the
/// boundaries and validity already; the periods and forces are filled in. Per flute window,
/// row_extremes() finds every channel's extremes and the first sample at the extreme each peak
/// is refined at (the sample a pass tracking strict new extremes would keep).
template <typename Rows>
void measure_revolution(const Rows& row, double sample_rate_hz, RevolutionMeasurement& m) {
  const int flutes = m.flutes;
  measure_periods(sample_rate_hz, m);
  for (int j = 0; j < flutes; ++j) {
    const auto uj = static_cast<std::size_t>(j);
    const auto from = static_cast<std::int64_t>(std::ceil(m.boundary_sample[uj]));
    const auto to = static_cast<std::int64_t>(std::floor(m.boundary_sample[uj + 1]));
    // The sample each peak is refined at: fx, fy, fz's of largest magnitude, the resultant's
    // largest square.
    const RowExtremes x = row_extremes(row, from, to);
    const std::array<std::int64_t, 4>& at = x.peak_at;
    for (std::size_t c = 0; c < 3; ++c) {
      auto value = [&](std::int64_t n) { return row(n)[c]; };
      const std::int64_t best = at[c];
      double peak = value(best);
      if (best > from && best < to) {
        const Extremum e = refine_extremum(value, best, 1, peak < 0.0);
        if (e.valid) {
          peak = e.value;
        }
      }
      m.peak_N[uj][c] = peak;
      m.range_N[uj][c] = x.highest[c] - x.lowest[c];
    }
    // The in-plane resultant √(fx² + fy²), searched on its square.
    const std::int64_t best_squared = at[3];
    double peak = std::sqrt(row(best_squared)[3]);
    if (best_squared > from && best_squared < to) {
      const Extremum e = refine_extremum([&](std::int64_t n) { return std::sqrt(row(n)[3]); },
                                         best_squared, 1, false);
      if (e.valid) {
        peak = e.value;
      }
    }
    m.peak_resultant_N[uj] = peak;
  }
  m.delta_fy_N = flutes >= 2 ? std::fabs(m.peak_N[0][1]) - std::fabs(m.peak_N[1][1]) : 0.0;
}

}  // namespace millwatch::monitor
