#pragma once
// The stretches of stream time covered by blocks rejected at or after the time the stream
// expected next (InputCheck): their samples are counted as dropped when rejected, so the gap the
// stream later shows over them must not count them again. Spans that overlap or touch are
// merged (a run of rejected blocks, or the same block twice, is one span); fixed capacity, no
// allocation.

#include <array>
#include <cstddef>
#include <cstdint>

namespace millwatch::monitor {

class RejectedSpans {
 public:
  static constexpr std::size_t kCapacity = 8;

  /// Adds [begin_us, end_us), merged with every span it overlaps or comes within tolerance_us
  /// of. When all kCapacity spans are taken by others, the furthest ahead is given up (a gap is
  /// more likely to cover a nearer one; far ahead lie corrupt times).
  void add(std::int64_t begin_us, std::int64_t end_us, std::int64_t tolerance_us);
  /// How much of [from_us, to_us) the spans cover, µs.
  [[nodiscard]] std::int64_t covered_us(std::int64_t from_us, std::int64_t to_us) const;
  /// Forgets what lies before t_us (the stream has passed it).
  void forget_before(std::int64_t t_us);
  void clear() { count_ = 0; }
  [[nodiscard]] bool empty() const { return count_ == 0; }
  [[nodiscard]] std::size_t size() const { return count_; }

 private:
  struct Span {
    std::int64_t begin_us = 0;
    std::int64_t end_us = 0;
  };
  std::array<Span, kCapacity> spans_{};  // [0, count_): disjoint, in time order
  std::size_t count_ = 0;
};

}  // namespace millwatch::monitor
