#include "core/monitor/rejected_spans.hpp"

#include <algorithm>

namespace millwatch::monitor {

void RejectedSpans::add(std::int64_t begin_us, std::int64_t end_us, std::int64_t tolerance_us) {
  Span merged{begin_us, end_us};
  std::array<Span, kCapacity> kept{};
  std::size_t n = 0;
  // The spans are disjoint and further apart than the tolerance (they would have merged), so
  // one pass in time order merges every span the new one reaches, however far it grows.
  for (std::size_t i = 0; i < count_; ++i) {
    const Span& s = spans_[i];
    if (s.end_us + tolerance_us >= merged.begin_us && merged.end_us + tolerance_us >= s.begin_us) {
      merged.begin_us = std::min(merged.begin_us, s.begin_us);
      merged.end_us = std::max(merged.end_us, s.end_us);
    } else {
      kept[n++] = s;
    }
  }
  if (n == kCapacity) {
    if (merged.begin_us >= kept[n - 1].begin_us) {
      return;  // the furthest ahead: given up
    }
    --n;
  }
  const auto at = static_cast<std::size_t>(
      std::upper_bound(kept.begin(), kept.begin() + static_cast<std::ptrdiff_t>(n), merged,
                       [](const Span& a, const Span& b) { return a.begin_us < b.begin_us; }) -
      kept.begin());
  std::copy(kept.begin(), kept.begin() + static_cast<std::ptrdiff_t>(at), spans_.begin());
  spans_[at] = merged;
  std::copy(kept.begin() + static_cast<std::ptrdiff_t>(at),
            kept.begin() + static_cast<std::ptrdiff_t>(n),
            spans_.begin() + static_cast<std::ptrdiff_t>(at) + 1);
  count_ = n + 1;
}

std::int64_t RejectedSpans::covered_us(std::int64_t from_us, std::int64_t to_us) const {
  std::int64_t covered = 0;
  for (std::size_t i = 0; i < count_; ++i) {
    covered += std::max<std::int64_t>(
        0, std::min(spans_[i].end_us, to_us) - std::max(spans_[i].begin_us, from_us));
  }
  return covered;
}

void RejectedSpans::forget_before(std::int64_t t_us) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < count_; ++i) {
    if (spans_[i].end_us > t_us) {
      spans_[n++] = {std::max(spans_[i].begin_us, t_us), spans_[i].end_us};
    }
  }
  count_ = n;
}

}  // namespace millwatch::monitor
