#pragma once
// Revolution-synchronous average: the filtered force of a window of W revolutions on a uniform
// spindle-angle grid (bin k at 2πk/B from the tracker's angle zero). Each sample is shared
// between its two neighbouring bins in proportion to its angle, so a grid finer than the
// samples of one revolution still fills in over several revolutions.
//
// The windows follow one another (tumbling): a window fills to W closed revolutions, and the
// next revolution's first sample starts a new one. The pipeline reads the average when a window
// is full (its reports, every W revolutions) and while the first window since it cleared the
// average fills (a lock's template, the model's alignments after it: first_window()), never
// part-way through a later one: a sliding window would give those reads the same revolutions,
// but would have to keep every revolution's sums apart (31 grids of 8 KB, one cleared a
// revolution, where one grid stays in the L1 cache).
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

#include "core/monitor/cache_aligned.hpp"
#include "core/monitor/grid_line.hpp"
#include "core/signal/cpu_features.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
// Three channels and their weight fill one 256-bit register: an AVX kernel, compiled for AVX
// alone (target attribute) and run only where the CPU has it.
#if defined(__SSE2__) && defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#define MILLWATCH_SYNC_AVERAGE_AVX 1
#include <immintrin.h>
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
    sums_.assign(kRow * static_cast<std::size_t>(bins_), 0.0);
    avx_ = signal::cpu_has_avx();
  }

  /// Adds one sample at spindle angle `angle_rad` (any real; taken modulo 2π) to the current
  /// revolution.
  void add(double angle_rad, const Values& values) {
    start_window_if_full();
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
    start_window_if_full();
    if (!spindle_line(bins_per_sample)) {  // not a spindle's line: any
      add_any_line(count, first_bin, bins_per_sample, values);
      return;
    }
    Line line = line_of(first_bin, bins_per_sample, bins_);
    if (bins_per_sample >= 1.0) {
      for (std::size_t i = 0; i < count; ++i) {
        add_at(line.at(i), values(i));
      }
      return;
    }
#if defined(__SSE2__)
    if constexpr (Channels == 3) {
      add_dense_sse2(count, line, values);
      return;
    }
#endif
    int k0 = -1;
    Row lo{}, hi{};
    for (std::size_t i = 0; i < count; ++i) {
      const double pos = line.at(i);
      const int k = std::min(static_cast<int>(pos), bins_ - 1);
      const double w = pos - k;
      if (k != k0) {
        if (k0 >= 0 && k == k0 + 1) {
          carry_run(k0, lo, hi);
        } else {
          flush_run(k0, lo, hi);
        }
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
  /// add_line() for three channels read from rows: rows(i) points at sample i's fx, fy, fz and
  /// one more double, which must be readable (the AVX kernel loads all four) but does not reach
  /// the sums (the pipeline's ring holds fx² + fy² there). Where the CPU has AVX (and set_avx()
  /// has not turned it off), a sample's row and a bin's sums, three channels and the weight,
  /// each fill one 256-bit register: half the instructions of the SSE2 pairs; the samples' bins
  /// and shares come four at a time (grid_chunk_avx: the positions the line gives). The same
  /// operations on each lane, so the same sums, bit for bit.
  template <typename RowsOf>
  void add_line_rows(std::size_t count, double first_bin, double bins_per_sample,
                     const RowsOf& rows) {
    static_assert(Channels == 3, "rows of three channels and one more double");
    start_window_if_full();
#if defined(MILLWATCH_SYNC_AVERAGE_AVX)
    if (avx_ && spindle_line(bins_per_sample)) {
      Line line = line_of(first_bin, bins_per_sample, bins_);
      if (bins_per_sample >= 1.0) {
        add_sparse_avx(count, line, rows);
      } else {
        add_dense_avx(count, line, rows);
      }
      return;
    }
#endif
    add_line(count, first_bin, bins_per_sample, [&](std::size_t i) {
      const double* r = rows(i);
      return Values{r[0], r[1], r[2]};
    });
  }
  /// Whether add_line_rows() may use its AVX kernel (on by default where the CPU has AVX; the
  /// tests compare it with the SSE2 code).
  void set_avx(bool allowed) {
    avx_ = allowed && signal::cpu_has_avx();
  }
  /// Whether add_line_rows() runs its AVX kernel.
  [[nodiscard]] bool avx() const {
    return avx_;
  }
  /// Closes the current revolution: it joins the window. The window's W-th closes it; the next
  /// revolution starts a new window.
  void end_revolution() {
    start_window_if_full();  // (a revolution without samples after a full window)
    ++filled_;
    full_ = filled_ >= window_;
  }
  /// Average of channel c at bin k over the window's revolutions. Read it after end_revolution():
  /// a sample added after that belongs to a revolution not yet closed, and is in the sums too
  /// (after a full window, the first such sample starts the next window's sums).
  [[nodiscard]] double average(int channel, int bin) const {
    const double* t = row(bin);
    return t[kValues] > 0.0 ? t[channel] / t[kValues] : 0.0;
  }
  /// The window's sums at bin k: each channel's weighted sum, then the weight (what average()
  /// divides), as added up.
  [[nodiscard]] std::array<double, static_cast<std::size_t>(Channels) + 1> window_sums(
      int bin) const {
    std::array<double, kRow> out{};
    std::copy_n(row(bin), kRow, out.begin());
    return out;
  }
  /// The average of a channel on the whole grid, into `out` (size bins()).
  void average(int channel, std::vector<double>& out) const {
    out.resize(static_cast<std::size_t>(bins_));
    for (int k = 0; k < bins_; ++k) {
      out[static_cast<std::size_t>(k)] = average(channel, k);
    }
    // Bins no sample has reached yet take their neighbours' mean.
    for (int k = 0; k < bins_; ++k) {
      if (row(k)[kValues] <= 0.0) {
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
  /// Whether the window is the first since clear() (or construction): it holds every revolution
  /// closed since, up to a full window.
  [[nodiscard]] bool first_window() const {
    return !continued_;
  }
  void clear() {
    std::fill(sums_.begin(), sums_.end(), 0.0);
    filled_ = 0;
    full_ = false;
    continued_ = false;
  }

 private:
  static constexpr std::size_t kValues = static_cast<std::size_t>(Channels);
  static constexpr std::size_t kRow = kValues + 1;  // the channels' sums, then their weight
  using Row = std::array<double, kRow>;

  /// The bin positions of a line of samples, sample i at first_bin + i·bins_per_sample, in
  /// [0, bins] (grid_line.hpp).
  using Line = GridLine;
  [[nodiscard]] static Line line_of(double first_bin, double bins_per_sample, int bins) {
    const auto grid = static_cast<double>(bins);
    return Line(first_bin - grid * std::floor(first_bin / grid), bins_per_sample, grid);
  }
  /// A line a spindle makes: forwards, less than a turn a sample.
  [[nodiscard]] bool spindle_line(double bins_per_sample) const {
    return bins_per_sample >= 0.0 && bins_per_sample < static_cast<double>(bins_);
  }
  /// add_line() on any line: each sample's position wrapped on its own.
  template <typename ValuesOf>
  void add_any_line(std::size_t count, double first_bin, double bins_per_sample,
                    const ValuesOf& values) {
    const auto grid = static_cast<double>(bins_);
    for (std::size_t i = 0; i < count; ++i) {
      const double pos = first_bin + bins_per_sample * static_cast<double>(i);
      add_at(pos - grid * std::floor(pos / grid), values(i));
    }
  }

  /// A full window's sums give way to the next revolution's samples: a new window.
  void start_window_if_full() {
    if (full_) {
      clear();
      continued_ = true;
    }
  }
  /// The next sample is in the next bin (k + 1 < bins): the run's sums for bin k are done and
  /// added to it; its sums for k + 1 carry on as the next run's start (`lo`), where they would
  /// have been added to memory only to be read back at once. Dense samples (the pipeline's
  /// 333.3 kHz: 0.97 bins a sample) move on a bin nearly every sample: a store and a load fewer
  /// a sample, and no store-to-load wait between successive samples.
  void carry_run(int k, Row& lo, Row& hi) {
    double* a = row(k);
    for (std::size_t c = 0; c < kRow; ++c) {
      a[c] += lo[c];
      lo[c] = hi[c];
      hi[c] = 0.0;
    }
  }
  /// Adds a run's sums to bin k and the next one (nothing for k < 0), and zeroes them.
  void flush_run(int k, Row& lo, Row& hi) {
    if (k < 0) {
      return;
    }
    double* a = row(k);
    double* b = row(k + 1 == bins_ ? 0 : k + 1);
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
    double* a = row(k);
    double* b = row(k + 1 == bins_ ? 0 : k + 1);
    _mm_storeu_pd(a, _mm_add_pd(_mm_loadu_pd(a), r.lo01));
    _mm_storeu_pd(a + 2, _mm_add_pd(_mm_loadu_pd(a + 2), r.lo2w));
    _mm_storeu_pd(b, _mm_add_pd(_mm_loadu_pd(b), r.hi01));
    _mm_storeu_pd(b + 2, _mm_add_pd(_mm_loadu_pd(b + 2), r.hi2w));
  }
  /// add_line()'s dense samples for three channels: a run's sums held in SSE2 registers.
  template <typename ValuesOf>
  void add_dense_sse2(std::size_t count, Line& line, const ValuesOf& values) {
    const __m128d zero = _mm_setzero_pd();
    int k0 = -1;
    PairRows run{zero, zero, zero, zero};
    for (std::size_t i = 0; i < count; ++i) {
      const double pos = line.at(i);
      const int k = std::min(static_cast<int>(pos), bins_ - 1);
      if (k != k0) {
        if (k0 >= 0 && k == k0 + 1) {  // carry_run()
          double* a = row(k0);
          _mm_storeu_pd(a, _mm_add_pd(_mm_loadu_pd(a), run.lo01));
          _mm_storeu_pd(a + 2, _mm_add_pd(_mm_loadu_pd(a + 2), run.lo2w));
          run = {run.hi01, run.hi2w, zero, zero};
        } else {
          if (k0 >= 0) {
            add_pairs(k0, run);
          }
          run = {zero, zero, zero, zero};
        }
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
#if defined(MILLWATCH_SYNC_AVERAGE_AVX)
  /// Adds `lo` to bin k's row of `sums` (channels and weight) and `hi` to the next bin's (bin 0
  /// after the last).
  __attribute__((target("avx"))) static void add_two_rows_avx(double* sums, int k, int last,
                                                              __m256d lo, __m256d hi) {
    double* a = sums + static_cast<std::size_t>(k) * kRow;
    double* b = k == last ? sums : a + kRow;
    _mm256_storeu_pd(a, _mm256_add_pd(_mm256_loadu_pd(a), lo));
    _mm256_storeu_pd(b, _mm256_add_pd(_mm256_loadu_pd(b), hi));
  }
  /// add_line_rows()'s samples sparser than the bins: each straight to its two bins, a chunk
  /// of their bins and shares at a time (grid_chunk_avx). Everything the loop reads is in locals
  /// (the line and `rows` by value): the compiler must assume that a SIMD store may change any
  /// memory, and would read members again after every one.
  template <typename RowsOf>
  __attribute__((target("avx"))) void add_sparse_avx(std::size_t count, Line line,
                                                     const RowsOf rows) {
    double* const sums = row(0);
    const int last = bins_ - 1;
    const __m256d one = _mm256_set1_pd(1.0);
    GridChunk chunk;
    for (std::size_t from = 0; from < count; from += kGridChunk) {
      const std::size_t n = std::min(kGridChunk, count - from);
      grid_chunk_avx(line, from, n, last, chunk);
      for (std::size_t j = 0; j < n; ++j) {
        const __m256d w = _mm256_broadcast_sd(&chunk.fraction[j]);
        const __m256d v = _mm256_blend_pd(_mm256_loadu_pd(rows(from + j)), one, 0x8);  // (c, 1)
        add_two_rows_avx(sums, chunk.point[j], last, _mm256_mul_pd(_mm256_sub_pd(one, w), v),
                         _mm256_mul_pd(w, v));
      }
    }
  }
  /// add_line_rows()'s denser samples: a run's sums held in two registers until it moves on (to
  /// the next bin: carry_run()).
  template <typename RowsOf>
  __attribute__((target("avx"))) void add_dense_avx(std::size_t count, Line line,
                                                    const RowsOf rows) {
    double* const sums = row(0);
    const int last = bins_ - 1;
    const __m256d one = _mm256_set1_pd(1.0);
    const __m256d zero = _mm256_setzero_pd();
    int k0 = -1;
    __m256d lo = zero, hi = zero;
    GridChunk chunk;
    for (std::size_t from = 0; from < count; from += kGridChunk) {
      const std::size_t n = std::min(kGridChunk, count - from);
      grid_chunk_avx(line, from, n, last, chunk);
      for (std::size_t j = 0; j < n; ++j) {
        const int k = chunk.point[j];
        if (k != k0) {
          if (k0 >= 0 && k == k0 + 1) {  // carry_run()
            double* a = sums + static_cast<std::size_t>(k0) * kRow;
            _mm256_storeu_pd(a, _mm256_add_pd(_mm256_loadu_pd(a), lo));
            lo = hi;
          } else {
            if (k0 >= 0) {
              add_two_rows_avx(sums, k0, last, lo, hi);
            }
            lo = zero;
          }
          hi = zero;
          k0 = k;
        }
        const __m256d w = _mm256_broadcast_sd(&chunk.fraction[j]);
        const __m256d v = _mm256_blend_pd(_mm256_loadu_pd(rows(from + j)), one, 0x8);
        lo = _mm256_add_pd(lo, _mm256_mul_pd(_mm256_sub_pd(one, w), v));
        hi = _mm256_add_pd(hi, _mm256_mul_pd(w, v));
      }
    }
    if (k0 >= 0) {
      add_two_rows_avx(sums, k0, last, lo, hi);
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
    double* a = row(k);
    double* b = row(k + 1 == bins_ ? 0 : k + 1);
    for (std::size_t c = 0; c < kValues; ++c) {
      a[c] += (1.0 - w) * v[c];
      b[c] += w * v[c];
    }
    a[kValues] += 1.0 - w;
    b[kValues] += w;
  }
  // Layout [bin][channels, weight]: a sample's two bins are two short contiguous runs.
  [[nodiscard]] double* row(int bin) {
    return sums_.data() + static_cast<std::size_t>(bin) * kRow;
  }
  [[nodiscard]] const double* row(int bin) const {
    return sums_.data() + static_cast<std::size_t>(bin) * kRow;
  }

  int bins_ = 0;
  double bins_per_rad_ = 0.0;
  int window_ = 0;
  int filled_ = 0;          // closed revolutions in the window
  bool full_ = false;       // filled_ reached window_: the next sample starts a new window
  bool continued_ = false;  // a window has followed a full one since clear()
  bool avx_ = false;        // add_line_rows() runs its AVX kernel
  // The window's sums per bin: the channels' weighted sums and the weights.
  CacheAlignedVector<double> sums_;
};

/// The pipeline's average: fx, fy, fz.
using SyncAverage = SyncAverageOf<3>;

}  // namespace millwatch::monitor
