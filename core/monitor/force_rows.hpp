#pragma once
// The pipeline's rows of filtered force, as its sample ring holds them: fx, fy, fz and the
// in-plane square fx² + fy² (what the valley search, the extremes and the residuals read) side
// by side, from the three channels' arrays.

#include <cstddef>

#include "core/signal/cpu_features.hpp"

#if defined(__SSE2__) && defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#define MILLWATCH_FORCE_ROWS_AVX 1
#include <immintrin.h>
#endif

namespace millwatch::monitor {

/// Rows of `count` samples: sample i from fx[i·stride], fy[i·stride], fz[i·stride] into
/// rows[4i], …, rows[4i + 3].
inline void force_rows_scalar(const double* fx, const double* fy, const double* fz,
                              std::size_t stride, std::size_t count, double* rows) {
  for (std::size_t i = 0; i < count; ++i, rows += 4) {
    const std::size_t j = i * stride;
    rows[0] = fx[j];
    rows[1] = fy[j];
    rows[2] = fz[j];
    rows[3] = fx[j] * fx[j] + fy[j] * fy[j];
  }
}

#if defined(MILLWATCH_FORCE_ROWS_AVX)
/// force_rows_scalar() for consecutive samples (stride 1), four at a time: four samples of
/// each channel and their squares, transposed into four rows. The same products and sum on
/// each lane, so the same rows, bit for bit.
__attribute__((target("avx"))) inline void force_rows_avx(const double* fx, const double* fy,
                                                          const double* fz, std::size_t count,
                                                          double* rows) {
  std::size_t i = 0;
  for (; i + 4 <= count; i += 4) {
    const __m256d x = _mm256_loadu_pd(fx + i);
    const __m256d y = _mm256_loadu_pd(fy + i);
    const __m256d z = _mm256_loadu_pd(fz + i);
    const __m256d s = _mm256_add_pd(_mm256_mul_pd(x, x), _mm256_mul_pd(y, y));
    const __m256d xy_even = _mm256_unpacklo_pd(x, y);  // x0 y0 x2 y2
    const __m256d xy_odd = _mm256_unpackhi_pd(x, y);   // x1 y1 x3 y3
    const __m256d zs_even = _mm256_unpacklo_pd(z, s);  // z0 s0 z2 s2
    const __m256d zs_odd = _mm256_unpackhi_pd(z, s);   // z1 s1 z3 s3
    double* r = rows + 4 * i;
    _mm256_storeu_pd(r, _mm256_permute2f128_pd(xy_even, zs_even, 0x20));
    _mm256_storeu_pd(r + 4, _mm256_permute2f128_pd(xy_odd, zs_odd, 0x20));
    _mm256_storeu_pd(r + 8, _mm256_permute2f128_pd(xy_even, zs_even, 0x31));
    _mm256_storeu_pd(r + 12, _mm256_permute2f128_pd(xy_odd, zs_odd, 0x31));
  }
  force_rows_scalar(fx + i, fy + i, fz + i, 1, count - i, rows + 4 * i);
}
#endif

/// force_rows_avx() for consecutive samples where the CPU has AVX (and `allow_avx`: the tests
/// compare the two), else force_rows_scalar().
inline void force_rows(const double* fx, const double* fy, const double* fz, std::size_t stride,
                       std::size_t count, double* rows, bool allow_avx = true) {
#if defined(MILLWATCH_FORCE_ROWS_AVX)
  if (stride == 1 && allow_avx && signal::cpu_has_avx()) {
    force_rows_avx(fx, fy, fz, count, rows);
    return;
  }
#endif
  (void)allow_avx;
  force_rows_scalar(fx, fy, fz, stride, count, rows);
}

}  // namespace millwatch::monitor
