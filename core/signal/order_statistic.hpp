#pragma once
// The k-th smallest of a set of numbers, as std::nth_element finds it, without its branches: a
// quickselect whose partition is branch-free and out of place (each element is written to the
// front or the back of a second buffer, a comparison deciding which end moves), so that data
// in no particular order costs no mispredictions and no store waits on the previous one. On the
// few hundred noise-floor magnitudes the spindle tracker takes the median of, several times
// faster. Allocates nothing; NaN-free input.

#include <cstddef>
#include <span>

namespace millwatch::signal {

/// The value that would stand at index k (< values.size()) if `values` were sorted ascending.
/// `values` and `scratch` (at least as long) are reordered. With a NaN among them (outside the
/// contract) it still returns, some value of the set or a NaN.
double kth_smallest(std::span<double> values, std::size_t k, std::span<double> scratch);

}  // namespace millwatch::signal
