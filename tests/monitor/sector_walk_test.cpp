#include "core/monitor/sector_walk.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

namespace millwatch::monitor {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

/// The definition, sample by sample: a(s) = start + slope·(s − from) less the turns passed (a
/// turn passed once a(s) reaches 2π), its sector ⌊a·sectors/2π⌋ within [0, sectors).
std::vector<int> sectors_by_sample(double start_rad, double slope_rad, std::int64_t from,
                                   std::int64_t to, int sectors) {
  std::vector<int> out;
  double turns_rad = 0.0;
  for (std::int64_t s = from; s <= to; ++s) {
    double a = start_rad + slope_rad * static_cast<double>(s - from) - turns_rad;
    if (a >= kTwoPi) {
      turns_rad += kTwoPi;
      a -= kTwoPi;
    }
    out.push_back(std::clamp(static_cast<int>(a * (sectors / kTwoPi)), 0, sectors - 1));
  }
  return out;
}

/// Walks the line and checks its runs: they cover [from, to] in order, each sample in its run's
/// sector by the definition, and — on a line that reaches no second turn — each run the whole of
/// its sector within its turn (a new run only where the sector changes). Returns the runs.
int check_runs(double start_rad, double slope_rad, std::int64_t from, std::int64_t to,
               int sectors) {
  const std::vector<int> expected = sectors_by_sample(start_rad, slope_rad, from, to, sectors);
  const bool one_turn = start_rad + slope_rad * static_cast<double>(to - from) < 2.0 * kTwoPi;
  std::int64_t next = from;
  int last_sector = -1, runs = 0, turns = 0;
  SectorWalk(start_rad, slope_rad, from, sectors)
      .runs(to, [&](std::int64_t first, std::int64_t last, int sector) {
        EXPECT_EQ(first, next);
        EXPECT_LE(first, last);
        for (std::int64_t s = first; s <= last; ++s) {
          EXPECT_EQ(sector, expected[static_cast<std::size_t>(s - from)])
              << sectors << " sectors, sample " << s - from << " of " << to - from;
        }
        turns += sector <= last_sector ? 1 : 0;  // the sectors start again: a turn
        last_sector = sector;
        next = last + 1;
        ++runs;
      });
  EXPECT_EQ(next, to + 1);
  if (one_turn) {
    EXPECT_LE(turns, 1) << "a run split within a turn: start " << start_rad;
  }
  return runs;
}

// The runs cover the revolution's samples in order, each sample in its run's sector by the
// per-sample definition, and within a turn every run is the whole of its sector (a new run only
// where the sector changes): on lines of 60 to 1,200 samples a turn (50 to 333.3 kHz), a turn
// and a bit long, from any angle, in 1 to 36 sectors, and from a sector's edge, also with whole
// samples a sector (each edge's sample then decided by rounding).
TEST(SectorWalk, RunsAreTheSectorsOfEachSampleAndWholeWithinATurn) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  int lines = 0;
  for (const int sectors : {1, 5, 7, 12, 36}) {
    for (int trial = 0; trial < 400; ++trial) {
      double per_turn = 60.0 + 1140.0 * uniform(rng);
      if (trial % 4 == 2) {  // whole samples a sector: edges on samples, up to rounding
        per_turn = sectors * std::ceil(per_turn / sectors);
      }
      const double slope_rad = kTwoPi / per_turn;
      double start_rad = kTwoPi * uniform(rng);
      if (trial % 4 == 1 || trial % 4 == 2) {  // on a sector's edge
        start_rad = kTwoPi * std::floor(sectors * uniform(rng)) / sectors;
      }
      const std::int64_t from = 1000 + trial;
      const auto to = from + static_cast<std::int64_t>(per_turn * (1.0 + 0.1 * uniform(rng)));
      check_runs(start_rad, slope_rad, from, to, sectors);
      ++lines;
    }
  }
  EXPECT_EQ(lines, 2000);
}

// Lines with fewer samples a turn than sectors (sectors no sample falls in), lines starting on
// the turn (the first turn's part empty) or just before it, and lines into a second turn (walked
// sample by sample): the same checks.
TEST(SectorWalk, SparseLinesTurnsAtTheStartAndSecondTurns) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (int trial = 0; trial < 300; ++trial) {
    const double per_turn = 5.0 + 30.0 * uniform(rng);  // 36 sectors: some empty
    const auto to = 50 + static_cast<std::int64_t>(per_turn * 1.05);
    check_runs(kTwoPi * uniform(rng), kTwoPi / per_turn, 50, to, 36);
  }
  for (const double start_rad : {kTwoPi, std::nextafter(kTwoPi, 0.0), kTwoPi - 1e-9}) {
    for (const int sectors : {1, 12, 36}) {
      check_runs(start_rad, kTwoPi / 250.0, 0, 260, sectors);
    }
  }
  // 2.5 turns: into a second turn, sample by sample, each in its sector.
  EXPECT_EQ(check_runs(1.0, kTwoPi / 100.0, 0, 250, 12), 251);
}

// Where the angle does not advance (a slope of zero), every sample is its own run, in the
// start's sector.
TEST(SectorWalk, AStandingAngleIsWalkedSampleBySample) {
  std::vector<std::int64_t> firsts;
  SectorWalk(1.0, 0.0, 5, 12).runs(9, [&](std::int64_t first, std::int64_t last, int sector) {
    EXPECT_EQ(first, last);
    EXPECT_EQ(sector, 1);  // 1 rad: the second of twelve 30° sectors
    firsts.push_back(first);
  });
  EXPECT_EQ(firsts, (std::vector<std::int64_t>{5, 6, 7, 8, 9}));
}

}  // namespace
}  // namespace millwatch::monitor
