#pragma once
// The raw blocks' udpm:// group read by millwatchd's sample thread itself, a round's datagrams in
// one recvmmsg: LCM 1.3.1's udpm provider always reads in a receive thread of its own, woken for
// every datagram and waking the reader through a pipe — at 1,000 blocks a second, ~2.9 % of a
// core pinned beside the pipeline (bench/HISTORY.md, the eighty-first stop). The socket is set up
// as LCM's (lcm_udpm.c): bound to the group and port with SO_REUSEADDR, so that LCM's own
// programs (lcm-logger, lcm-spy) on the same group keep receiving, the group joined on any
// interface, its buffer sized by the URL's recv_buf_size. Datagrams are read as they are:
// msgs/lcm_datagram.hpp tells their channel and payload.

#include <netinet/in.h>
#include <sys/socket.h>

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace millwatch::daemon {

/// Where a udpm:// URL listens: "udpm://GROUP:PORT?opt=value&..." (LCM's defaults
/// 239.255.76.67 and 7667 where left out).
struct UdpmEndpoint {
  in_addr group{};
  std::uint16_t port = 7667;
  int recv_buf_size_bytes = 0;  ///< 0: the kernel's default
};

/// The endpoint of a udpm:// URL; nullopt for another provider. A udpm URL whose group, port or
/// recv_buf_size does not read gives nullopt too (LCM itself then refuses it at start).
[[nodiscard]] std::optional<UdpmEndpoint> parse_udpm_url(std::string_view url);

class UdpmReceiver {
 public:
  /// Datagrams read in one call: a 5 ms round at 1,000 blocks a second is 5.
  static constexpr std::size_t kBatch = 16;

  /// Opens, binds and joins. @throws std::runtime_error naming the step and the system's error
  explicit UdpmReceiver(const UdpmEndpoint& endpoint);
  ~UdpmReceiver();
  UdpmReceiver(const UdpmReceiver&) = delete;
  UdpmReceiver& operator=(const UdpmReceiver&) = delete;

  /// Reads the datagrams waiting (at most kBatch) without waiting: how many (0: none).
  std::size_t read_waiting();
  /// The i-th datagram of the last read_waiting() (i < its count); valid until the next one.
  [[nodiscard]] std::span<const std::uint8_t> datagram(std::size_t i) const;
  /// Sleeps until a datagram waits or `timeout` has passed; true when one waits.
  bool wait(std::chrono::milliseconds timeout) const;
  /// The socket's receive buffer as the kernel set it.
  [[nodiscard]] int buffer_bytes() const;

 private:
  static constexpr std::size_t kSlotBytes = 65536;  // more than a UDP payload can be

  int fd_ = -1;
  std::vector<std::uint8_t> buffers_;  // kBatch slots of kSlotBytes
  std::array<iovec, kBatch> iov_{};
  std::array<mmsghdr, kBatch> headers_{};
};

}  // namespace millwatch::daemon
