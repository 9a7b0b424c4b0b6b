#include "daemon/udpm_receiver.hpp"

#include <arpa/inet.h>
#include <poll.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace millwatch::daemon {
namespace {

std::runtime_error system_error(const std::string& what) {
  return std::runtime_error(what + ": " + std::strerror(errno));
}

/// A number as LCM reads it (strtol, base 0: decimal, 0x hex or 0 octal): its leading digits;
/// false when there are none.
bool read_like_lcm(const std::string& text, long& out) {
  char* end = nullptr;
  errno = 0;
  out = std::strtol(text.c_str(), &end, 0);
  return end != text.c_str() && errno == 0;
}

}  // namespace

std::optional<UdpmEndpoint> parse_udpm_url(std::string_view url) {
  // As lcm_udpm.c's parse_mc_addr_and_port and its options: the group by inet_aton, the port
  // and recv_buf_size by strtol, so that both read a URL alike.
  constexpr std::string_view kScheme = "udpm://";
  if (!url.starts_with(kScheme)) {
    return std::nullopt;
  }
  url.remove_prefix(kScheme.size());
  const std::size_t query = url.find('?');
  std::string_view network = url.substr(0, query);
  std::string_view options = query == std::string_view::npos ? "" : url.substr(query + 1);
  if (network.empty()) {
    network = "239.255.76.67:7667";
  }
  UdpmEndpoint e;
  const std::size_t colon = network.find(':');
  if (inet_aton(std::string(network.substr(0, colon)).c_str(), &e.group) == 0) {
    return std::nullopt;
  }
  long port = 0;
  if (colon != std::string_view::npos) {
    if (!read_like_lcm(std::string(network.substr(colon + 1)), port) || port < 0 || port > 65535) {
      return std::nullopt;
    }
    e.port = static_cast<std::uint16_t>(port);
  }
  while (!options.empty()) {
    const std::size_t amp = options.find('&');
    const std::string_view option = options.substr(0, amp);
    options = amp == std::string_view::npos ? "" : options.substr(amp + 1);
    constexpr std::string_view kBuffer = "recv_buf_size=";
    long bytes = 0;
    if (option.starts_with(kBuffer) &&
        read_like_lcm(std::string(option.substr(kBuffer.size())), bytes) && bytes > 0 &&
        bytes <= std::numeric_limits<int>::max()) {
      e.recv_buf_size_bytes = static_cast<int>(bytes);  // LCM warns of a bad one and asks none
    }
  }
  return e;
}

UdpmReceiver::UdpmReceiver(const UdpmEndpoint& endpoint) : buffers_(kBatch * kSlotBytes) {
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) {
    throw system_error("cannot open a UDP socket");
  }
  const auto fail = [this](const std::string& what) {
    const auto e = system_error(what);
    ::close(fd_);
    return e;
  };
  const int one = 1;
  if (::setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) < 0) {
    throw fail("cannot set SO_REUSEADDR");
  }
  const int buffer_bytes =
      endpoint.recv_buf_size_bytes > 0 ? endpoint.recv_buf_size_bytes : kDefaultBufferBytes;
  if (::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &buffer_bytes, sizeof buffer_bytes) < 0) {
    throw fail("cannot set the receive buffer (recv_buf_size)");
  }
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr = endpoint.group;
  address.sin_port = htons(endpoint.port);
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&address), sizeof address) < 0) {
    throw fail("cannot bind to the udpm group's port " + std::to_string(endpoint.port));
  }
  ip_mreq membership{};
  membership.imr_multiaddr = endpoint.group;
  membership.imr_interface.s_addr = htonl(INADDR_ANY);
  if (::setsockopt(fd_, IPPROTO_IP, IP_ADD_MEMBERSHIP, &membership, sizeof membership) < 0) {
    throw fail("cannot join the udpm multicast group");
  }
  // The kernel's count of datagrams it dropped on this socket (its buffer full), on each
  // datagram read: LCM's thread drained the socket into a queue of its own, and a socket left
  // to fill must say when it overflowed. Without it (an old kernel) the losses show as gaps only.
  counts_drops_ = ::setsockopt(fd_, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof one) == 0;
  for (std::size_t i = 0; i < kBatch; ++i) {
    iov_[i] = {buffers_.data() + i * kSlotBytes, kSlotBytes};
    headers_[i].msg_hdr.msg_iov = &iov_[i];
    headers_[i].msg_hdr.msg_iovlen = 1;
  }
}

UdpmReceiver::~UdpmReceiver() {
  ::close(fd_);
}

std::size_t UdpmReceiver::read_waiting() {
  for (;;) {
    for (std::size_t i = 0; i < kBatch; ++i) {  // the kernel shortens it to what it wrote
      headers_[i].msg_hdr.msg_control = control_[i].data();
      headers_[i].msg_hdr.msg_controllen = control_[i].size();
    }
    const int n = ::recvmmsg(fd_, headers_.data(), kBatch, MSG_DONTWAIT, nullptr);
    if (n >= 0) {
      note_drops(static_cast<std::size_t>(n));
      return static_cast<std::size_t>(n);
    }
    if (errno == EAGAIN || errno == EWOULDBLOCK) {
      return 0;  // none waiting
    }
    if (errno != EINTR) {
      // Not expected of a bound UDP socket (ENOMEM): said, and the round ends as if empty.
      if (++errors_ <= 10) {
        spdlog::warn("reading the udpm group: {}", std::strerror(errno));
      }
      return 0;
    }
  }
}

void UdpmReceiver::note_drops(std::size_t read) {
  // SO_RXQ_OVFL: a uint32 count, the socket's since it opened, as the datagram was queued
  // (absent while it is 0); the latest datagram's is the latest count.
  for (std::size_t i = 0; i < read; ++i) {
    msghdr& h = headers_[i].msg_hdr;
    for (cmsghdr* c = CMSG_FIRSTHDR(&h); c != nullptr; c = CMSG_NXTHDR(&h, c)) {
      if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL &&
          c->cmsg_len >= CMSG_LEN(sizeof(std::uint32_t))) {
        std::uint32_t count = 0;
        std::memcpy(&count, CMSG_DATA(c), sizeof count);
        dropped_ += static_cast<std::uint32_t>(count - last_drop_count_);  // modulo 2³²
        last_drop_count_ = count;
      }
    }
  }
}

std::span<const std::uint8_t> UdpmReceiver::datagram(std::size_t i) const {
  return {buffers_.data() + i * kSlotBytes, headers_[i].msg_len};
}

bool UdpmReceiver::wait(std::chrono::milliseconds timeout) const {
  pollfd p{fd_, POLLIN, 0};
  return ::poll(&p, 1, static_cast<int>(timeout.count())) > 0 && (p.revents & POLLIN) != 0;
}

int UdpmReceiver::buffer_bytes() const {
  int bytes = 0;
  socklen_t length = sizeof bytes;
  ::getsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &bytes, &length);
  return bytes;
}

}  // namespace millwatch::daemon
