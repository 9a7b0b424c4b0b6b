#include "core/signal/order_statistic.hpp"

#include <algorithm>
#include <utility>

namespace millwatch::signal {
namespace {

constexpr std::size_t kSmall = 8;  // ranges this short are sorted outright (a short sort
                                   // mispredicts more than a branch-free partition costs)

/// Copies from[0, n) to to[0, n), those for which `left(x)` holds first (in order), the others
/// after them (in reverse order). Both ends are written every time; the end that does not move
/// is written over later. Returns the number of left elements.
template <typename Left>
std::size_t partition(const double* from, double* to, std::size_t n, Left left) {
  std::size_t front = 0, back = n - 1;
  for (std::size_t i = 0; i < n; ++i) {
    const double x = from[i];
    const std::size_t is_left = left(x) ? 1 : 0;
    to[front] = x;
    to[back] = x;
    front += is_left;
    back -= 1 - is_left;
  }
  return front;
}

}  // namespace

double kth_smallest(std::span<double> values, std::size_t k, std::span<double> scratch) {
  double* v = values.data();
  double* other = scratch.data();
  std::size_t n = values.size();
  while (n > kSmall) {
    const double a = v[0], b = v[n / 2], c = v[n - 1];
    const double pivot = std::max(std::min(a, b), std::min(std::max(a, b), c));  // median of 3
    std::size_t split = partition(v, other, n, [pivot](double x) { return x < pivot; });
    if (split == 0) {
      // Nothing below the pivot (the smallest of the range): its copies go left.
      split = partition(v, other, n, [pivot](double x) { return x <= pivot; });
      if (k < split || split == 0) {
        // Among the copies of the smallest value; or (none, the pivot itself not ≤ itself) a
        // NaN, outside the contract: it is the answer rather than a range that never shrinks.
        return pivot;
      }
    }
    std::swap(v, other);  // the partitioned range is in the other buffer now
    if (k < split) {
      n = split;
    } else {
      v += split;
      other += split;
      k -= split;
      n -= split;
    }
  }
  std::sort(v, v + n);
  return v[k];
}

}  // namespace millwatch::signal
