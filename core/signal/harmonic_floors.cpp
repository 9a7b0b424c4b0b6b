#include "core/signal/harmonic_floors.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <utility>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "core/signal/order_statistic.hpp"

namespace millwatch::signal {
namespace {

/// The value at index k of A ∪ B sorted ascending (A and B sorted, k < |A| + |B|): the split
/// taking i from A and k + 1 − i from B with A[i] ≥ B[k − i], found by bisection.
double kth_of_two(std::span<const double> a, std::span<const double> b, std::size_t k) {
  std::size_t lo = k + 1 > b.size() ? k + 1 - b.size() : 0;
  std::size_t hi = std::min(k + 1, a.size());
  while (lo < hi) {
    const std::size_t i = (lo + hi) / 2;
    if (a[i] < b[k - i]) {  // b[k + 1 − i − 1]: more of A belongs below the split
      lo = i + 1;
    } else {
      hi = i;
    }
  }
  const std::size_t j = k + 1 - lo;
  constexpr double kNone = -std::numeric_limits<double>::infinity();
  return std::max(lo > 0 ? a[lo - 1] : kNone, j > 0 ? b[j - 1] : kNone);
}

/// How many of v[from, to) are below x (`or_equal`: or equal to it).
template <bool or_equal>
std::size_t count_below(const double* v, std::size_t from, std::size_t to, double x) {
  std::size_t count = 0;
  std::size_t j = from;
#if defined(__SSE2__)
  // Two at a time: a true comparison is all ones, −1 as an integer.
  const __m128d xx = _mm_set1_pd(x);
  __m128i minus = _mm_setzero_si128();
  for (; j + 2 <= to; j += 2) {
    const __m128d y = _mm_loadu_pd(v + j);
    minus = _mm_add_epi64(minus,
                          _mm_castpd_si128(or_equal ? _mm_cmple_pd(y, xx) : _mm_cmplt_pd(y, xx)));
  }
  alignas(16) std::int64_t lanes[2];
  _mm_store_si128(reinterpret_cast<__m128i*>(lanes), minus);
  count = static_cast<std::size_t>(-(lanes[0] + lanes[1]));
#endif
  for (; j < to; ++j) {
    count += (or_equal ? v[j] <= x : v[j] < x) ? 1 : 0;
  }
  return count;
}

/// The comparators of Batcher's odd–even merge sort of n (a power of two) values, in order,
/// from its merges of sorted runs of `first_run` values on (1: the whole sort; n/2: the last
/// merge alone, of two sorted halves): `out` (if given) receives them; returns their number.
constexpr std::size_t batcher_comparators(std::size_t n, std::size_t first_run,
                                          std::array<std::uint8_t, 2>* out) {
  std::size_t count = 0;
  for (std::size_t p = first_run; p < n; p += p) {
    for (std::size_t k = p; k > 0; k /= 2) {
      for (std::size_t j = k % p; j + k < n; j += 2 * k) {
        for (std::size_t i = 0; i < k && i < n - j - k; ++i) {
          if ((i + j) / (2 * p) == (i + j + k) / (2 * p)) {
            if (out != nullptr) {
              out[count] = {static_cast<std::uint8_t>(i + j), static_cast<std::uint8_t>(i + j + k)};
            }
            ++count;
          }
        }
      }
    }
  }
  return count;
}

template <std::size_t N, std::size_t FirstRun>
constexpr auto kBatcher = [] {
  std::array<std::array<std::uint8_t, 2>, batcher_comparators(N, FirstRun, nullptr)> pairs{};
  batcher_comparators(N, FirstRun, pairs.data());
  return pairs;
}();

/// Orders a ≤ b. On a tie each keeps its own value (a −0 beside a +0 stays one of each). Written
/// as std::min and std::max that way, the two selects share one comparison, which the compiler
/// turns into a branch (mispredicted half the time); minsd and maxsd need none.
inline void compare_exchange(double& a, double& b) {
#if defined(__SSE2__)
  const __m128d va = _mm_set_sd(a), vb = _mm_set_sd(b);
  a = _mm_cvtsd_f64(_mm_min_sd(vb, va));  // vb < va ? vb : va
  b = _mm_cvtsd_f64(_mm_max_sd(va, vb));  // va > vb ? va : vb
#else
  const double low = std::min(a, b), high = std::max(b, a);
  a = low;
  b = high;
#endif
}

/// Applies Batcher's comparators (N, FirstRun) to x, unrolled: `comparators` is
/// std::make_index_sequence<kBatcher<N, FirstRun>.size()>.
template <std::size_t N, std::size_t FirstRun, std::size_t... I>
void apply_network(std::array<double, N>& x, std::index_sequence<I...> /*comparators*/) {
  (compare_exchange(x[kBatcher<N, FirstRun>[I][0]], x[kBatcher<N, FirstRun>[I][1]]), ...);
}
template <std::size_t N, std::size_t FirstRun>
void apply_network(std::array<double, N>& x) {
  apply_network<N, FirstRun>(x, std::make_index_sequence<kBatcher<N, FirstRun>.size()>{});
}

/// Sorts v[0, n) (n ≤ N, a power of two) into out[0, n) by Batcher's network, padded with +∞:
/// a minimum and a maximum per comparator, unrolled, the values in registers — no branch to
/// mispredict and no value waiting on a count.
template <std::size_t N>
void sort_by_network(const double* v, std::size_t n, double* out) {
  std::array<double, N> x;
  for (std::size_t i = 0; i < N; ++i) {
    x[i] = i < n ? v[i] : std::numeric_limits<double>::infinity();
  }
  apply_network<N, 1>(x);
  std::copy_n(x.begin(), n, out);
}

/// Merges sorted a and b (each at most M values, M a power of two) into out by the last merge
/// of Batcher's network on 2M values, each run padded with +∞ to M.
template <std::size_t M>
void merge_by_network(std::span<const double> a, std::span<const double> b, double* out) {
  std::array<double, 2 * M> x;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < M; ++i) {
    x[i] = i < a.size() ? a[i] : kInf;
    x[M + i] = i < b.size() ? b[i] : kInf;
  }
  apply_network<2 * M, M>(x);
  std::copy_n(x.begin(), a.size() + b.size(), out);
}

/// Sorts v[0, n) into out[0, n). Runs of up to 16 bins (the tracker's at its default window:
/// ~13) by a sorting network; longer short runs (up to ~40) by rank: each value goes to the
/// number of values before it (smaller, or equal and earlier), counted without a branch, where
/// a comparison sort mispredicts about every other comparison. The same values in the same
/// order either way.
void sort_run(const double* v, std::size_t n, double* out) {
  constexpr std::size_t kRankSortMax = 48;
  if (n <= 8) {
    sort_by_network<8>(v, n, out);
    return;
  }
  if (n <= 16) {
    sort_by_network<16>(v, n, out);
    return;
  }
  if (n > kRankSortMax) {
    std::copy(v, v + n, out);
    std::sort(out, out + n);
    return;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const double x = v[i];
    out[count_below<true>(v, 0, i, x) + count_below<false>(v, i + 1, n, x)] = x;
  }
}

/// Merges sorted a and b into out: runs of up to 16 values each (the tracker's) by a merging
/// network; longer ones with a select per value instead of a branch, from both ends at once:
/// each end's next index waits on its last comparison, and two such chains overlap.
void merge_runs(std::span<const double> a, std::span<const double> b, double* out) {
  const std::size_t na = a.size(), nb = b.size(), n = na + nb;
  if (na <= 16 && nb <= 16 && n > 0) {
    merge_by_network<16>(a, b, out);
    return;
  }
  if (na == 0 || nb == 0) {
    std::copy(b.begin(), b.end(), std::copy(a.begin(), a.end(), out));
    return;
  }
  constexpr double kInf = std::numeric_limits<double>::infinity();
  // The next value from the front (kInf past the end) and from the back (−kInf before the start).
  const auto front = [](std::span<const double> v, std::size_t i) {
    const double x = v[std::min(i, v.size() - 1)];
    return i < v.size() ? x : kInf;
  };
  const auto back = [](std::span<const double> v, std::size_t left) {  // `left` not yet taken
    const double x = v[left > 0 ? left - 1 : 0];
    return left > 0 ? x : -kInf;
  };
  std::size_t i = 0, j = 0;              // taken from the front
  std::size_t a_left = na, b_left = nb;  // not yet taken from the back
  for (std::size_t o = 0; o < n / 2; ++o) {
    const double x = front(a, i), y = front(b, j);
    const bool take_b = y < x;
    out[o] = take_b ? y : x;
    i += take_b ? 0 : 1;
    j += take_b ? 1 : 0;
    const double u = back(a, a_left), w = back(b, b_left);
    const bool take_a = u > w;
    out[n - 1 - o] = take_a ? u : w;
    a_left -= take_a ? 1 : 0;
    b_left -= take_a ? 0 : 1;
  }
  if (n % 2 == 1) {
    out[n / 2] = std::min(front(a, i), front(b, j));
  }
}

}  // namespace

