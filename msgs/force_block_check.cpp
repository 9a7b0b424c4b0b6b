#include "msgs/force_block_check.hpp"

#include <algorithm>
#include <bit>
#include <cstdio>
#include <cstring>

namespace millwatch::messaging {
namespace {

// LCM encodes big-endian: a load and a byte swap (one instruction) on a little-endian machine.
template <class Unsigned>
Unsigned big_endian(const unsigned char* bytes) {
  static_assert(sizeof(Unsigned) == 4 || sizeof(Unsigned) == 8);
  Unsigned v = 0;
  std::memcpy(&v, bytes, sizeof v);
  if constexpr (std::endian::native == std::endian::little) {
    if constexpr (sizeof(Unsigned) == 8) {
      v = __builtin_bswap64(v);
    } else {
      v = __builtin_bswap32(v);
    }
  }
  return v;
}

double big_endian_double(const unsigned char* bytes) {
  return std::bit_cast<double>(big_endian<std::uint64_t>(bytes));
}

std::string hex(std::uint64_t v) {
  char text[24];
  std::snprintf(text, sizeof text, "0x%016llx", static_cast<unsigned long long>(v));
  return text;
}

}  // namespace

ForceBlockCheck check_force_block(const void* data, std::size_t size_bytes,
                                  std::int64_t max_samples) {
  ForceBlockCheck c;
  c.size_bytes = size_bytes;
  c.max_samples = std::clamp<std::int64_t>(max_samples, 0, kForceBlockMaxEncodableSamples);
  if (size_bytes < kForceBlockHeaderBytes) {
    c.problem = ForceBlockProblem::kShorterThanHeader;
    return c;
  }
  const auto* bytes = static_cast<const unsigned char*>(data);
  c.fingerprint = big_endian<std::uint64_t>(bytes);
  c.num_samples = static_cast<std::int32_t>(big_endian<std::uint32_t>(bytes + 32));
  if (c.fingerprint != static_cast<std::uint64_t>(force_block_t::getHash())) {
    c.problem = ForceBlockProblem::kWrongFingerprint;
  } else if (c.num_samples < 0) {
    c.problem = ForceBlockProblem::kNegativeCount;
  } else if (size_bytes != kForceBlockHeaderBytes +
                               kForceBlockSampleBytes * static_cast<std::size_t>(c.num_samples)) {
    // In size_t: 24 · (2³¹ − 1) does not wrap.
    c.problem = ForceBlockProblem::kWrongLength;
  } else if (c.num_samples > c.max_samples) {
    c.problem = ForceBlockProblem::kTooManySamples;
  }
  return c;
}

ForceBlockCheck decode_force_block(const void* data, std::size_t size_bytes,
                                   std::int64_t max_samples, force_block_t& out) {
  ForceBlockCheck c = check_force_block(data, size_bytes, max_samples);
  if (c.ok()) {
    // decode() leaves the arrays as they were for num_samples 0: a reused message must not
    // keep its last samples. (clear() keeps the capacity: no allocation for a reused message.)
    out.fx_N.clear();
    out.fy_N.clear();
    out.fz_N.clear();
    // size_bytes ≤ 36 + 24 · kForceBlockMaxEncodableSamples fits an int.
    const int used = out.decode(data, 0, static_cast<int>(size_bytes));
    if (used != static_cast<int>(size_bytes)) {  // cannot happen after the check
      c.problem = ForceBlockProblem::kWrongLength;
    }
  }
  return c;
}

ForceBlockCheck decode_force_block_into(const void* data, std::size_t size_bytes,
                                        std::int64_t max_samples, ForceBlockHeader& header,
                                        double* fx, double* fy, double* fz) {
  const ForceBlockCheck c = check_force_block(data, size_bytes, max_samples);
  if (!c.ok()) {
    return c;
  }
  const auto* bytes = static_cast<const unsigned char*>(data);
  header.utime = static_cast<std::int64_t>(big_endian<std::uint64_t>(bytes + 8));
  header.seq = static_cast<std::int64_t>(big_endian<std::uint64_t>(bytes + 16));
  header.sample_rate_hz = big_endian_double(bytes + 24);
  header.num_samples = static_cast<std::size_t>(c.num_samples);
  const std::size_t n = header.num_samples;
  const unsigned char* samples = bytes + kForceBlockHeaderBytes;
  for (double* axis : {fx, fy, fz}) {
    for (std::size_t i = 0; i < n; ++i) {
      axis[i] = big_endian_double(samples + 8 * i);
    }
    samples += 8 * n;
  }
  return c;
}

std::string ForceBlockCheck::describe() const {
  const std::string n = std::to_string(num_samples);
  switch (problem) {
    case ForceBlockProblem::kNone:
      return "a whole force_block_t of " + n + " samples";
    case ForceBlockProblem::kShorterThanHeader:
      return std::to_string(size_bytes) + " bytes, fewer than force_block_t's " +
             std::to_string(kForceBlockHeaderBytes) + "-byte header";
    case ForceBlockProblem::kWrongFingerprint:
      return "fingerprint " + hex(fingerprint) + " is not force_block_t's " +
             hex(static_cast<std::uint64_t>(force_block_t::getHash()));
    case ForceBlockProblem::kNegativeCount:
      return "num_samples " + n + " is negative";
    case ForceBlockProblem::kWrongLength:
      return std::to_string(kForceBlockHeaderBytes) + " + " +
             std::to_string(kForceBlockSampleBytes) + " x " + n + " = " +
             std::to_string(static_cast<std::int64_t>(kForceBlockHeaderBytes) +
                            static_cast<std::int64_t>(kForceBlockSampleBytes) * num_samples) +
             " bytes expected for num_samples " + n + ", got " + std::to_string(size_bytes);
    case ForceBlockProblem::kTooManySamples:
      return "num_samples " + n + " is more than the maximum of " + std::to_string(max_samples);
  }
  return "unknown problem";
}

}  // namespace millwatch::messaging
