#pragma once
// The raw blocks' udpm:// group read by millwatchd's sample thread itself, a round's datagrams
// (up to kBatch) in one recvmmsg: LCM 1.3.1's udpm provider always reads in a receive thread of
// its own, woken for every datagram and waking the reader through a pipe — at 1,000 blocks a
// second 1.1–4.9 % of a core beside the pipeline, pinned to one core (bench/HISTORY.md, the
// eighty-first stop). The socket is set up as LCM's provider sets up its own (lcm_udpm.c):
// SO_REUSEADDR, so that LCM's programs on the same group and port (lcm-logger, lcm-spy) keep
// receiving; bound to the group's address, as LCM ≥ 1.4 binds it (1.3.1 binds any address and
// also hears other groups sent to the port); the group joined on any interface. Its kernel
// buffer is the URL's recv_buf_size, or kDefaultBufferBytes: no receive thread drains the
// socket into a queue any more, so the buffer alone holds what comes while the sample thread
// is busy (the kernel caps it at net.core.rmem_max; millwatchd logs what it got). Datagrams are
// read as they are: msgs/lcm_datagram.hpp tells their channel and payload.

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

/// The endpoint of a udpm:// URL, read as LCM reads it; nullopt for another provider, or a group
/// or port LCM refuses too (it then fails at start). A recv_buf_size that does not read is left
/// out, as LCM leaves it out (with a warning of its own).
[[nodiscard]] std::optional<UdpmEndpoint> parse_udpm_url(std::string_view url);

class UdpmReceiver {
 public:
  /// Datagrams read in one call: a 5 ms round at 1,000 blocks a second is 5.
  static constexpr std::size_t kBatch = 16;
  /// The kernel buffer asked for when the URL asks none: 4 MiB, about half a second of
  /// 333.3 kHz blocks (LCM's default is the kernel's, ~208 KiB: some 20 ms of them).
  static constexpr int kDefaultBufferBytes = 4 << 20;

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
  /// Datagrams of any channel the kernel dropped on this socket, its buffer full (SO_RXQ_OVFL;
  /// 0 where the kernel does not count them): the count rides on each datagram queued after a
  /// drop, so drops are known once the next datagram that came after them is read.
  [[nodiscard]] std::uint64_t dropped_datagrams() const { return dropped_; }
  /// Whether the kernel counts them (SO_RXQ_OVFL was taken).
  [[nodiscard]] bool counts_drops() const { return counts_drops_; }

 private:
  static constexpr std::size_t kSlotBytes = 65536;  // more than a UDP payload can be

  void note_drops(std::size_t read);

  int fd_ = -1;
  int errors_ = 0;                     // reads that failed otherwise than empty
  std::vector<std::uint8_t> buffers_;  // kBatch slots of kSlotBytes
  std::array<iovec, kBatch> iov_{};
  std::array<mmsghdr, kBatch> headers_{};
  struct alignas(cmsghdr) Control : std::array<char, CMSG_SPACE(sizeof(std::uint32_t))> {};
  std::array<Control, kBatch> control_{};  // each datagram's drop count
  bool counts_drops_ = false;
  std::uint32_t last_drop_count_ = 0;
  std::uint64_t dropped_ = 0;
};

}  // namespace millwatch::daemon