void HarmonicFloors::resize(std::size_t bins) {
  rank_.assign(bins + 1, 0);
  values_.assign(bins, 0.0);
  sorted_.assign(bins, 0.0);
  run_start_.assign(bins + 3, 0);
  runs_ = 0;
  pairs_.assign(2 * bins, 0.0);
  scratch_.assign(bins, 0.0);
  other_.assign(bins, 0.0);
}

void HarmonicFloors::prepare(std::span<const double> magnitude, double harmonic_bins,
                             double lobe_bins, std::size_t last_bin) {
  const double per_bin = 1.0 / harmonic_bins;
  // Bin c is a floor bin of run `whole` (between harmonics whole and whole + 1) when this holds.
  const auto floor_bin = [per_bin, harmonic_bins, lobe_bins](std::size_t c, std::int64_t& whole) {
    const double x = static_cast<double>(c) * per_bin;  // in harmonics
    // |x − round(x)|, exactly, without a call: the fraction or its complement to 1.
    whole = static_cast<std::int64_t>(x);
    const double fraction = x - static_cast<double>(whole);
    return std::min(fraction, 1.0 - fraction) * harmonic_bins > lobe_bins;
  };
  // Within a run, x grows with c and its fraction (exact) with it, so min(fraction, 1 − fraction)
  // rises and then falls: a run's floor bins are one stretch of bins, between its harmonics'
  // lobes, (j·H + L, (j + 1)·H − L). Each stretch's ends are found by testing the bins about
  // those bounds (a bin or two each), not every bin: the same bins as testing every one.
  std::size_t* const rank = rank_.data();
  std::size_t* const run_start = run_start_.data();
  double* const values = values_.data();
  std::size_t n = 0;     // floor bins so far
  std::size_t runs = 0;  // runs started
  std::size_t next = 0;  // the first bin whose rank is not written yet
  const auto last_run = static_cast<std::int64_t>(static_cast<double>(last_bin) * per_bin);
  const auto bin_near = [last_bin](double at) -> std::size_t {  // in [1, last_bin]; NaN: 1
    if (!(at > 1.0)) {
      return 1;
    }
    return at < static_cast<double>(last_bin) ? static_cast<std::size_t>(at) : last_bin;
  };
  for (std::int64_t j = 0; last_bin >= 1 && j <= last_run; ++j) {
    const auto jd = static_cast<double>(j);
    std::size_t lo = bin_near(jd * harmonic_bins + lobe_bins - 1.0);
    std::size_t hi = bin_near((jd + 1.0) * harmonic_bins - lobe_bins + 1.0);
    std::int64_t whole = 0;
    const auto in_run = [&](std::size_t c) { return floor_bin(c, whole) && whole == j; };
    while (lo <= hi && !in_run(lo)) {
      ++lo;
    }
    if (lo > hi) {
      continue;  // no floor bins between harmonics j and j + 1
    }
    while (hi > lo && !in_run(hi)) {
      --hi;
    }
    while (lo > 1 && in_run(lo - 1)) {  // the bounds' guesses are within a bin; never wider
      --lo;
    }
    while (hi < last_bin && in_run(hi + 1)) {
      ++hi;
    }
    while (runs <= static_cast<std::size_t>(j)) {  // runs up to this one start here
      run_start[runs++] = n;
    }
    for (; next <= lo; ++next) {
      rank[next] = n;
    }
    for (std::size_t c = lo; c <= hi; ++c) {
      rank[c] = n;
      values[n++] = magnitude[c];
    }
    next = hi + 1;
  }
  for (; next <= last_bin + 1; ++next) {
    rank[next] = n;
  }
  runs_ = runs;
  run_start[runs] = n;  // the end, and an empty run after the last
  run_start[runs + 1] = n;
  for (std::size_t j = 0; j < runs_; ++j) {
    sort_run(&values_[run_start_[j]], run_start_[j + 1] - run_start_[j], &sorted_[run_start_[j]]);
  }
  for (std::size_t j = 0; j < runs_; ++j) {
    merge_runs(run(j), run(j + 1), &pairs_[pair_offset(j)]);
  }
}

