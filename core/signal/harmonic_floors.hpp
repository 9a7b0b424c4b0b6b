#pragma once
// The noise floors around the harmonics of a spectrum, as the spindle tracker measures them: the
// median magnitude of the "floor" bins (those outside every harmonic's main lobe) within a
// window of bins around each harmonic. The floor bins between harmonics j and j + 1 form run j;
// a harmonic's window (± two spindle frequencies) holds runs h − 2 … h + 1 whole, so each run is
// sorted once, neighbouring runs are merged in pairs, and a window's median is the k-th of two
// sorted pairs (a binary search): where gathering each window and selecting its median cost
// each hop ~4 passes over a window's bins per harmonic. A window that does not hold whole runs
// (or more than four) takes the gathering way. The same medians, exactly. Allocates nothing
// after resize(); NaN-free input.

#include <cstddef>
#include <span>
#include <vector>

namespace millwatch::signal {

class HarmonicFloors {
 public:
  /// Room for spectra of up to `bins` bins.
  void resize(std::size_t bins);

  /// Marks bins 1 … last_bin of `magnitude` (last_bin < magnitude.size() ≤ the resize()d bins):
  /// bin c is a floor bin when its distance to the nearest multiple of `harmonic_bins` exceeds
  /// `lobe_bins`. Sorts the runs and merges their pairs.
  void prepare(std::span<const double> magnitude, double harmonic_bins, double lobe_bins,
               std::size_t last_bin);

  /// Whether bin c (1 … last_bin) is a floor bin.
  [[nodiscard]] bool is_floor(std::size_t c) const { return rank_[c + 1] > rank_[c]; }
  /// The number of floor bins in [from, to] (1 ≤ from, to ≤ last_bin).
  [[nodiscard]] std::size_t count(std::size_t from, std::size_t to) const {
    return to < from ? 0 : rank_[to + 1] - rank_[from];
  }
  /// The value at index count/2 of the floor bins in [from, to] sorted ascending (the tracker's
  /// median); count(from, to) > 0.
  [[nodiscard]] double median(std::size_t from, std::size_t to);

 private:
  [[nodiscard]] std::span<const double> run(std::size_t j) const;
  [[nodiscard]] std::span<const double> pair(std::size_t j) const;
  [[nodiscard]] std::size_t pair_offset(std::size_t j) const;

  std::vector<std::size_t> rank_;       // [c]: floor bins below bin c (c = 0 … last_bin + 1)
  std::vector<double> values_;          // the floor bins' magnitudes, in bin order
  std::vector<double> sorted_;          // the same, each run sorted
  std::vector<std::size_t> run_start_;  // [j]: index of run j's first floor bin; one past the end
  std::size_t runs_ = 0;
  std::vector<double> pairs_;    // runs j and j + 1 merged, for every j, one after the other
  std::vector<double> scratch_;  // the gathering way's two buffers
  std::vector<double> other_;
};

}  // namespace millwatch::signal
