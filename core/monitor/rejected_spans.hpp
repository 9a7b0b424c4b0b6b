#pragma once
// The stretches of stream time covered by blocks rejected at or after the time the stream
// expected next (InputCheck): their samples are counted as dropped when rejected, so the gap the
// stream later shows over them must not count them again. Spans that overlap or touch are
// merged (a run of rejected blocks, or the same block twice, is one span), each with the samples
// counted in it; fixed capacity, no allocation.

#include <array>
#include <cstddef>
#include <cstdint>

namespace millwatch::monitor {

class RejectedSpans {
 public:
  static constexpr std::size_t kCapacity = 8;

  /// Adds [begin_us, end_us), in which `samples` samples were counted (nothing for an empty
  /// span or none counted), merged with every span it overlaps or comes within tolerance_us of.
  /// Beyond kCapacity spans, the two closest become one (with the time between them): a gap
  /// that covers both still subtracts exactly their samples.
  void add(std::int64_t begin_us, std::int64_t end_us, std::int64_t samples,
           std::int64_t tolerance_us);
  /// Of the samples counted in the spans, those in [from_us, to_us) (a stream's gap): for each
  /// span, its samples in the overlap (its share, by time; all of them where the gap holds it),
  /// at most the stream samples the overlap takes at `samples_per_us` (a block received twice
  /// counts once: the time it took). A share of a span the stream has partly passed is
  /// subtracted once: forget_before() keeps the share ahead.
  [[nodiscard]] std::int64_t counted_within(std::int64_t from_us, std::int64_t to_us,
                                            double samples_per_us) const;
  /// Forgets what lies before t_us (the stream has passed it).
  void forget_before(std::int64_t t_us);
  void clear() { count_ = 0; }
  [[nodiscard]] bool empty() const { return count_ == 0; }
  [[nodiscard]] std::size_t size() const { return count_; }

 private:
  struct Span {
    std::int64_t begin_us = 0;
    std::int64_t end_us = 0;
    std::int64_t samples = 0;
  };
  /// The samples counted in `us` of a span's time, by time (all of them for the whole span).
  [[nodiscard]] static std::int64_t share(const Span& s, std::int64_t us);
  /// Joins the two spans with the least time between them (count_ ≥ 2).
  void join_closest();

  std::array<Span, kCapacity + 1> spans_{};  // [0, count_): disjoint, in time order; one over
                                             // the capacity while add() joins two
  std::size_t count_ = 0;
};

}  // namespace millwatch::monitor
