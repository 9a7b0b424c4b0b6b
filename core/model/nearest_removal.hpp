#pragma once
// The rigid chip's nearest removal, for one pass of the steady-state evaluator
// (SteadyStateWorkspace::Impl::run_pass): the chip a flute meets is the least, over the last P
// passes, of its geometric chip to that pass plus what that pass left (its deficit) — [000]
// eq 19's minimum over the earlier passes, with [002] eqs 11–12's passes that removed nothing
// (accumulation below the minimum chip) left out.

#include <algorithm>
#include <array>
#include <limits>
#include <utility>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace millwatch::model {

/// A deficit of a pass that removed nothing.
inline constexpr double kNoRemoval = std::numeric_limits<double>::infinity();

/// Both arrays run over the last P passes, the oldest first (index P − n holds pass n back):
/// the minimum over them of g + deficit, a pass that removed nothing (deficit kNoRemoval) or a
/// NaN sum never taken, and its n, the nearest of equal ones; (kNoRemoval, 0) when no pass
/// removed anything. The same as one sweep from the nearest pass keeping the first of equal
/// ones, computed as the minimum first, in four lanes without a branch over arrays read
/// forwards (one sweep's chain of compares and mispredicted branches had been most of a pass's
/// time with 32 passes looked back), then the nearest pass that reaches it.
inline std::pair<double, int> nearest_removal(const double* g, const double* deficit, int passes) {
  // g + kNoRemoval is kNoRemoval, never below another. A minimum is exact in any order.
  std::array<double, 4> lane{kNoRemoval, kNoRemoval, kNoRemoval, kNoRemoval};
  int m = 0;
#if defined(__SSE2__)
  __m128d low = _mm_set1_pd(kNoRemoval);
  __m128d high = low;
  for (; m + 3 < passes; m += 4) {
    // minpd(sum, lane): a NaN sum leaves the lane, as the sweep's c < h skipped it.
    low = _mm_min_pd(_mm_add_pd(_mm_loadu_pd(g + m), _mm_loadu_pd(deficit + m)), low);
    high = _mm_min_pd(_mm_add_pd(_mm_loadu_pd(g + m + 2), _mm_loadu_pd(deficit + m + 2)), high);
  }
  _mm_storeu_pd(&lane[0], low);
  _mm_storeu_pd(&lane[2], high);
#endif
  for (; m + 3 < passes; m += 4) {
    for (int l = 0; l < 4; ++l) {
      const auto ul = static_cast<std::size_t>(l);
      lane[ul] = std::min(lane[ul], g[m + l] + deficit[m + l]);
    }
  }
  for (; m < passes; ++m) {
    lane[0] = std::min(lane[0], g[m] + deficit[m]);
  }
  const double h = std::min(std::min(lane[0], lane[1]), std::min(lane[2], lane[3]));
  if (h == kNoRemoval) {
    return {kNoRemoval, 0};
  }
  for (m = passes - 1; m > 0 && g[m] + deficit[m] != h; --m) {
  }
  return {h, passes - m};
}

}  // namespace millwatch::model
