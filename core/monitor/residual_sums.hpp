#pragma once
// The sums behind a revolution's residuals over a run of samples: measured rows (fx, fy, fz,
// Fx² + Fy², as the sample ring holds them) against the model's rows at the same samples.
//   Σ dx², Σ dy², Σ dz² (d = measured − model), Σ (Fx² + Fy²) measured,
//   and the flute's and the sector's Σ (dx² + dy²): two sums of the same terms, reset at their
//   own edges by the caller.
// Every sum adds its terms in the samples' order: the AVX kernel (one 256-bit register for the
// four axis sums) does on each lane what the scalar one does, so the same sums, bit for bit.

#include <array>
#include <cstdint>

#include "core/signal/cpu_features.hpp"

#if defined(__SSE2__) && defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#define MILLWATCH_RESIDUAL_SUMS_AVX 1
#include <immintrin.h>
#endif

namespace millwatch::monitor {

struct ResidualSums {
  /// Σ dx², Σ dy², Σ dz², and Σ (Fx² + Fy²) measured (N²).
  std::array<double, 4> sums_N2{};
  /// The flute's and the sector's Σ (dx² + dy²) (N²).
  std::array<double, 2> flute_sector_N2{};
};

/// Adds samples [first, last] to `s`: `measured(n)` points at sample n's row of at least four
/// doubles (fx, fy, fz, Fx² + Fy²), `model` at sample first's row of four (fx, fy, fz, any), the
/// next samples' rows after it.
template <typename Rows>
void add_residuals_scalar(const Rows& measured, const double* model, std::int64_t first,
                          std::int64_t last, ResidualSums& s) {
  // In locals: sums reached through a reference would be stored and reloaded at every sample,
  // the compiler unable to rule out that the rows alias them.
  double sx = s.sums_N2[0], sy = s.sums_N2[1], sz = s.sums_N2[2], sm = s.sums_N2[3];
  double sf = s.flute_sector_N2[0], ss = s.flute_sector_N2[1];
  for (std::int64_t n = first; n <= last; ++n, model += 4) {
    const double* v = measured(n);
    const double dx = v[0] - model[0];
    const double dy = v[1] - model[1];
    const double dz = v[2] - model[2];
    const double dx2 = dx * dx;
    const double dy2 = dy * dy;
    sx += dx2;
    sy += dy2;
    sz += dz * dz;
    sm += v[3];
    const double d_xy2 = dx2 + dy2;
    sf += d_xy2;
    ss += d_xy2;
  }
  s.sums_N2 = {sx, sy, sz, sm};
  s.flute_sector_N2 = {sf, ss};
}

#if defined(MILLWATCH_RESIDUAL_SUMS_AVX)
/// add_residuals_scalar() with a sample's row in one 256-bit register: d² on the three axes and
/// the measured Fx² + Fy² in the fourth lane, added to the four sums at once; dx² + dy² added to
/// the flute's and the sector's sums as one SSE pair.
template <typename Rows>
__attribute__((target("avx"))) void add_residuals_avx(const Rows measured, const double* model,
                                                      std::int64_t first, std::int64_t last,
                                                      ResidualSums& s) {
  __m256d sums = _mm256_loadu_pd(s.sums_N2.data());
  __m128d flute_sector = _mm_loadu_pd(s.flute_sector_N2.data());
  for (std::int64_t n = first; n <= last; ++n, model += 4) {
    const __m256d v = _mm256_loadu_pd(measured(n));
    const __m256d d = _mm256_sub_pd(v, _mm256_loadu_pd(model));
    const __m256d d2 = _mm256_mul_pd(d, d);
    sums = _mm256_add_pd(sums, _mm256_blend_pd(d2, v, 0x8));  // (dx², dy², dz², Fx² + Fy²)
    const __m128d xy = _mm256_castpd256_pd128(d2);
    const __m128d d_xy2 = _mm_add_sd(xy, _mm_unpackhi_pd(xy, xy));  // dx² + dy²
    flute_sector = _mm_add_pd(flute_sector, _mm_movedup_pd(d_xy2));
  }
  _mm256_storeu_pd(s.sums_N2.data(), sums);
  _mm_storeu_pd(s.flute_sector_N2.data(), flute_sector);
}
#endif

/// add_residuals_avx() where the CPU has AVX and `allow_avx` (the tests compare the two), else
/// add_residuals_scalar().
template <typename Rows>
void add_residuals(const Rows& measured, const double* model, std::int64_t first, std::int64_t last,
                   ResidualSums& s, bool allow_avx = true) {
#if defined(MILLWATCH_RESIDUAL_SUMS_AVX)
  if (allow_avx && signal::cpu_has_avx()) {
    add_residuals_avx(measured, model, first, last, s);
    return;
  }
#endif
  (void)allow_avx;
  add_residuals_scalar(measured, model, first, last, s);
}

}  // namespace millwatch::monitor
