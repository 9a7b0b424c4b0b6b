#pragma once
// Revolution-synchronous average: the filtered force of the last W revolutions on a uniform
// spindle-angle grid (bin k at 2πk/B from the tracker's angle zero). Each sample is shared
// between its two neighbouring bins in proportion to its angle, so a grid finer than the
// samples of one revolution still fills in over several revolutions.
//
// SyncAverageOf<C> averages C channels. The pipeline's is SyncAverage (fx, fy, fz); the tooth
// events' template at a lock also averages the in-plane resultant √(fx² + fy²), in an average
// of its own on the same grid and window (SyncAverageOf<1>). A bin holds its C sums and their
// weight side by side: four doubles for the pipeline's, one 32-byte row.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace millwatch::monitor {

template <int Channels>
class SyncAverageOf {
 public:
  static constexpr int kChannels = Channels;
  using Values = std::array<double, static_cast<std::size_t>(Channels)>;

  SyncAverageOf() = default;
  SyncAverageOf(int bins, int window_revolutions)
      : bins_(bins), bins_per_rad_(bins / (2.0 * std::numbers::pi)), window_(window_revolutions) {
    // window_ closed revolutions and the one being filled.
    sums_.assign(static_cast<std::size_t>(window_ + 1) * kRow * static_cast<std::size_t>(bins_),
                 0.0);
    totals_.assign(kRow * static_cast<std::size_t>(bins_), 0.0);
  }

  /// Adds one sample at spindle angle `angle_rad` (any real; taken modulo 2π) to the current
  /// revolution.
  void add(double angle_rad, const Values& values) {
    const double pos = angle_rad * bins_per_rad_;
    const double whole = std::floor(pos);
    int k = static_cast<int>(whole);
    if (k >= bins_ || k < 0) {
      k %= bins_;
      k += k < 0 ? bins_ : 0;
    }
    add_to(k, pos - whole, values);
  }
  /// Adds `count` samples to the current revolution on a line of positions: sample i at bin
  /// position first_bin + i·bins_per_sample (any real, taken modulo bins()) with values(i)
  /// (Values): the same sums as add() sample by sample. The position advances by a step,
  /// wrapped once a turn, instead of an angle wrapped per sample. Samples sparser than the bins
  /// (each in bins of its own: 50 kHz) go straight to their two bins; denser ones (a run sharing
  /// two bins: 333.3 kHz) are summed in registers until the run moves on (adding to memory one
  /// sample after the other would wait on each store).
  template <typename ValuesOf>
  void add_line(std::size_t count, double first_bin, double bins_per_sample,
                const ValuesOf& values) {
    const auto grid = static_cast<double>(bins_);
    if (!(bins_per_sample >= 0.0 && bins_per_sample < grid)) {  // not a spindle's line: any
      for (std::size_t i = 0; i < count; ++i) {
        const double pos = first_bin + bins_per_sample * static_cast<double>(i);
        add_at(pos - grid * std::floor(pos / grid), values(i));
      }
      return;
    }
    const double start = first_bin - grid * std::floor(first_bin / grid);  // [0, bins]
    double wrapped = 0.0;  // whole turns of the grid passed, in bins
    const auto position = [&](std::size_t i) {
      double pos = start + bins_per_sample * static_cast<double>(i) - wrapped;
      if (pos >= grid) {
        wrapped += grid;
        pos -= grid;
      }
      return pos;
    };
    if (bins_per_sample >= 1.0) {
      for (std::size_t i = 0; i < count; ++i) {
        add_at(position(i), values(i));
      }
      return;
    }
#if defined(__SSE2__)
    if constexpr (Channels == 3) {
      add_dense_sse2(count, position, values);
      return;
    }
#endif
    int k0 = -1;
    Row lo{}, hi{};
    for (std::size_t i = 0; i < count; ++i) {
      const double pos = position(i);
      const int k = std::min(static_cast<int>(pos), bins_ - 1);
      const double w = pos - k;
      if (k != k0) {
        flush_run(k0, lo, hi);
        k0 = k;
      }
      const Values v = values(i);
      for (std::size_t c = 0; c < kValues; ++c) {
        lo[c] += (1.0 - w) * v[c];
        hi[c] += w * v[c];
      }
      lo[kValues] += 1.0 - w;
      hi[kValues] += w;
    }
    flush_run(k0, lo, hi);
  }
  /// Closes the current revolution: it joins the window, the oldest leaves it.
  void end_revolution() {
    // The closed revolution stays in its slot; the oldest one's slot is reused (cleared).
    // Totals are summed only when an average is asked for (rarely), keeping this per-revolution
    // step short.
    slot_ = (slot_ + 1) % (window_ + 1);
    const auto begin = sums_.begin() + static_cast<std::ptrdiff_t>(index(slot_, 0));
    std::fill(begin, begin + static_cast<std::ptrdiff_t>(kRow * static_cast<std::size_t>(bins_)),
              0.0);
    filled_ = std::min(filled_ + 1, window_);
    totals_stale_ = true;
  }
  /// Average of channel c at bin k over the window (revolutions closed so far).
  [[nodiscard]] double average(int channel, int bin) const {
    sum_window();
    const double* t = &totals_[static_cast<std::size_t>(bin) * kRow];
    return t[kValues] > 0.0 ? t[channel] / t[kValues] : 0.0;
  }
  /// The average of a channel on the whole grid, into `out` (size bins()).
  void average(int channel, std::vector<double>& out) const {
    out.resize(static_cast<std::size_t>(bins_));
    for (int k = 0; k < bins_; ++k) {
      out[static_cast<std::size_t>(k)] = average(channel, k);
    }
    // Bins no sample has reached yet take their neighbours' mean.
    for (int k = 0; k < bins_; ++k) {
      if (totals_[static_cast<std::size_t>(k) * kRow + kValues] <= 0.0) {
        const int prev = (k + bins_ - 1) % bins_;
        const int next = (k + 1) % bins_;
        out[static_cast<std::size_t>(k)] =
            0.5 * (out[static_cast<std::size_t>(prev)] + out[static_cast<std::size_t>(next)]);
      }
    }
  }
  [[nodiscard]] int bins() const {
    return bins_;
  }
  [[nodiscard]] int revolutions() const {
    return filled_;
  }
  [[nodiscard]] int window() const {
    return window_;
  }
  void clear() {
    std::fill(sums_.begin(), sums_.end(), 0.0);
    slot_ = 0;
    filled_ = 0;
    totals_stale_ = true;
  }

