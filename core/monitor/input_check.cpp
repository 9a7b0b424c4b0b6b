#include "core/monitor/input_check.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <span>

#include "core/monitor/nearest_integer.hpp"
#include "core/signal/sample_limit.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace millwatch::monitor {

InputCheck::InputCheck(const InputCheckConfig& config) : config_(config) {
  const double plausible = std::min(config_.plausible_N, std::numeric_limits<double>::max());
  for (std::size_t a = 0; a < 3; ++a) {
    limits_[a] = std::min(plausible, std::nextafter(config_.saturation_N[a], 0.0));
  }
  for (auto& channel : out_) {
    channel = std::make_unique_for_overwrite<double[]>(config_.max_block_samples);
  }
  flags_ = std::make_unique_for_overwrite<std::uint8_t[]>(config_.max_block_samples);
}

namespace {

/// Whether |v[a][i]| ≤ limit[a] for every channel a and sample i (a NaN is not): the three
/// channels side by side, two samples per SSE2 comparison — the block's first read, from
/// memory, goes down three streams at once rather than one after another.
bool all_within(const std::array<std::span<const double>, 3>& v, std::size_t n,
                const std::array<double, 3>& limit) {
  std::size_t i = 0;
  bool ok = true;
#if defined(__SSE2__)
  const __m128d sign = _mm_set1_pd(-0.0);
  const __m128d bx = _mm_set1_pd(limit[0]), by = _mm_set1_pd(limit[1]), bz = _mm_set1_pd(limit[2]);
  const double* x = v[0].data();
  const double* y = v[1].data();
  const double* z = v[2].data();
  __m128d all = _mm_cmpeq_pd(bx, bx);  // every bit set (the limits are not NaN)
  for (; i + 2 <= n; i += 2) {
    const __m128d in_x = _mm_cmple_pd(_mm_andnot_pd(sign, _mm_loadu_pd(x + i)), bx);
    const __m128d in_y = _mm_cmple_pd(_mm_andnot_pd(sign, _mm_loadu_pd(y + i)), by);
    const __m128d in_z = _mm_cmple_pd(_mm_andnot_pd(sign, _mm_loadu_pd(z + i)), bz);
    all = _mm_and_pd(all, _mm_and_pd(in_x, _mm_and_pd(in_y, in_z)));
  }
  ok = _mm_movemask_pd(all) == 3;
#endif
  for (; i < n; ++i) {
    for (std::size_t a = 0; a < 3; ++a) {
      ok = ok && signal::within_limit(v[a][i], limit[a]);
    }
  }
  return ok;
}

}  // namespace

std::int64_t InputCheck::utime_of(std::int64_t sample) const {
  return start_utime_us_ + nearest_integer(static_cast<double>(sample - start_sample_) * 1e6 /
                                           config_.sample_rate_hz);
}

double InputCheck::samples_late(std::int64_t utime_us, std::int64_t expected_utime_us) const {
  // Both utimes are within ±kMaxAbsUtime_us (2⁵³): their difference cannot overflow.
  return static_cast<double>(utime_us - expected_utime_us) * config_.sample_rate_hz / 1e6;
}

void InputCheck::restart() {
  started_ = false;
  hole_samples_ = 0;
  continued_from_utime_us_.reset();
  rejected_ahead_.clear();
}

void InputCheck::continue_after(const InputCheck& predecessor) {
  if (const std::optional<std::int64_t> next_us = predecessor.next_utime();
      next_us && predecessor.config_.sample_rate_hz == config_.sample_rate_hz) {
    continue_after(*next_us);
    rejected_ahead_ = predecessor.rejected_ahead_;
    // A block rejected at its time just before the reload: the successor's first block follows
    // the hole (its samples counted as dropped by the predecessor, the gap not yet).
    hole_samples_ = predecessor.hole_samples_;
    hole_start_utime_us_ = predecessor.hole_start_utime_us_;
  }
}

std::optional<double> InputCheck::samples_into_hole(std::int64_t utime_us) const {
  if (hole_samples_ == 0) {
    return std::nullopt;
  }
  const double into = samples_late(utime_us, hole_start_utime_us_);
  return into >= -config_.tolerance_samples ? std::optional<double>(into) : std::nullopt;
}

std::int64_t InputCheck::duration_us(std::int64_t samples, double rate_hz) const {
  // A block's own rate within a factor 1000 of the configured one (≥ 1 Hz), else the configured
  // rate: at most 2³¹ samples last within 2⁵¹ µs, no overflow added to a utime within ±2⁵³.
  const double configured = config_.sample_rate_hz;
  const double rate =
      rate_hz >= 1e-3 * configured && rate_hz <= 1e3 * configured ? rate_hz : configured;
  return std::llround(static_cast<double>(samples) * 1e6 / rate);
}

