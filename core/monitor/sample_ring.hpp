#pragma once
// A ring buffer of several channels addressed by absolute sample index: the pipeline's recent
// history, from which revolutions are measured once their samples have arrived. The channels of
// one sample sit side by side (one push writes one short run, a revolution's scan reads memory
// in order).

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/monitor/cache_aligned.hpp"

namespace millwatch::monitor {

class SampleRing {
 public:
  SampleRing() = default;
  /// @param channels number of channels; @param min_capacity samples kept (rounded up to 2^k)
  SampleRing(int channels, std::size_t min_capacity);

  /// Appends one sample of every channel at index `sample` (must be newest() + 1 unless empty).
  void push(std::int64_t sample, const double* values) {
    take(sample, 1);
    double* slot = row(sample);
    if (channels_ == 4) {  // the pipeline's: four stores, not a call to memcpy
      slot[0] = values[0];
      slot[1] = values[1];
      slot[2] = values[2];
      slot[3] = values[3];
      return;
    }
    for (std::size_t c = 0; c < channels_; ++c) {
      slot[c] = values[c];
    }
  }
  /// push() of `count` samples from index `first` on, a stretch of rows at a time: fill(i, n,
  /// rows) writes samples first + i … first + i + n − 1 into the n rows from `rows` on (2^k
  /// doubles each: the channels, then padding), at most twice (the ring's end splits the run;
  /// of a run longer than the ring, only the samples it keeps). For a fill that handles several
  /// rows at once in vector registers.
  template <typename Fill>
  void push_rows(std::int64_t first, std::size_t count, const Fill& fill) {
    if (count == 0) {
      return;
    }
    take(first, count);
    const std::size_t skipped = count > capacity_ ? count - capacity_ : 0;
    const std::size_t at =
        static_cast<std::size_t>(first + static_cast<std::int64_t>(skipped)) & mask_;
    const std::size_t kept = count - skipped;
    const std::size_t before_end = std::min(kept, capacity_ - at);
    fill(skipped, before_end, &data_[at << row_shift_]);
    if (before_end < kept) {
      fill(skipped + before_end, kept - before_end, data_.data());
    }
  }
  /// Value of channel c at absolute index n (oldest() ≤ n ≤ newest()).
  [[nodiscard]] double at(int channel, std::int64_t n) const {
    return row(n)[static_cast<std::size_t>(channel)];
  }
  /// Every channel of sample n, side by side (oldest() ≤ n ≤ newest()).
  [[nodiscard]] const double* row(std::int64_t n) const {
    return &data_[(static_cast<std::size_t>(n) & mask_) << row_shift_];
  }
  /// The ring's rows by value, for a loop that stores through pointers the compiler must assume
  /// alias anything (SIMD stores): its base, mask and shift then stay in registers.
  struct Rows {
    const double* data;
    std::size_t mask;
    std::size_t shift;
    [[nodiscard]] const double* row(std::int64_t n) const {
      return data + ((static_cast<std::size_t>(n) & mask) << shift);
    }
  };
  [[nodiscard]] Rows rows() const { return {data_.data(), mask_, row_shift_}; }
  [[nodiscard]] bool empty() const { return newest_ < oldest_; }
  [[nodiscard]] std::int64_t oldest() const { return oldest_; }
  [[nodiscard]] std::int64_t newest() const { return newest_; }
  [[nodiscard]] std::size_t capacity() const { return capacity_; }
  /// Forget everything; the next push starts anywhere.
  void clear();

 private:
  /// The ring now holds samples [first, first + count) after what it held, if they follow it
  /// (else they start a new stretch, as the first samples do).
  void take(std::int64_t first, std::size_t count) {
    if (first != newest_ + 1 || empty()) {
      oldest_ = first;
    }
    newest_ = first + static_cast<std::int64_t>(count) - 1;
    if (newest_ - oldest_ >= static_cast<std::int64_t>(capacity_)) {
      oldest_ = newest_ - static_cast<std::int64_t>(capacity_) + 1;
    }
  }
  [[nodiscard]] double* row(std::int64_t n) {
    return &data_[(static_cast<std::size_t>(n) & mask_) << row_shift_];
  }

  std::size_t channels_ = 0;
  // A row holds 2^row_shift_ doubles (the channels rounded up): a row's place is a shift, not a
  // multiplication, in every access.
  std::size_t row_shift_ = 0;
  std::size_t capacity_ = 0;
  std::size_t mask_ = 0;
  CacheAlignedVector<double>
      data_;  // [sample slot][channel]; a row of 4 or 8 within one cache line
  std::int64_t oldest_ = 0;
  std::int64_t newest_ = -1;
};

}  // namespace millwatch::monitor
