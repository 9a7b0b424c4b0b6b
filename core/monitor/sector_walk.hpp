#pragma once
// The residuals' angle sectors along a revolution: the sector of sample s is that of its angle
// within the turn, a(s) = (start + slope·(s − from)) − turns, where turns steps by 2π once a(s)
// reaches 2π, in [0, sectors). Within a turn a(s) never decreases (every rounding is
// monotonic), so the sector changes only where the angle crosses a sector's edge: runs() finds
// those samples from the edges' angles and checks them with the per-sample arithmetic itself,
// so every sample gets the sector a per-sample walk would give it.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>

#include "core/monitor/revolution_record.hpp"

namespace millwatch::monitor {

class SectorWalk {
 public:
  /// @param sectors the number of sectors, taken within 1 to kMaxSectors
  SectorWalk(double start_rad, double slope_rad, std::int64_t from, int sectors)
      : start_(start_rad),
        slope_(slope_rad),
        samples_per_rad_(1.0 / slope_rad),
        from_(from),
        sectors_(std::clamp(sectors, 1, kMaxSectors)),
        per_rad_(sectors_ / kTwoPi),
        rad_per_sector_(kTwoPi / sectors_) {}

  /// Calls run(first, last, sector) for the runs of samples in [from, to] that share a sector,
  /// in order. Sample by sample where the angle does not advance (slope ≤ 0, not finite, or so
  /// small that its inverse is not) or turns twice.
  template <typename Run>
  void runs(std::int64_t to, const Run& run) const {
    if (!(slope_ > 0.0) || !std::isfinite(start_) || !std::isfinite(slope_) ||
        !std::isfinite(samples_per_rad_)) {  // a subnormal slope: its inverse is infinite
      walk_each(to, run);
      return;
    }
    // The first sample whose raw angle reaches a turn (to + 1: none), then the turn after it.
    std::int64_t wrap = estimate(from_, to, kTwoPi, 0.0);
    while (wrap <= to && raw(wrap) < kTwoPi) {
      ++wrap;
    }
    while (wrap > from_ && raw(wrap - 1) >= kTwoPi) {
      --wrap;
    }
    if (wrap <= to && raw(to) - kTwoPi >= kTwoPi) {
      walk_each(to, run);  // a second turn: more than a revolution's span
      return;
    }
    segment(from_, std::min(wrap - 1, to), 0.0, run);
    segment(wrap, to, kTwoPi, run);
  }

  /// The sector of sample s less `turns_rad` (0 or 2π): the per-sample arithmetic.
  [[nodiscard]] int sector(std::int64_t s, double turns_rad) const {
    return sector_of(raw(s) - turns_rad);
  }

 private:
  static constexpr double kTwoPi = 2.0 * std::numbers::pi;

  [[nodiscard]] double raw(std::int64_t s) const {
    return start_ + slope_ * static_cast<double>(s - from_);
  }
  [[nodiscard]] int sector_of(double a) const {
    return std::clamp(static_cast<int>(a * per_rad_), 0, sectors_ - 1);
  }
  /// About where, in [lo, hi + 1], the line's angle less turns reaches `angle` (to be checked).
  [[nodiscard]] std::int64_t estimate(std::int64_t lo, std::int64_t hi, double angle,
                                      double turns_rad) const {
    const double samples =
        std::clamp(std::ceil((angle + turns_rad - start_) * samples_per_rad_), -1.0, 1e15);
    return std::clamp(from_ + static_cast<std::int64_t>(samples), lo, hi + 1);
  }
  /// The first sample in (lo, hi + 1] whose sector is k or later (sector(lo) < k): from the
  /// edge's angle, checked by the samples' own sectors.
  [[nodiscard]] std::int64_t first_of(int k, std::int64_t lo, std::int64_t hi,
                                      double turns_rad) const {
    std::int64_t s = estimate(lo + 1, hi, k * rad_per_sector_, turns_rad);
    while (s <= hi && sector(s, turns_rad) < k) {
      ++s;
    }
    while (s - 1 > lo && sector(s - 1, turns_rad) >= k) {
      --s;
    }
    return s;
  }
  /// runs() within one turn, [lo, hi]. The first sample of each sector after lo's is found on
  /// its own (none waits on the one before: they overlap in the processor), then the runs
  /// between them are handed on, empty sectors passed over.
  template <typename Run>
  void segment(std::int64_t lo, std::int64_t hi, double turns_rad, const Run& run) const {
    if (lo > hi) {
      return;
    }
    const int k_lo = sector(lo, turns_rad);
    const int k_hi = sector(hi, turns_rad);
    std::array<std::int64_t, kMaxSectors> first{};
    for (int k = k_lo + 1; k <= k_hi; ++k) {
      first[static_cast<std::size_t>(k)] = first_of(k, lo, hi, turns_rad);
    }
    std::int64_t s = lo;
    int k_s = k_lo;  // the sector of sample s
    for (int k = k_lo + 1; k <= k_hi; ++k) {
      const std::int64_t next = first[static_cast<std::size_t>(k)];
      if (next > s) {
        run(s, next - 1, k_s);
        s = next;
      }
      k_s = k;  // from `next` on the sector is k or later
    }
    run(s, hi, k_s);
  }
  template <typename Run>
  void walk_each(std::int64_t to, const Run& run) const {
    double turns_rad = 0.0;
    for (std::int64_t s = from_; s <= to; ++s) {
      double a = raw(s) - turns_rad;
      if (a >= kTwoPi) {
        turns_rad += kTwoPi;
        a -= kTwoPi;
      }
      run(s, s, sector_of(a));
    }
  }

  double start_;
  double slope_;
  double samples_per_rad_;
  std::int64_t from_;
  int sectors_;
  double per_rad_;
  double rad_per_sector_;
};

}  // namespace millwatch::monitor
