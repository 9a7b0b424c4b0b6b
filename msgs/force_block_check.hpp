#pragma once
// Checks an encoded millwatch.force_block_t *before* lcm-gen's decode() sees it.
//
// lcm 1.3.1's generated decode() trusts num_samples: its size check computes
// sizeof(double) · num_samples in int, so a large count wraps around the check and the decode
// reads past the buffer; a negative count makes std::vector::resize throw; and it allocates
// whatever the count asks for. Every force_block_t from a log or the network goes through
// decode_force_block() (into a message) or decode_force_block_into() (into arrays) instead.
//
// Layout (msgs/force_block_t.lcm as lcm-gen encodes it, big-endian, no padding):
//   offset  0  int64   fingerprint (force_block_t::getHash())
//           8  int64   utime
//          16  int64   seq
//          24  double  sample_rate_hz
//          32  int32   num_samples = n
//          36  double  fx_N[n], then fy_N[n], then fz_N[n]
//   total   36 + 24·n bytes

#include <cstddef>
#include <cstdint>
#include <string>

#include "millwatch/force_block_t.hpp"

namespace millwatch::messaging {

/// Bytes of an encoded force_block_t before its samples.
inline constexpr std::size_t kForceBlockHeaderBytes = 36;
/// Bytes per sample of an encoded force_block_t (fx, fy, fz).
inline constexpr std::size_t kForceBlockSampleBytes = 24;
/// The most samples a force_block_t can hold for lcm-gen's int-sized buffers.
inline constexpr std::int64_t kForceBlockMaxEncodableSamples =
    (std::int64_t{2147483647} - static_cast<std::int64_t>(kForceBlockHeaderBytes)) /
    static_cast<std::int64_t>(kForceBlockSampleBytes);

enum class ForceBlockProblem {
  kNone,
  kShorterThanHeader,  ///< fewer bytes than the fixed fields
  kWrongFingerprint,   ///< another type (or garbage)
  kNegativeCount,      ///< num_samples < 0
  kWrongLength,        ///< the length does not match num_samples
  kTooManySamples,     ///< the length matches, but num_samples is above the maximum
};

/// What check_force_block() found; describe() says it in words.
struct ForceBlockCheck {
  ForceBlockProblem problem = ForceBlockProblem::kNone;
  std::size_t size_bytes = 0;     ///< length of the encoded message
  std::int64_t num_samples = 0;   ///< declared count (when the header was there to read)
  std::int64_t max_samples = 0;   ///< the maximum it was checked against
  std::uint64_t fingerprint = 0;  ///< the message's (when the header was there to read)

  [[nodiscard]] bool ok() const { return problem == ForceBlockProblem::kNone; }
  /// E.g. "36 + 24 x 40 = 996 bytes expected for num_samples 40, got 1000".
  [[nodiscard]] std::string describe() const;
};

/// Checks that `data` (`size_bytes` long) is a whole force_block_t of at most `max_samples`
/// samples (clamped to kForceBlockMaxEncodableSamples). Reads only the header; never allocates.
ForceBlockCheck check_force_block(const void* data, std::size_t size_bytes,
                                  std::int64_t max_samples);

/// check_force_block(), then (only if it passed) decodes into `out`. A message that passes the
/// check always decodes; `out` is untouched when it does not pass.
ForceBlockCheck decode_force_block(const void* data, std::size_t size_bytes,
                                   std::int64_t max_samples, force_block_t& out);

/// A force_block_t's fixed fields, as decode_force_block_into() gives them.
struct ForceBlockHeader {
  std::int64_t utime = 0;
  std::int64_t seq = 0;
  double sample_rate_hz = 0.0;
  std::size_t num_samples = 0;
};

/// check_force_block(), then (only if it passed) decodes the fixed fields into `header` and the
/// samples straight into `fx`, `fy`, `fz`, which hold at least `max_samples` each: no message
/// object in between (the daemon decodes into its queue's slot). Untouched when it does not pass.
ForceBlockCheck decode_force_block_into(const void* data, std::size_t size_bytes,
                                        std::int64_t max_samples, ForceBlockHeader& header,
                                        double* fx, double* fy, double* fz);

}  // namespace millwatch::messaging
