// The UDP layer under lever-bridge: address syntax, IPv4 and IPv6 loopback, peer identity, ICMP errors.
#include <netinet/in.h>
#include <poll.h>

#include <array>
#include <catch2/catch.hpp>
#include <cerrno>
#include <cstring>

#include "lever/board/udp_socket.hpp"
#include "skip.hpp"

using namespace lever::board;

namespace {

SocketAddress address(const std::string& text) {
  std::string error;
  const auto a = parse_socket_address(text, error);
  INFO(error);
  REQUIRE(a.has_value());
  return *a;
}

// The port the kernel chose for a socket bound to port 0.
SocketAddress bound(const UdpSocket& s) {
  SocketAddress a;
  a.length = sizeof a.storage;
  REQUIRE(::getsockname(s.fd(), reinterpret_cast<sockaddr*>(&a.storage), &a.length) == 0);
  return a;
}

bool wait_readable(int fd, short events = POLLIN) {
  pollfd p{fd, events, 0};
  return ::poll(&p, 1, 1000) == 1 && (p.revents & events);
}

}  // namespace

TEST_CASE("socket addresses: IPv4, IPv6 in brackets, names; mistakes named", "[bridge][udp]") {
  CHECK(address("127.0.0.1:5000").to_string() == "127.0.0.1:5000");
  CHECK(address("[::1]:5001").to_string() == "[::1]:5001");
  CHECK(address("localhost:7").family() != AF_UNSPEC);
  std::string error;
  CHECK_FALSE(parse_socket_address("::1:5000", error));
  CHECK_THAT(error, Catch::Contains("[ADDR]:PORT"));
  CHECK_FALSE(parse_socket_address("127.0.0.1:70000", error));
  CHECK_THAT(error, Catch::Contains("port"));
  CHECK_FALSE(parse_socket_address("127.0.0.1", error));
  CHECK_FALSE(parse_socket_address("[::1]5000", error));
  CHECK(address("127.0.0.1:5000") == address("127.0.0.1:5000"));
  CHECK_FALSE(address("127.0.0.1:5000") == address("127.0.0.2:5000"));
  CHECK_FALSE(address("127.0.0.1:5000") == address("127.0.0.1:5001"));
}

namespace {

void check_loopback(UdpSocket& a, const SocketAddress& local) {
  auto opened_b = UdpSocket::open(local);
  REQUIRE(opened_b.ok());
  auto& b = opened_b.value();
  const std::array<std::uint8_t, 3> payload{1, 2, 3};
  REQUIRE(a.send_to(payload, bound(b)) == UdpStatus::ok);
  REQUIRE(wait_readable(b.fd()));
  std::array<std::uint8_t, 16> buffer{};
  std::size_t size = 0;
  SocketAddress from;
  REQUIRE(b.receive(buffer, size, from) == UdpStatus::ok);
  CHECK(size == 3u);
  CHECK(from == bound(a));
}

}  // namespace

TEST_CASE("datagrams cross IPv4 loopback with the sender's address", "[bridge][udp]") {
  auto opened = UdpSocket::open(address("127.0.0.1:0"));
  REQUIRE(opened.ok());
  check_loopback(opened.value(), address("127.0.0.1:0"));
}

TEST_CASE("datagrams cross IPv6 loopback with the sender's address", "[bridge][udp]") {
  auto opened = UdpSocket::open(address("[::1]:0"));
  if (!opened) LEVER_SKIP("no IPv6 loopback (::1) on this machine: " + opened.error().message);
  check_loopback(opened.value(), address("[::1]:0"));
}

TEST_CASE("a datagram larger than the buffer reports its real size", "[bridge][udp]") {
  auto opened_a = UdpSocket::open(address("127.0.0.1:0"));
  auto opened_b = UdpSocket::open(address("127.0.0.1:0"));
  REQUIRE((opened_a.ok() && opened_b.ok()));
  auto& a = opened_a.value();
  auto& b = opened_b.value();
  std::array<std::uint8_t, 1000> big{};
  REQUIRE(a.send_to(big, bound(b)) == UdpStatus::ok);
  REQUIRE(wait_readable(b.fd()));
  std::array<std::uint8_t, 100> small{};
  std::size_t size = 0;
  SocketAddress from;
  REQUIRE(b.receive(small, size, from) == UdpStatus::ok);
  CHECK(size == 1000u);
}

TEST_CASE("a socket that cannot bind does not exist: the error names the address and the reason", "[bridge][udp]") {
  auto first = UdpSocket::open(address("127.0.0.1:0"));
  REQUIRE(first.ok());
  const auto taken = bound(first.value());
  const auto second = UdpSocket::open(taken);
  REQUIRE_FALSE(second.ok());
  CHECK_THAT(second.error().message, Catch::Contains("bind " + taken.to_string()));
  CHECK_THAT(second.error().message, Catch::Contains("in use"));
  CHECK(second.error().errno_value == EADDRINUSE);
}

TEST_CASE("sending to a closed port comes back as an ICMP error on the error queue", "[bridge][udp]") {
  auto opened_a = UdpSocket::open(address("127.0.0.1:0"));
  REQUIRE(opened_a.ok());
  auto& a = opened_a.value();
  SocketAddress gone;
  {
    auto closed = UdpSocket::open(address("127.0.0.1:0"));
    REQUIRE(closed.ok());
    gone = bound(closed.value());
  }  // the port closes
  const std::array<std::uint8_t, 1> byte{0};
  a.send_to(byte, gone);
  REQUIRE(wait_readable(a.fd(), POLLERR));
  CHECK(a.drain_errors() >= 1);
}
