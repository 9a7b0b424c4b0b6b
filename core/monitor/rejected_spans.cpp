#include "core/monitor/rejected_spans.hpp"

#include <algorithm>
#include <cmath>

namespace millwatch::monitor {

void RejectedSpans::add(std::int64_t begin_us, std::int64_t end_us, std::int64_t samples,
                        std::int64_t tolerance_us) {
  if (end_us <= begin_us || samples <= 0) {
    return;
  }
  Span merged{begin_us, end_us, samples};
  std::size_t n = 0;
  // The spans are disjoint and further apart than the tolerance (they would have merged), so
  // one pass in time order merges every span the new one reaches, however far it grows.
  for (std::size_t i = 0; i < count_; ++i) {
    const Span s = spans_[i];
    if (s.end_us + tolerance_us >= merged.begin_us && merged.end_us + tolerance_us >= s.begin_us) {
      merged = {std::min(merged.begin_us, s.begin_us), std::max(merged.end_us, s.end_us),
                merged.samples + s.samples};
    } else {
      spans_[n++] = s;
    }
  }
  count_ = n;
  const auto* at =
      std::upper_bound(spans_.begin(), spans_.begin() + static_cast<std::ptrdiff_t>(count_), merged,
                       [](const Span& a, const Span& b) { return a.begin_us < b.begin_us; });
  std::copy_backward(at, spans_.cbegin() + static_cast<std::ptrdiff_t>(count_),
                     spans_.begin() + static_cast<std::ptrdiff_t>(count_) + 1);
  spans_[static_cast<std::size_t>(at - spans_.begin())] = merged;
  ++count_;
  if (count_ > kCapacity) {
    join_closest();
  }
}

std::int64_t RejectedSpans::share(const Span& s, std::int64_t us) {
  const std::int64_t length_us = s.end_us - s.begin_us;
  return us == length_us ? s.samples
                         : std::llround(static_cast<double>(s.samples) * static_cast<double>(us) /
                                        static_cast<double>(length_us));
}

void RejectedSpans::join_closest() {
  std::size_t best = 0;
  for (std::size_t i = 1; i + 1 < count_; ++i) {
    if (spans_[i + 1].begin_us - spans_[i].end_us <
        spans_[best + 1].begin_us - spans_[best].end_us) {
      best = i;
    }
  }
  spans_[best] = {spans_[best].begin_us, spans_[best + 1].end_us,
                  spans_[best].samples + spans_[best + 1].samples};
  std::copy(spans_.begin() + static_cast<std::ptrdiff_t>(best) + 2,
            spans_.begin() + static_cast<std::ptrdiff_t>(count_),
            spans_.begin() + static_cast<std::ptrdiff_t>(best) + 1);
  --count_;
}

std::int64_t RejectedSpans::counted_within(std::int64_t from_us, std::int64_t to_us,
                                           double samples_per_us) const {
  std::int64_t counted = 0;
  for (std::size_t i = 0; i < count_; ++i) {
    const Span& s = spans_[i];
    const std::int64_t overlap_us = std::min(s.end_us, to_us) - std::max(s.begin_us, from_us);
    if (overlap_us <= 0) {
      continue;
    }
    // The span's samples in the overlap, at most the stream samples the overlap takes; each
    // span rounded on its own.
    counted += std::min<std::int64_t>(
        share(s, overlap_us), std::llround(static_cast<double>(overlap_us) * samples_per_us));
  }
  return counted;
}

void RejectedSpans::forget_before(std::int64_t t_us) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < count_; ++i) {
    const Span& s = spans_[i];
    if (s.end_us > t_us) {  // of a span the stream is inside, the part ahead keeps its share
      const std::int64_t begin_us = std::max(s.begin_us, t_us);
      spans_[n++] = {begin_us, s.end_us, share(s, s.end_us - begin_us)};
    }
  }
  count_ = n;
}

}  // namespace millwatch::monitor
