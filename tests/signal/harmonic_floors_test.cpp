#include "core/signal/harmonic_floors.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

namespace millwatch::signal {
namespace {

/// The definition, independently: bin c is a floor bin when it lies more than `lobe` bins from
/// every multiple of `harmonic_bins`.
bool floor_bin(std::size_t c, double harmonic_bins, double lobe) {
  const double x = static_cast<double>(c) / harmonic_bins;
  return std::fabs(x - std::round(x)) * harmonic_bins > lobe;
}

/// The floor bins of [from, to], sorted: their count and the value at index count/2.
std::pair<std::size_t, double> brute_median(const std::vector<double>& magnitude, std::size_t from,
                                            std::size_t to, double harmonic_bins, double lobe) {
  std::vector<double> v;
  for (std::size_t c = from; c <= to; ++c) {
    if (floor_bin(c, harmonic_bins, lobe)) {
      v.push_back(magnitude[c]);
    }
  }
  std::sort(v.begin(), v.end());
  return {v.size(), v.empty() ? 0.0 : v[v.size() / 2]};
}

/// A tracker's spectrum: noise with a long tail, lines at the harmonics, and sometimes many
/// copies of a few values (quantised input) so that ties are exercised.
std::vector<double> spectrum(std::mt19937_64& rng, std::size_t bins, double harmonic_bins,
                             bool ties) {
  std::exponential_distribution<double> noise(1.0);
  std::vector<double> m(bins);
  for (std::size_t c = 0; c < bins; ++c) {
    m[c] = ties ? std::floor(3.0 * noise(rng)) : noise(rng);
    const double x = static_cast<double>(c) / harmonic_bins;
    if (std::fabs(x - std::round(x)) * harmonic_bins < 2.0) {
      m[c] += 50.0;
    }
  }
  return m;
}

// The floor bins are found a run at a time from the lobes' bounds (a few bins tested about each),
// not bin by bin: the same bins as testing every one, where a bin lies exactly on a lobe's edge
// too (whole spacings and lobes: c = j·H + L), with narrow runs, lobes of half the spacing and
// more (no floor bins), spacings below a bin's width of lobe, and a last bin anywhere. The
// definition here is the tracker's own form of it (x = c·(1/H), as prepare() tests a bin).
TEST(HarmonicFloors, FloorBinsAreThoseOfTheDefinitionAtTheLobesEdges) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  HarmonicFloors floors;
  const std::size_t bins = 1025;
  const std::vector<double> m = spectrum(rng, bins, 10.0, false);
  floors.resize(bins);
  int cases = 0, floor_bins = 0, on_edges = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    const bool whole = trial % 2 == 0;
    const double harmonic_bins =
        whole ? static_cast<double>(2 + trial % 60) : 1.5 + 90.0 * uniform(rng);
    const double lobe = whole ? static_cast<double>(1 + (trial / 2) % 12)
                              : (trial % 5 == 1 ? 0.5 * harmonic_bins : 0.5 + 12.0 * uniform(rng));
    const std::size_t last_bin = 1 + static_cast<std::size_t>(uniform(rng) * (bins - 2));
    floors.prepare(m, harmonic_bins, lobe, last_bin);
    const double per_bin = 1.0 / harmonic_bins;
    std::size_t count = 0;
    for (std::size_t c = 1; c <= last_bin; ++c) {
      const double x = static_cast<double>(c) * per_bin;
      const double fraction = x - std::floor(x);
      const double distance = std::min(fraction, 1.0 - fraction) * harmonic_bins;
      const bool expected = distance > lobe;
      ASSERT_EQ(floors.is_floor(c), expected)
          << "bin " << c << ", spacing " << harmonic_bins << ", lobe " << lobe;
      count += expected ? 1 : 0;
      on_edges += distance == lobe ? 1 : 0;
    }
    ASSERT_EQ(floors.count(1, last_bin), count);
    floor_bins += static_cast<int>(count);
    ++cases;
  }
  EXPECT_EQ(cases, 4000);
  EXPECT_GT(floor_bins, 100000);
  EXPECT_GT(on_edges, 1000);  // bins exactly a lobe from a harmonic: not floor bins
}

