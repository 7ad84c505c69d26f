#include "lever/board/udp_socket.hpp"

#include <arpa/inet.h>
#include <linux/errqueue.h>
#include <netdb.h>
#include <netinet/in.h>

#include <cerrno>
#include <cstring>

namespace lever::board {

std::string SocketAddress::to_string() const {
  char host[INET6_ADDRSTRLEN] = {};
  if (family() == AF_INET) {
    const auto* a = reinterpret_cast<const sockaddr_in*>(&storage);
    ::inet_ntop(AF_INET, &a->sin_addr, host, sizeof host);
    return std::string(host) + ":" + std::to_string(ntohs(a->sin_port));
  }
  if (family() == AF_INET6) {
    const auto* a = reinterpret_cast<const sockaddr_in6*>(&storage);
    ::inet_ntop(AF_INET6, &a->sin6_addr, host, sizeof host);
    return "[" + std::string(host) + "]:" + std::to_string(ntohs(a->sin6_port));
  }
  return "?";
}

bool SocketAddress::operator==(const SocketAddress& other) const noexcept {
  if (family() != other.family()) return false;
  if (family() == AF_INET) {
    const auto* a = reinterpret_cast<const sockaddr_in*>(&storage);
    const auto* b = reinterpret_cast<const sockaddr_in*>(&other.storage);
    return a->sin_port == b->sin_port && a->sin_addr.s_addr == b->sin_addr.s_addr;
  }
  if (family() == AF_INET6) {
    const auto* a = reinterpret_cast<const sockaddr_in6*>(&storage);
    const auto* b = reinterpret_cast<const sockaddr_in6*>(&other.storage);
    return a->sin6_port == b->sin6_port && std::memcmp(&a->sin6_addr, &b->sin6_addr, sizeof a->sin6_addr) == 0;
  }
  return false;
}

std::optional<SocketAddress> parse_socket_address(const std::string& text, std::string& error) {
  std::string host, port;
  if (!text.empty() && text.front() == '[') {
    const auto close = text.find(']');
    if (close == std::string::npos || close + 1 >= text.size() || text[close + 1] != ':') {
      error = "'" + text + "': expected [IPv6]:PORT";
      return std::nullopt;
    }
    host = text.substr(1, close - 1);
    port = text.substr(close + 2);
  } else {
    const auto colon = text.rfind(':');
    if (colon == std::string::npos || text.find(':') != colon) {
      error = "'" + text + "': expected HOST:PORT (write IPv6 addresses as [ADDR]:PORT)";
      return std::nullopt;
    }
    host = text.substr(0, colon);
    port = text.substr(colon + 1);
  }
  // At most five digits before stoul, which would throw on a number beyond unsigned long.
  if (host.empty() || port.empty() || port.size() > 5 || port.find_first_not_of("0123456789") != std::string::npos ||
      std::stoul(port) > 65535) {
    error = "'" + text + "': expected HOST:PORT with a port from 0 to 65535";
    return std::nullopt;
  }
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_DGRAM;
  hints.ai_flags = AI_NUMERICSERV;
  addrinfo* found = nullptr;
  if (const int rc = ::getaddrinfo(host.c_str(), port.c_str(), &hints, &found); rc != 0) {
    error = "'" + text + "': " + ::gai_strerror(rc);
    return std::nullopt;
  }
  SocketAddress address;
  std::memcpy(&address.storage, found->ai_addr, found->ai_addrlen);
  address.length = found->ai_addrlen;
  ::freeaddrinfo(found);
  return address;
}

UdpStatus UdpSocket::fail(int err) {
  errno_ = err;
  error_ = std::strerror(err);
  switch (err) {
    case EAGAIN:
      return UdpStatus::would_block;
    case ECONNREFUSED:
    case EHOSTUNREACH:
    case ENETUNREACH:
    case ENETDOWN:
      return UdpStatus::unreachable;
    default:
      return UdpStatus::error;
  }
}

Result<UdpSocket> UdpSocket::open(const SocketAddress& local) {
  UniqueFd fd(::socket(local.family(), SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0));
  if (!fd) {
    const int err = errno;
    return Error{std::string("socket: ") + std::strerror(err), err};
  }
  // Without IP_RECVERR an unconnected socket never learns that its peer is unreachable.
  const int on = 1;
  if (local.family() == AF_INET6) {
    ::setsockopt(fd.get(), IPPROTO_IPV6, IPV6_RECVERR, &on, sizeof on);
  } else {
    ::setsockopt(fd.get(), IPPROTO_IP, IP_RECVERR, &on, sizeof on);
  }
  if (::bind(fd.get(), local.get(), local.length) < 0) {
    const int err = errno;
    return Error{"bind " + local.to_string() + ": " + std::strerror(err), err};
  }
  return UdpSocket(std::move(fd));
}

UdpStatus UdpSocket::send_to(std::span<const std::uint8_t> data, const SocketAddress& to) {
  const ssize_t n = ::sendto(fd_.get(), data.data(), data.size(), 0, to.get(), to.length);
  if (n < 0) return fail(errno);
  return UdpStatus::ok;
}

UdpStatus UdpSocket::receive(std::span<std::uint8_t> buffer, std::size_t& size, SocketAddress& from) {
  from.length = sizeof from.storage;
  // MSG_TRUNC: the real length even when the buffer is smaller, so oversized datagrams are recognized.
  const ssize_t n = ::recvfrom(fd_.get(), buffer.data(), buffer.size(), MSG_TRUNC,
                               reinterpret_cast<sockaddr*>(&from.storage), &from.length);
  if (n < 0) return fail(errno);
  size = static_cast<std::size_t>(n);
  return UdpStatus::ok;
}

int UdpSocket::drain_errors() {
  int errors = 0;
  for (int i = 0; i < 64; ++i) {
    std::uint8_t payload[512];
    alignas(cmsghdr) char control[512];
    iovec iov{payload, sizeof payload};
    msghdr msg{};
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = control;
    msg.msg_controllen = sizeof control;
    if (::recvmsg(fd_.get(), &msg, MSG_ERRQUEUE) < 0) break;
    ++errors;
  }
  return errors;
}

}  // namespace lever::board