 private:
  static constexpr std::size_t kValues = static_cast<std::size_t>(Channels);
  static constexpr std::size_t kRow = kValues + 1;  // the channels' sums, then their weight
  using Row = std::array<double, kRow>;

  /// The window's sums per bin (totals_), from the closed revolutions' slots, when they changed.
  void sum_window() const {
    if (!totals_stale_) {
      return;
    }
    const std::size_t size = totals_.size();
    std::fill(totals_.begin(), totals_.end(), 0.0);
    for (int s = 0; s <= window_; ++s) {
      if (s != slot_) {
        const double* slot = &sums_[index(s, 0)];
        for (std::size_t i = 0; i < size; ++i) {
          totals_[i] += slot[i];
        }
      }
    }
    totals_stale_ = false;
  }
  /// Adds a run's sums to bin k and the next one (nothing for k < 0), and zeroes them.
  void flush_run(int k, Row& lo, Row& hi) {
    if (k < 0) {
      return;
    }
    double* a = &sums_[index(slot_, k)];
    double* b = &sums_[index(slot_, k + 1 == bins_ ? 0 : k + 1)];
    for (std::size_t c = 0; c < kRow; ++c) {
      a[c] += lo[c];
      b[c] += hi[c];
      lo[c] = 0.0;
      hi[c] = 0.0;
    }
  }
#if defined(__SSE2__)
  /// A three-channel row as two SSE2 pairs, (c0, c1) and (c2, weight): a bin's share and the
  /// next bin's.
  struct PairRows {
    __m128d lo01, lo2w, hi01, hi2w;
  };
  /// One sample's shares: (1 − w)·v to the bin, w·v to the next; the weight's terms are (1 − w)·1
  /// and w·1, exactly 1 − w and w, so each lane is what the scalar code computes, bit for bit.
  static PairRows split_sample(double w, const Values& v) {
    const __m128d v01 = _mm_loadu_pd(v.data());
    const __m128d v2_one = _mm_set_pd(1.0, v[2]);
    const __m128d wa = _mm_set1_pd(1.0 - w);
    const __m128d wb = _mm_set1_pd(w);
    return {_mm_mul_pd(wa, v01), _mm_mul_pd(wa, v2_one), _mm_mul_pd(wb, v01),
            _mm_mul_pd(wb, v2_one)};
  }
  /// Adds `r` to bin k and the next one.
  void add_pairs(int k, const PairRows& r) {
    double* a = &sums_[index(slot_, k)];
    double* b = &sums_[index(slot_, k + 1 == bins_ ? 0 : k + 1)];
    _mm_storeu_pd(a, _mm_add_pd(_mm_loadu_pd(a), r.lo01));
    _mm_storeu_pd(a + 2, _mm_add_pd(_mm_loadu_pd(a + 2), r.lo2w));
    _mm_storeu_pd(b, _mm_add_pd(_mm_loadu_pd(b), r.hi01));
    _mm_storeu_pd(b + 2, _mm_add_pd(_mm_loadu_pd(b + 2), r.hi2w));
  }
  /// add_line()'s dense samples for three channels: a run's sums held in SSE2 registers.
  template <typename Position, typename ValuesOf>
  void add_dense_sse2(std::size_t count, const Position& position, const ValuesOf& values) {
    const __m128d zero = _mm_setzero_pd();
    int k0 = -1;
    PairRows run{zero, zero, zero, zero};
    for (std::size_t i = 0; i < count; ++i) {
      const double pos = position(i);
      const int k = std::min(static_cast<int>(pos), bins_ - 1);
      if (k != k0) {
        if (k0 >= 0) {
          add_pairs(k0, run);
        }
        run = {zero, zero, zero, zero};
        k0 = k;
      }
      const PairRows p = split_sample(pos - k, values(i));
      run = {_mm_add_pd(run.lo01, p.lo01), _mm_add_pd(run.lo2w, p.lo2w),
             _mm_add_pd(run.hi01, p.hi01), _mm_add_pd(run.hi2w, p.hi2w)};
    }
    if (k0 >= 0) {
      add_pairs(k0, run);
    }
  }
#endif
  /// Adds one sample at bin position pos ∈ [0, bins] to its two bins.
  void add_at(double pos, const Values& v) {
    const int k = std::min(static_cast<int>(pos), bins_ - 1);
    add_to(k, pos - k, v);
  }
  /// Adds one sample to bin k with weight 1 − w and to the next bin with weight w.
  void add_to(int k, double w, const Values& v) {
#if defined(__SSE2__)
    if constexpr (Channels == 3) {
      add_pairs(k, split_sample(w, v));
      return;
    }
#endif
    double* a = &sums_[index(slot_, k)];
    double* b = &sums_[index(slot_, k + 1 == bins_ ? 0 : k + 1)];
    for (std::size_t c = 0; c < kValues; ++c) {
      a[c] += (1.0 - w) * v[c];
      b[c] += w * v[c];
    }
    a[kValues] += 1.0 - w;
    b[kValues] += w;
  }
  // Layout [slot][bin][channels, weight]: a sample's two bins are two short contiguous runs.
  [[nodiscard]] std::size_t index(int slot, int bin) const {
    return (static_cast<std::size_t>(slot) * static_cast<std::size_t>(bins_) +
            static_cast<std::size_t>(bin)) *
           kRow;
  }

  int bins_ = 0;
  double bins_per_rad_ = 0.0;
  int window_ = 0;
  int slot_ = 0;    // ring slot of the revolution being filled
  int filled_ = 0;  // closed revolutions in the window
  // Per ring slot (window_ + 1 of them: the closed revolutions and the one being filled): the
  // channels' weighted sums and the weights, per bin.
  std::vector<double> sums_;
  // The window's sums, [bin][channels, weight], summed once after the window changed: averages
  // are read a few times per window (a report, an alignment), each reading every bin of several
  // channels. The slot being filled is not in them, so add() leaves them valid.
  mutable std::vector<double> totals_;
  mutable bool totals_stale_ = true;
};

/// The pipeline's average: fx, fy, fz.
using SyncAverage = SyncAverageOf<3>;

}  // namespace millwatch::monitor
