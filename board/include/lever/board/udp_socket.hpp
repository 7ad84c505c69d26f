#pragma once
// A non-blocking UDP socket bound to one local address, IPv4 or IPv6, with socket addresses parsed from
// "HOST:PORT" (IPv4, a name) or "[IPv6]:PORT".
#include <sys/socket.h>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <utility>

#include "lever/board/result.hpp"
#include "lever/board/unique_fd.hpp"

namespace lever::board {

struct SocketAddress {
  sockaddr_storage storage{};
  socklen_t length = 0;

  int family() const noexcept { return storage.ss_family; }
  const sockaddr* get() const noexcept { return reinterpret_cast<const sockaddr*>(&storage); }
  std::string to_string() const;
  // Same family, address and port.
  bool operator==(const SocketAddress& other) const noexcept;
};

// "127.0.0.1:5000", "localhost:5000", "[::1]:5000". On failure returns nullopt and sets `error`.
std::optional<SocketAddress> parse_socket_address(const std::string& text, std::string& error);

enum class UdpStatus : std::uint8_t { ok, would_block, unreachable, error };

class UdpSocket {
 public:
  // A socket bound to `local`, or why not (naming the call and the address). No half-open sockets.
  static Result<UdpSocket> open(const SocketAddress& local);
  UdpSocket(UdpSocket&&) noexcept = default;
  UdpSocket& operator=(UdpSocket&&) noexcept = default;
  UdpSocket(const UdpSocket&) = delete;
  UdpSocket& operator=(const UdpSocket&) = delete;

  int fd() const noexcept { return fd_.get(); }
  const std::string& error_text() const noexcept { return error_; }
  int last_errno() const noexcept { return errno_; }

  UdpStatus send_to(std::span<const std::uint8_t> data, const SocketAddress& to);
  // One datagram into `buffer`; `size` is its real length (may exceed the buffer: then it was truncated).
  UdpStatus receive(std::span<std::uint8_t> buffer, std::size_t& size, SocketAddress& from);
  // ICMP errors about earlier sends (port or host unreachable), which an unconnected socket only reports through
  // its error queue (IP_RECVERR; poll() says POLLERR). Drains the queue and returns how many there were.
  int drain_errors();

 private:
  explicit UdpSocket(UniqueFd fd) noexcept : fd_(std::move(fd)) {}
  UdpStatus fail(int err);
  UniqueFd fd_;
  int errno_ = 0;
  std::string error_;
};

}  // namespace lever::board
