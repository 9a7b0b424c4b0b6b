#include "msgs/lcm_datagram.hpp"

#include <algorithm>
#include <cstring>

namespace millwatch::messaging {
namespace {

std::uint32_t big_endian_32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         std::uint32_t{p[3]};
}

std::uint16_t big_endian_16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>((p[0] << 8) | p[1]);
}

/// The NUL-terminated channel at the start of `rest`, or false if it has no NUL within LCM's
/// limit.
bool read_channel(std::span<const std::uint8_t> rest, std::string_view& channel,
                  std::span<const std::uint8_t>& after) {
  const std::size_t limit = std::min(rest.size(), kLcmMaxChannelBytes + 1);
  const void* nul = std::memchr(rest.data(), 0, limit);
  if (nul == nullptr) {
    return false;
  }
  const auto length = static_cast<std::size_t>(static_cast<const std::uint8_t*>(nul) - rest.data());
  channel = std::string_view(reinterpret_cast<const char*>(rest.data()), length);
  after = rest.subspan(length + 1);
  return true;
}

}  // namespace

LcmDatagram parse_lcm_datagram(std::span<const std::uint8_t> bytes) {
  LcmDatagram d;
  constexpr std::size_t kShortHeader = 8;
  constexpr std::size_t kFragmentHeader = 20;
  if (bytes.size() < kShortHeader) {
    return d;
  }
  const std::uint32_t magic = big_endian_32(bytes.data());
  d.sequence = big_endian_32(bytes.data() + 4);
  if (magic == kLcmMagicShort) {
    if (read_channel(bytes.subspan(kShortHeader), d.channel, d.payload)) {
      d.kind = LcmDatagram::Kind::kShort;
    }
    return d;
  }
  if (magic != kLcmMagicFragment || bytes.size() < kFragmentHeader) {
    return d;
  }
  d.message_bytes = big_endian_32(bytes.data() + 8);
  d.fragment = big_endian_16(bytes.data() + 16);
  d.fragments = big_endian_16(bytes.data() + 18);
  d.payload = bytes.subspan(kFragmentHeader);
  if (d.fragment == 0 && !read_channel(d.payload, d.channel, d.payload)) {
    return d;
  }
  d.kind = LcmDatagram::Kind::kFragment;
  return d;
}

}  // namespace millwatch::messaging
