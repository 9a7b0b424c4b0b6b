#pragma once
// A line of positions on a cyclic grid of `grid` points: sample i at start + step·i, for a
// spindle's line (0 ≤ step < grid: forwards, less than a turn a sample). The position advances
// by a step and is wrapped once a turn, instead of a division and a floor per sample; at() must
// be called for i = 0, 1, 2, … in order. The synchronous average's bins and the lockstep model's
// table walk it.
//
// grid_chunk_avx() gives the same positions' grid points and fractions four samples at a time,
// a chunk ahead of the loop that uses them: at() one sample at a time was a third of the
// synchronous average's time (conversions and a compare a sample, none in parallel).

#include <array>
#include <cstddef>
#include <cstdint>

#if defined(__SSE2__) && defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#define MILLWATCH_GRID_LINE_AVX 1
#include <immintrin.h>
#endif

namespace millwatch::monitor {

class GridLine {
 public:
  /// @param start_points the first sample's position, already in [0, grid]
  GridLine(double start_points, double step_points, double grid_points)
      : grid_(grid_points), start_(start_points), step_(step_points) {}

  /// Sample i's position in [0, grid].
  double at(std::int64_t i) {
    double pos = start_ + step_ * static_cast<double>(i) - wrapped_;
    if (pos >= grid_) {
      wrapped_ += grid_;
      pos -= grid_;
    }
    return pos;
  }

  [[nodiscard]] double start_points() const { return start_; }
  [[nodiscard]] double step_points() const { return step_; }
  [[nodiscard]] double grid_points() const { return grid_; }

 private:
  double grid_;
  double start_;
  double step_;
  double wrapped_ = 0.0;  // whole turns of the grid passed, in grid points
};

/// Samples a chunk holds (a multiple of four).
inline constexpr std::size_t kGridChunk = 64;

/// A chunk of a line's samples: each one's grid point, min(⌊pos⌋, last point), and its
/// fraction pos − point.
/// Not zeroed (a chunk is written before it is read): zeroing its 768 bytes at every line would
/// cost as much as the positions of a few dozen samples.
struct GridChunk {
  alignas(32) std::array<double, kGridChunk> fraction;
  alignas(16) std::array<std::int32_t, kGridChunk> point;
};

#if defined(MILLWATCH_GRID_LINE_AVX)
/// Samples [from, from + n) of `line` (n ≤ kGridChunk; the last group of four is computed
/// whole) into `out`, sample from + j at j: the positions at() gives, bit for bit, for a line of
/// integer grid points whose positions stay below 2⁵³. at() subtracts the grid once each time a
/// position passes it, so sample i's is start + step·i less m·grid, the m that puts it in
/// [0, grid); here m comes from a division (a floor, checked both ways) — the same difference,
/// exactly: m·grid is an integer, as is every multiple of the position's last bit there.
/// `last_point` < 2³¹. For a spindle's line, whose step lies below the grid by more than a
/// position's rounding (at() wraps once a sample: a step within a rounding of the grid can leave
/// its position at or past the grid, where this one wraps it again).
__attribute__((target("avx"))) inline void grid_chunk_avx(const GridLine& line, std::size_t from,
                                                          std::size_t n, std::int32_t last_point,
                                                          GridChunk& out) {
  const __m256d start = _mm256_set1_pd(line.start_points());
  const __m256d step = _mm256_set1_pd(line.step_points());
  const __m256d grid = _mm256_set1_pd(line.grid_points());
  const __m256d per_grid = _mm256_set1_pd(1.0 / line.grid_points());
  const __m256d last = _mm256_set1_pd(static_cast<double>(last_point));
  const __m256d zero = _mm256_setzero_pd();
  const __m256d four = _mm256_set1_pd(4.0);
  const auto first = static_cast<double>(from);
  __m256d i = _mm256_set_pd(first + 3.0, first + 2.0, first + 1.0, first);
  for (std::size_t j = 0; j < n; j += 4) {
    const __m256d raw = _mm256_add_pd(start, _mm256_mul_pd(step, i));
    const __m256d turns = _mm256_floor_pd(_mm256_mul_pd(raw, per_grid));
    __m256d pos = _mm256_sub_pd(raw, _mm256_mul_pd(grid, turns));
    // pos + (pos < 0 ? grid : 0), pos − (pos ≥ grid ? grid : 0): adding a zero changes no
    // position (a −0 becomes +0, whose point and fraction are the same). Not blendv: GCC 12
    // lowers a blend of a compare's mask to a branch per lane, here 8 a chunk of four samples
    // (the 333.3 kHz average took 13.3 % of the pipeline's profile with them, 11.1 % without).
    pos = _mm256_add_pd(pos, _mm256_and_pd(_mm256_cmp_pd(pos, zero, _CMP_LT_OQ), grid));
    pos = _mm256_sub_pd(pos, _mm256_and_pd(_mm256_cmp_pd(pos, grid, _CMP_GE_OQ), grid));
    const __m256d point =
        _mm256_min_pd(_mm256_round_pd(pos, _MM_FROUND_TO_ZERO | _MM_FROUND_NO_EXC), last);
    _mm_store_si128(reinterpret_cast<__m128i*>(&out.point[j]), _mm256_cvttpd_epi32(point));
    _mm256_store_pd(&out.fraction[j], _mm256_sub_pd(pos, point));
    i = _mm256_add_pd(i, four);
  }
}
#endif

}  // namespace millwatch::monitor
