#pragma once
// One UDP datagram of LCM's udpm transport, read without LCM (daemon/udpm_receiver.hpp takes a
// round's datagrams in one recvmmsg; LCM 1.3.1 reads each in its receive thread).
//
// The wire format (lcm/udpm_util.h and lcm_udpm.c's publish, big-endian):
//   short message, when channel + 1 + payload ≤ 65,499 bytes:
//     uint32 magic "LC02", uint32 sequence number, channel (NUL-terminated), payload
//   a fragment of a longer one:
//     uint32 magic "LC03", uint32 sequence number, uint32 message size, uint32 fragment offset,
//     uint16 fragment number, uint16 fragments in the message,
//     then (fragment 0 only) the channel (NUL-terminated), then that fragment's payload
// A force_block_t of at most 2,000 samples (48,036 bytes, msgs/force_block_t.lcm) is always a
// short message.

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

namespace millwatch::messaging {

inline constexpr std::uint32_t kLcmMagicShort = 0x4c433032;     // "LC02"
inline constexpr std::uint32_t kLcmMagicFragment = 0x4c433033;  // "LC03"
/// LCM's limit on a channel name (lcm.h's LCM_MAX_CHANNEL_NAME_LENGTH).
inline constexpr std::size_t kLcmMaxChannelBytes = 63;
/// The largest UDP payload: a buffer this long never truncates a datagram.
inline constexpr std::size_t kUdpMaxDatagramBytes = 65507;

struct LcmDatagram {
  enum class Kind {
    kShort,     ///< a whole message: channel and payload
    kFragment,  ///< part of a longer message; `channel` only in fragment 0, else empty
    kNotLcm,    ///< no LCM magic, cut short, or a channel without its NUL or too long
  };
  Kind kind = Kind::kNotLcm;
  std::uint32_t sequence = 0;
  std::string_view channel;
  std::span<const std::uint8_t> payload;  ///< the message (short) or this fragment's part
  std::uint32_t message_bytes = 0;        ///< a fragment's whole message size
  std::uint16_t fragment = 0;             ///< a fragment's number
  std::uint16_t fragments = 0;            ///< fragments in its message
};

/// Reads `bytes` as one udpm datagram; views into `bytes`, never allocates.
[[nodiscard]] LcmDatagram parse_lcm_datagram(std::span<const std::uint8_t> bytes);

}  // namespace millwatch::messaging