TEST(HarmonicFloors, MediansAreThoseOfTheFloorBinsInEveryWindow) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  HarmonicFloors floors;
  int whole_runs = 0, checked = 0, short_runs = 0;
  for (int trial = 0; trial < 300; ++trial) {
    // Spectra of 129 to 2049 bins, 7 to 90 bins between harmonics, lobes of 4 to 9 bins (the
    // tracker's: 2·(padded size)/window + 1), some wider than half the spacing (no floor bins).
    const std::size_t bins = (std::size_t{64} << (trial % 6)) + 1;
    const double harmonic_bins = 7.0 + 83.0 * uniform(rng);
    const double lobe = 4.0 + 5.0 * uniform(rng);
    const std::vector<double> m = spectrum(rng, bins, harmonic_bins, trial % 3 == 0);
    // Runs of at most 16 floor bins (sorted and merged by networks) and longer ones.
    const double run_bins = harmonic_bins - 2.0 * lobe;  // about: floor bins between harmonics
    short_runs += run_bins > 1.0 && run_bins <= 16.0 ? 1 : 0;
    const std::size_t last_bin = bins - 1 - static_cast<std::size_t>(uniform(rng) * bins / 4);
    floors.resize(bins);
    floors.prepare(m, harmonic_bins, lobe, last_bin);
    for (std::size_t c = 1; c <= last_bin; ++c) {
      ASSERT_EQ(floors.is_floor(c), floor_bin(c, harmonic_bins, lobe)) << "bin " << c;
    }
    // The tracker's windows (± two spacings around each harmonic, clipped), then random ones.
    const auto reach = static_cast<std::size_t>(2.0 * harmonic_bins);
    std::vector<std::pair<std::size_t, std::size_t>> windows;
    for (int h = 1; h * harmonic_bins < static_cast<double>(last_bin); ++h) {
      const auto center = static_cast<std::size_t>(std::lround(h * harmonic_bins));
      windows.emplace_back(center > reach + 1 ? center - reach : 1,
                           std::min(center + reach, last_bin));
    }
    // Windows of exactly one to five whole runs (the floor bins between harmonics j and j + 1
    // are run j): each of the merged runs' ways.
    for (int j = 0; (j + 1) * harmonic_bins < static_cast<double>(last_bin); ++j) {
      for (int runs = 1; runs <= 5; ++runs) {
        const auto from = std::max<std::size_t>(1, static_cast<std::size_t>(j * harmonic_bins));
        const auto to = static_cast<std::size_t>((j + runs) * harmonic_bins);
        windows.emplace_back(from, std::min(to, last_bin));
      }
    }
    for (int r = 0; r < 20; ++r) {
      const auto a = 1 + static_cast<std::size_t>(uniform(rng) * static_cast<double>(last_bin));
      const auto b = 1 + static_cast<std::size_t>(uniform(rng) * static_cast<double>(last_bin));
      windows.emplace_back(std::min({a, b, last_bin}), std::min(std::max(a, b), last_bin));
    }
    for (const auto& [from, to] : windows) {
      const auto [count, median] = brute_median(m, from, to, harmonic_bins, lobe);
      ASSERT_EQ(floors.count(from, to), count) << "[" << from << ", " << to << "]";
      if (count > 0) {
        ASSERT_EQ(floors.median(from, to), median)
            << "[" << from << ", " << to << "] of " << bins << " bins, spacing " << harmonic_bins
            << ", lobe " << lobe;
        ++checked;
        whole_runs += to - from + 1 >= 3 * harmonic_bins ? 1 : 0;
      }
    }
  }
  EXPECT_GT(checked, 5000);
  EXPECT_GT(whole_runs, 1000);  // the merged runs' way, not only the gathering one
  EXPECT_GT(short_runs, 30);
  EXPECT_LT(short_runs, 270);
}

}  // namespace
}  // namespace millwatch::signal