std::span<const double> HarmonicFloors::run(std::size_t j) const {
  return std::span(sorted_).subspan(run_start_[j], run_start_[j + 1] - run_start_[j]);
}

std::size_t HarmonicFloors::pair_offset(std::size_t j) const {
  // Pairs 0 … j − 1 come first: runs 0 … j − 1 and runs 1 … j.
  return run_start_[j] + (run_start_[j + 1] - run_start_[1]);
}

std::span<const double> HarmonicFloors::pair(std::size_t j) const {
  return std::span(pairs_).subspan(pair_offset(j), run_start_[j + 2] - run_start_[j]);
}

double HarmonicFloors::median(std::size_t from, std::size_t to) {
  const std::size_t a = rank_[from], b = rank_[to + 1];
  const std::size_t k = (b - a) / 2;
  const auto starts = run_start_.begin();
  const auto runs_end = starts + static_cast<std::ptrdiff_t>(runs_);
  // The runs the window's floor bins span, if it holds them whole: the last run to start at a
  // (the earlier ones starting there are empty) to the first to end at b.
  const auto first = std::upper_bound(starts, runs_end, a) - 1;
  if (*first == a) {
    const auto end = std::lower_bound(first + 1, runs_end + 1, b);
    if (*end == b) {
      const auto ja = static_cast<std::size_t>(first - starts);
      switch (end - first) {
        case 1:
          return run(ja)[k];
        case 2:
          return pair(ja)[k];
        case 3:
          return kth_of_two(pair(ja), run(ja + 2), k);
        case 4:
          return kth_of_two(pair(ja), pair(ja + 2), k);
        default:
          break;
      }
    }
  }
  std::copy(values_.begin() + static_cast<std::ptrdiff_t>(a),
            values_.begin() + static_cast<std::ptrdiff_t>(b), scratch_.begin());
  return kth_smallest(std::span(scratch_).first(b - a), k, other_);
}

}  // namespace millwatch::signal
