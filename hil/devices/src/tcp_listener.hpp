#pragma once
// The listening socket of a simulated Modbus TCP device, made here rather than by libmodbus so that its
// options are ours to choose (SO_REUSEADDR, close-on-exec) and port 0 can report the port it got.
#include <string>

#include "lever/board/result.hpp"
#include "lever/board/unique_fd.hpp"

namespace lever::hil::devices {

struct TcpListener {
  board::UniqueFd fd;
  int port = 0;  // the bound port, also when 0 was asked for
};

// `host` a numeric IPv4 or IPv6 address, as the gauge's config requires; `port` 0 for any free port.
board::Result<TcpListener> listen_tcp(const std::string& host, int port);

}  // namespace lever::hil::devices
