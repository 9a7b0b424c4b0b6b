#include "daemon/udpm_receiver.hpp"

#include <arpa/inet.h>
#include <poll.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstring>
#include <stdexcept>

namespace millwatch::daemon {
namespace {

std::runtime_error system_error(const std::string& what) {
  return std::runtime_error(what + ": " + std::strerror(errno));
}

template <class T>
bool read_number(std::string_view text, T& out) {
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), out);
  return ec == std::errc() && end == text.data() + text.size();
}

}  // namespace

std::optional<UdpmEndpoint> parse_udpm_url(std::string_view url) {
  constexpr std::string_view kScheme = "udpm://";
  if (!url.starts_with(kScheme)) {
    return std::nullopt;
  }
  url.remove_prefix(kScheme.size());
  const std::size_t query = url.find('?');
  std::string_view network = url.substr(0, query);
  std::string_view options = query == std::string_view::npos ? "" : url.substr(query + 1);
  UdpmEndpoint e;
  std::string group = "239.255.76.67";
  if (!network.empty()) {
    const std::size_t colon = network.find(':');
    group = std::string(network.substr(0, colon));
    if (colon != std::string_view::npos && !read_number(network.substr(colon + 1), e.port)) {
      return std::nullopt;
    }
  }
  if (inet_pton(AF_INET, group.c_str(), &e.group) != 1) {
    return std::nullopt;
  }
  while (!options.empty()) {
    const std::size_t amp = options.find('&');
    const std::string_view option = options.substr(0, amp);
    options = amp == std::string_view::npos ? "" : options.substr(amp + 1);
    constexpr std::string_view kBuffer = "recv_buf_size=";
    if (option.starts_with(kBuffer) &&
        !read_number(option.substr(kBuffer.size()), e.recv_buf_size_bytes)) {
      return std::nullopt;
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
  if (endpoint.recv_buf_size_bytes > 0 &&
      ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &endpoint.recv_buf_size_bytes,
                   sizeof endpoint.recv_buf_size_bytes) < 0) {
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
    const int n = ::recvmmsg(fd_, headers_.data(), kBatch, MSG_DONTWAIT, nullptr);
    if (n >= 0) {
      return static_cast<std::size_t>(n);
    }
    if (errno != EINTR) {
      return 0;  // EAGAIN: none waiting (nothing else is expected of a bound UDP socket)
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
