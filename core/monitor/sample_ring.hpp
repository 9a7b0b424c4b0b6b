#pragma once
// A ring buffer of several channels addressed by absolute sample index: the pipeline's recent
// history, from which revolutions are measured once their samples have arrived.

#include <cstdint>
#include <vector>

namespace millwatch::monitor {

class SampleRing {
 public:
  SampleRing() = default;
  /// @param channels number of channels; @param min_capacity samples kept (rounded up to 2^k)
  SampleRing(int channels, std::size_t min_capacity);

  /// Appends one sample of every channel at index `sample` (must be newest() + 1 unless empty).
  void push(std::int64_t sample, const double* values);
  /// Value of channel c at absolute index n (oldest() ≤ n ≤ newest()).
  [[nodiscard]] double at(int channel, std::int64_t n) const {
    return data_[static_cast<std::size_t>(channel) * capacity_ +
                 (static_cast<std::size_t>(n) & mask_)];
  }
  [[nodiscard]] bool empty() const { return newest_ < oldest_; }
  [[nodiscard]] std::int64_t oldest() const { return oldest_; }
  [[nodiscard]] std::int64_t newest() const { return newest_; }
  [[nodiscard]] std::size_t capacity() const { return capacity_; }
  /// Forget everything; the next push starts anywhere.
  void clear();

 private:
  int channels_ = 0;
  std::size_t capacity_ = 0;
  std::size_t mask_ = 0;
  std::vector<double> data_;
  std::int64_t oldest_ = 0;
  std::int64_t newest_ = -1;
};

}  // namespace millwatch::monitor
