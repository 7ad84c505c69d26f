#include "tcp_listener.hpp"

#include <netdb.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <cerrno>
#include <cstring>

namespace lever::hil::devices {

board::Result<TcpListener> listen_tcp(const std::string& host, int port) {
  const std::string where = "gauge server: tcp " + host + " port " + std::to_string(port);
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICHOST | AI_NUMERICSERV;
  addrinfo* found = nullptr;
  if (const int rc = ::getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &found); rc != 0) {
    return board::Error{where + ": " + ::gai_strerror(rc) + " (the host must be a numeric address)", EINVAL};
  }
  const auto fail = [&](const char* step) {
    const int err = errno;
    ::freeaddrinfo(found);
    return board::Error{where + ": " + step + ": " + std::strerror(err), err};
  };
  TcpListener listener;
  listener.fd.reset(::socket(found->ai_family, SOCK_STREAM | SOCK_CLOEXEC, 0));
  if (!listener.fd) return fail("socket");
  // A HIL restarted at once must get its port back while the old connections sit in TIME_WAIT.
  const int on = 1;
  if (::setsockopt(listener.fd.get(), SOL_SOCKET, SO_REUSEADDR, &on, sizeof on) != 0) return fail("SO_REUSEADDR");
  if (::bind(listener.fd.get(), found->ai_addr, found->ai_addrlen) != 0) return fail("bind");
  if (::listen(listener.fd.get(), 4) != 0) return fail("listen");
  ::freeaddrinfo(found);

  sockaddr_storage bound{};
  socklen_t length = sizeof bound;
  if (::getsockname(listener.fd.get(), reinterpret_cast<sockaddr*>(&bound), &length) != 0) {
    const int err = errno;
    return board::Error{where + ": getsockname: " + std::strerror(err), err};
  }
  listener.port = bound.ss_family == AF_INET6 ? ntohs(reinterpret_cast<const sockaddr_in6*>(&bound)->sin6_port)
                                              : ntohs(reinterpret_cast<const sockaddr_in*>(&bound)->sin_port);
  return listener;
}

}  // namespace lever::hil::devices