std::int64_t InputCheck::counted_already(std::int64_t missing, std::int64_t expected_us,
                                         std::int64_t utime_us) const {
  if (rejected_ahead_.empty()) {
    return 0;
  }
  return std::min(
      missing, rejected_ahead_.counted_within(expected_us, utime_us, config_.sample_rate_hz / 1e6));
}

std::optional<std::int64_t> InputCheck::next_utime() const {
  if (started_) {
    return utime_of(next_sample_);
  }
  return continued_from_utime_us_;
}

CheckedBlock InputCheck::reject(const SampleBlock& block, std::string_view why) {
  const auto n = static_cast<std::int64_t>(block.fx_N.size());
  counters_.samples_dropped += n;
  ++counters_.blocks_rejected;
  const std::optional<std::int64_t> expected_us = next_utime();
  const double late = expected_us && plausible_utime(block.utime_us)
                          ? samples_late(block.utime_us, *expected_us)
                          : -std::numeric_limits<double>::infinity();
  // Within an open hole (before the time expected after it): a good block there would cut the
  // hole short (check()), and the gap after that block must find this one's samples counted.
  const bool within_hole =
      plausible_utime(block.utime_us) && samples_into_hole(block.utime_us).has_value();
  if (started_ && std::fabs(late) <= config_.tolerance_samples) {
    // A block rejected at its expected time leaves its slot empty: the next block follows the
    // hole without counting those samples again.
    if (hole_samples_ == 0) {
      hole_start_utime_us_ = *expected_us;
    }
    next_sample_ += n;
    hole_samples_ += n;
    if (!rejected_ahead_.empty()) {  // the spans within the hole stay: it may be cut short
      rejected_ahead_.forget_before(hole_start_utime_us_);
    }
  } else if (late >= -config_.tolerance_samples || within_hole) {
    // Later than expected, or before a continued stream's first block, or within a hole: the
    // stream's time stays where it was (one corrupt utime must not refuse the good blocks after
    // it, nor a good block at the same time be refused), and the gap before the next block does
    // not count these samples again.
    const double tolerance_us = config_.tolerance_samples * 1e6 / config_.sample_rate_hz;
    // Its span at its own rate (a sender at another rate sends contiguous blocks at it); a rate
    // in a header rejected for it may be corrupt, but a gap takes at most the span's samples,
    // shared out by time.
    rejected_ahead_.add(block.utime_us, block.utime_us + duration_us(n, block.sample_rate_hz), n,
                        static_cast<std::int64_t>(tolerance_us));
  }
  CheckedBlock out;
  out.verdict = BlockVerdict::kRejected;
  out.problem = why;
  return out;
}

CheckedBlock InputCheck::check(const SampleBlock& block) {
  const CheckedBlock timed = check_time(block);
  return timed.verdict == BlockVerdict::kRejected ? timed : check_samples(block, timed, false);
}

