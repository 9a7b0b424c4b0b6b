#pragma once
// First stage of the pipeline: checks each block and each sample, counts what is wrong, and
// hands on a clean block. Nothing is thrown; everything is counted.
//
//  - malformed block (channels of unequal length, empty, too long, wrong sample rate): rejected;
//    when it came at its expected time, its slot is a gap before the next block (counted once),
//    cut short by a block that comes within it (its length or rate said more than it lasted);
//    when later (or before a reload's successor has a block), the stream's time stays (a corrupt
//    utime must refuse no good block after it), and a gap over it does not count it again
//  - block whose utime is beyond ±kMaxAbsUtime_us (a corrupt time: a block from the network can
//    carry anything): rejected, with no effect on the stream's timing
//  - block older than expected (out of order, duplicate): rejected
//  - block later than expected: the missing samples are counted as dropped and reported as a
//    gap so that downstream stages can restart
//  - non-finite or implausible (|F| > plausible_N) sample: replaced by the channel's last good
//    value, flagged
//  - sample at or beyond the channel's saturation level (charge-amplifier range): kept, flagged
// Sample time is kept as a sample index from the first block (utime of the first block + index
// / rate), so that gaps keep later samples at their true time. With every accepted utime within
// ±kMaxAbsUtime_us, no time or index computed here can overflow.

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/monitor/rejected_spans.hpp"
#include "core/monitor/sample_block.hpp"

namespace millwatch::monitor {

/// Largest |reading| a dynamometer can have measured, N: beyond it a value is corrupt, not a
/// force (InputCheckConfig::plausible_N's default).
inline constexpr double kPlausibleForce_N = 1e6;

/// Largest |utime| a block may carry, µs: 2⁵³ µs ≈ 285 years either side of the epoch, where a
/// utime still converts to and from double exactly. Beyond it a time is corrupt.
inline constexpr std::int64_t kMaxAbsUtime_us = std::int64_t{1} << 53;
/// Whether a block's time is within ±kMaxAbsUtime_us (not a corrupt one).
inline bool plausible_utime(std::int64_t utime_us) {
  return utime_us >= -kMaxAbsUtime_us && utime_us <= kMaxAbsUtime_us;
}

struct InputCheckConfig {
  double sample_rate_hz = 50000.0;
  /// |reading| at or above this is saturated (the charge amplifier's range), per channel, N.
  std::array<double, 3> saturation_N = {std::numeric_limits<double>::infinity(),
                                        std::numeric_limits<double>::infinity(),
                                        std::numeric_limits<double>::infinity()};
  /// A reading beyond this is no force a dynamometer can have measured (a corrupt value):
  /// treated like a non-finite one.
  double plausible_N = kPlausibleForce_N;
  /// Timing mismatch tolerated before a block counts as a gap or out of order, in samples.
  double tolerance_samples = 0.5;
  std::size_t max_block_samples = 65536;
};

struct InputCounters {
  std::int64_t samples_in = 0;        ///< samples received in blocks (accepted or not)
  std::int64_t samples_accepted = 0;  ///< samples handed on
  std::int64_t samples_dropped = 0;   ///< rejected blocks' samples plus samples missing in gaps
  std::int64_t samples_flagged = 0;   ///< handed on but marked bad
  std::int64_t nonfinite_samples = 0;
  std::int64_t saturated_samples = 0;
  std::int64_t gaps = 0;
  std::int64_t out_of_order_blocks = 0;
  std::int64_t blocks_rejected = 0;  ///< malformed, out of order or with a corrupt utime
};

enum class BlockVerdict { kAccepted, kRejected };

/// Sample flags (bit set).
enum SampleFlag : std::uint8_t { kFlagNonFinite = 1, kFlagSaturated = 2 };

struct CheckedBlock {
  BlockVerdict verdict = BlockVerdict::kRejected;
  std::int64_t first_sample = 0;  ///< index of the block's first sample since the stream began
  std::int64_t gap_samples = 0;   ///< samples missing just before this block
  std::span<const double> fx_N, fy_N, fz_N;
  std::span<const std::uint8_t> flags;
  std::int64_t nonfinite_samples = 0;  ///< samples flagged kFlagNonFinite in this block
  std::int64_t saturated_samples = 0;  ///< samples flagged kFlagSaturated in this block
  /// Why a block was rejected or what was wrong: static text, or the check's own (valid until
  /// it takes its next block).
  std::string_view problem;
};

class InputCheck {
 public:
  explicit InputCheck(const InputCheckConfig& config);

