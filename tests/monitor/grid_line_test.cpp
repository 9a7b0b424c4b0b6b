#include "core/monitor/grid_line.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

#include "core/signal/cpu_features.hpp"

namespace millwatch::monitor {
namespace {

// grid_chunk_avx() gives, four samples at a time, each sample's grid point and fraction from
// the position GridLine::at() gives walking the line sample by sample, bit for bit: on the
// synchronous average's grid and the lockstep table's, lines from every kind of start (0, the
// grid itself, just below it, anywhere), steps from none to nearly a turn, over many turns,
// chunk after chunk and a last chunk cut short.
TEST(GridLine, ChunksOfFourAreThePositionsWalkedSampleBySample) {
#if defined(MILLWATCH_GRID_LINE_AVX)
  if (!signal::cpu_has_avx()) {
    GTEST_SKIP() << "this CPU has no AVX: grid_chunk_avx() does not run here";
  }
  const auto bits = [](double x) { return std::bit_cast<std::uint64_t>(x); };
  int compared = 0;
  for (const double grid : {256.0, 720.0, 7.0}) {
    const double below = std::nextafter(grid, 0.0);
    for (const double start : {0.0, grid, below, 0.37 * grid, 1e-300}) {
      for (const double step : {0.0, 1e-9, 0.2752, 1.0, 2.15, 0.5 * grid + 0.3, below - 1.0}) {
        for (const std::size_t count : {std::size_t{1}, std::size_t{63}, std::size_t{3001}}) {
          GridLine walked(start, step, grid);
          const GridLine line(start, step, grid);
          const auto last = static_cast<std::int32_t>(grid) - 1;
          GridChunk chunk;
          for (std::size_t from = 0; from < count; from += kGridChunk) {
            const std::size_t n = std::min(kGridChunk, count - from);
            grid_chunk_avx(line, from, n, last, chunk);
            for (std::size_t j = 0; j < n; ++j) {
              const double pos = walked.at(static_cast<std::int64_t>(from + j));
              const int point = std::min(static_cast<int>(pos), static_cast<int>(last));
              ASSERT_EQ(chunk.point[j], point) << grid << " " << start << " " << step << " at "
                                               << from + j << ": position " << pos;
              ASSERT_EQ(bits(chunk.fraction[j]), bits(pos - point))
                  << grid << " " << start << " " << step << " at " << from + j;
              ++compared;
            }
          }
        }
      }
    }
  }
  EXPECT_EQ(compared, 3 * 5 * 7 * (1 + 63 + 3001));
#else
  GTEST_SKIP() << "not an x86 build: grid_chunk_avx() is not compiled";
#endif
}

}  // namespace
}  // namespace millwatch::monitor