CheckedBlock InputCheck::check_time(const SampleBlock& block) {
  const std::size_t n = block.fx_N.size();
  counters_.samples_in += static_cast<std::int64_t>(n);
  if (n == 0) {
    return reject(block, "empty block");
  }
  if (block.fy_N.size() != n || block.fz_N.size() != n) {
    return reject(block, "channels of unequal length");
  }
  if (n > config_.max_block_samples) {
    return reject(block, "block longer than max_block_samples");
  }
  if (!plausible_utime(block.utime_us)) {
    return reject(block, "utime beyond +-2^53 us (a corrupt time)");
  }
  // Written so that a NaN rate fails too.
  if (!(std::fabs(block.sample_rate_hz - config_.sample_rate_hz) <=
        1e-6 * config_.sample_rate_hz)) {
    // Both rates said: after a reload that changed the configured one, every block of the
    // stream is refused for it, and which of the two is wrong is the user's to see.
    char text[128];
    std::snprintf(text, sizeof text,
                  "sample rate differs from the configured one (the block's %.7g Hz, "
                  "sample_rate_hz %.7g Hz)",
                  block.sample_rate_hz, config_.sample_rate_hz);
    rate_problem_ = text;
    return reject(block, rate_problem_);
  }

  CheckedBlock out;
  bool gap_counted = false;
  // When the block was due: after the stream's last block, or (its first after a reload) where
  // the predecessor's stream stopped; none for a new stream.
  if (const std::optional<std::int64_t> expected_us = next_utime()) {
    double late = samples_late(block.utime_us, *expected_us);
    if (late < -config_.tolerance_samples) {
      // Within the slot of a block rejected at its time: that block's length said more than the
      // stream skipped (or its samples, at its own rate, lasted less than at the stream's). The
      // hole ends at this block, which is not refused for it.
      if (const std::optional<double> into_hole = samples_into_hole(block.utime_us)) {
        const auto kept = std::max<std::int64_t>(0, std::llround(*into_hole));
        if (started_) {
          next_sample_ -= hole_samples_ - kept;
        }
        hole_samples_ = kept;
        late = 0.0;
      }
    }
    if (late < -config_.tolerance_samples) {  // a block the stream (or its predecessor) had
      ++counters_.out_of_order_blocks;
      return reject(block, "block older than expected (out of order or repeated)");
    }
    if (late > config_.tolerance_samples) {
      const auto missing = static_cast<std::int64_t>(std::llround(late));
      ++counters_.gaps;
      gap_counted = true;
      counters_.samples_dropped += missing - counted_already(missing, *expected_us, block.utime_us);
      out.gap_samples = missing;
      if (started_) {
        next_sample_ += missing;
        out.problem = "gap before block";
      } else {  // the new stream's timing starts at this block
        out.problem = "gap before block (since the stream before a reload)";
      }
    }
  }
  if (!rejected_ahead_.empty()) {  // the stream is past what lies before this block's end
    rejected_ahead_.forget_before(
        block.utime_us + duration_us(static_cast<std::int64_t>(n), config_.sample_rate_hz));
  }
  if (!started_) {
    started_ = true;
    start_utime_us_ = block.utime_us;
    start_sample_ = next_sample_;
    continued_from_utime_us_.reset();
  }
  if (hole_samples_ > 0) {  // a rejected block's slot: a discontinuity, its samples counted
    out.gap_samples += hole_samples_;
    hole_samples_ = 0;
    if (!gap_counted) {  // else one discontinuity: the hole and the samples missing after it
      ++counters_.gaps;
      out.problem = "samples of a rejected block missing before this one";
    }
  }

  out.verdict = BlockVerdict::kAccepted;  // its samples not yet tested (check_samples())
  out.first_sample = next_sample_;
  out.fx_N = block.fx_N;
  out.fy_N = block.fy_N;
  out.fz_N = block.fz_N;
  return out;
}

CheckedBlock InputCheck::check_samples(const SampleBlock& block, CheckedBlock timed,
                                       bool known_within) {
  CheckedBlock out = timed;
  const std::size_t n = block.fx_N.size();
  const std::array<std::span<const double>, 3> in = {block.fx_N, block.fy_N, block.fz_N};
  // The usual block: every sample plausible and below saturation (a NaN fails both tests). It
  // is handed on as it is, without copies.
  if (known_within || all_within(in, n, sample_limits())) {
    for (std::size_t a = 0; a < 3; ++a) {
      last_good_[a] = in[a][n - 1];
    }
    counters_.samples_accepted += static_cast<std::int64_t>(n);
    out.verdict = BlockVerdict::kAccepted;
    out.first_sample = next_sample_;
    out.fx_N = block.fx_N;
    out.fy_N = block.fy_N;
    out.fz_N = block.fz_N;
    std::fill(flags_.get(), flags_.get() + n, std::uint8_t{0});
    out.flags = {flags_.get(), n};
    next_sample_ += static_cast<std::int64_t>(n);
    return out;
  }
  for (std::size_t i = 0; i < n; ++i) {
    std::uint8_t flag = 0;
    for (std::size_t a = 0; a < 3; ++a) {
      double v = in[a][i];
      if (!std::isfinite(v) || std::fabs(v) > config_.plausible_N) {
        flag |= kFlagNonFinite;
        v = last_good_[a];
      } else {
        if (std::fabs(v) >= config_.saturation_N[a]) {
          flag |= kFlagSaturated;
        }
        last_good_[a] = v;
      }
      out_[a][i] = v;
    }
    flags_[i] = flag;
    if (flag != 0) {
      ++counters_.samples_flagged;
      out.nonfinite_samples += (flag & kFlagNonFinite) != 0 ? 1 : 0;
      out.saturated_samples += (flag & kFlagSaturated) != 0 ? 1 : 0;
    }
  }
  counters_.nonfinite_samples += out.nonfinite_samples;
  counters_.saturated_samples += out.saturated_samples;

  counters_.samples_accepted += static_cast<std::int64_t>(n);
  out.verdict = BlockVerdict::kAccepted;
  out.first_sample = next_sample_;
  out.fx_N = {out_[0].get(), n};
  out.fy_N = {out_[1].get(), n};
  out.fz_N = {out_[2].get(), n};
  out.flags = {flags_.get(), n};
  next_sample_ += static_cast<std::int64_t>(n);
  return out;
}

}  // namespace millwatch::monitor