  /// Checks a block; the returned spans point into this stage's buffers until the next call, or,
  /// when no sample needed replacing, into the block itself (valid as long as the block).
  CheckedBlock check(const SampleBlock& block);

  /// check() in two steps, for a caller that tests the samples in a pass of its own (the
  /// conditioner's filter: Conditioner::filter_checked): check_time() does all but the samples'
  /// test (the block's length, rate and time, a gap before it); for a block it did not reject,
  /// check_samples() must follow at once, given what it gave and whether every sample is known
  /// to be within sample_limits() — it then tests none (else it tests and replaces as check()
  /// does). The two give what check() gives.
  CheckedBlock check_time(const SampleBlock& block);
  CheckedBlock check_samples(const SampleBlock& block, CheckedBlock timed, bool known_within);
  /// A sample of input channel a (fx, fy, fz) is handed on as it is when |x| ≤ limit[a] (a NaN
  /// is not): plausible and below the channel's saturation.
  [[nodiscard]] const std::array<double, 3>& sample_limits() const { return limits_; }

  [[nodiscard]] const InputCounters& counters() const { return counters_; }
  /// utime (µs) of sample index n.
  [[nodiscard]] std::int64_t utime_of(std::int64_t sample) const;
  /// Index of the next sample expected.
  [[nodiscard]] std::int64_t next_sample() const { return next_sample_; }
  /// Forget the stream's timing (the next block starts a new stream); counters are kept.
  void restart();
  /// The utime (µs) the next sample is expected at; empty before the first block (unless
  /// continue_after() said).
  [[nodiscard]] std::optional<std::int64_t> next_utime() const;
  /// This check's stream goes on from one that expected its next sample at `next_utime_us` (a
  /// reload's successor, at the same sample rate): a first block later than that counts the
  /// samples missing before it as a gap (reported in its CheckedBlock), although the stream's
  /// timing starts at it; an earlier one (its predecessor had it) is rejected as out of order.
  void continue_after(std::int64_t next_utime_us) { continued_from_utime_us_ = next_utime_us; }
  /// continue_after() from a predecessor's stream at the same sample rate (nothing if it had
  /// none), with what its rejected blocks ahead of that time covered (counted already) and the
  /// slot of one it rejected at its time just before (a gap before this check's first block).
  void continue_after(const InputCheck& predecessor);

 private:
  CheckedBlock reject(const SampleBlock& block, std::string_view why);
  /// µs that `samples` samples take at `rate_hz` (a rejected block's own rate, when plausible).
  [[nodiscard]] std::int64_t duration_us(std::int64_t samples, double rate_hz) const;
  /// Of the `missing` samples before a block at `utime_us` (due at `expected_us`), those that
  /// rejected blocks covered — counted already.
  [[nodiscard]] std::int64_t counted_already(std::int64_t missing, std::int64_t expected_us,
                                             std::int64_t utime_us) const;

  /// With a hole open, how many samples after its start `utime_us` lies, when at or after it
  /// (within the tolerance); else none.
  [[nodiscard]] std::optional<double> samples_into_hole(std::int64_t utime_us) const;

  /// How many samples later than `expected_utime_us` a block at `utime_us` comes (< 0: earlier).
  [[nodiscard]] double samples_late(std::int64_t utime_us, std::int64_t expected_utime_us) const;

  InputCheckConfig config_;
  std::array<double, 3> limits_{};  // sample_limits()
  InputCounters counters_;
  bool started_ = false;
  std::int64_t start_utime_us_ = 0;  // utime of sample start_sample_
  std::int64_t start_sample_ = 0;    // first sample of the stream (since the last restart)
  std::int64_t next_sample_ = 0;
  std::int64_t hole_samples_ = 0;         // slot of a block rejected at its expected time
  std::int64_t hole_start_utime_us_ = 0;  // where that slot (or a run of them) began
  std::string rate_problem_;      // a block's rate refused, with both rates (CheckedBlock::problem)
  RejectedSpans rejected_ahead_;  // blocks rejected at or after the time expected
  std::optional<std::int64_t> continued_from_utime_us_;  // continue_after(), until the first block
  std::array<double, 3> last_good_{};
  // max_block_samples each, left uninitialised (not 1.5 MiB zeroed at construction for the
  // default 65,536): a page is touched (faulted in) only when a block reaches it — flags_ by
  // every block, out_ by a block with a sample to flag or replace.
  std::array<std::unique_ptr<double[]>, 3> out_;
  std::unique_ptr<std::uint8_t[]> flags_;
};

}  // namespace millwatch::monitor
