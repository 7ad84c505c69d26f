#pragma once
// The weighing amplifier as the board's Modbus client sees it: a libmodbus server (modbus_receive,
// modbus_reply) on a thread of its own, holding the force the simulated world gives it in the register the
// board's config (ModbusGaugeConfig) says, in its type and word order. The same config the board's lever-fw
// reads: over TCP the server listens where the client connects; over RTU it serves on a pty and makes the
// configured device path a symlink to the pty's slave end, which the client opens as its serial port.
//
// It serves reconnects for as long as it lives: a client killed and restarted, or one that dropped its
// connection after a timeout, is served again.
#include <cstdint>
#include <memory>
#include <string>

#include "lever/board/modbus_gauge_config.hpp"
#include "lever/board/result.hpp"

namespace lever::hil::devices {

struct GaugeServerCounters {
  std::uint64_t requests = 0;      // complete requests received (for us: RTU requests to other slaves are not)
  std::uint64_t replies = 0;       // answers sent: registers or Modbus exceptions
  std::uint64_t connections = 0;   // TCP connections accepted; 0 on RTU
  std::int64_t last_reply_ns = 0;  // CLOCK_MONOTONIC when the newest answer was sent (0: none yet)
};

class GaugeServer {
 public:
  // Checks the config as the client does (board::validate; a TCP port of 0 is allowed here and means any
  // free port), then listens (TCP, SO_REUSEADDR) or makes the pty and the symlink at rtu.device (an existing
  // symlink is replaced, anything else there is refused), and starts serving. The registers hold 0 N.
  // Only the configured registers exist: a request for any other address or table gets an exception.
  static board::Result<GaugeServer> open(const board::ModbusGaugeConfig& config);

  GaugeServer(GaugeServer&&) noexcept;
  GaugeServer& operator=(GaugeServer&&) noexcept;
  GaugeServer(const GaugeServer&) = delete;
  GaugeServer& operator=(const GaugeServer&) = delete;
  // Stops the thread at once (it waits in poll() on a wake-up descriptor too), closes the connection and the
  // listener, and removes the symlink if it still points at this server's pty.
  ~GaugeServer();

  // The register value for this force: raw = (newtons - offset) / scale, encoded by encode_registers()
  // (register_encode.hpp). From any thread; the next reply carries it. Returns the answers sent before it was in
  // the registers: every later one carries it (or a newer value).
  std::uint64_t set_force(double newtons) noexcept;
  // Muted: requests are read and counted but never answered, as an amplifier that hangs. The client times
  // out (and, doing what board::ModbusGauge does, reconnects).
  void set_muted(bool muted) noexcept;

  GaugeServerCounters counters() const noexcept;
  int port() const noexcept;  // TCP: the port listened on (the one picked when 0 was configured); RTU: 0
  // "Modbus TCP 127.0.0.1:1502 unit 255, holding 0 int32 high_first",
  // "Modbus RTU /tmp/gauge -> /dev/pts/3 slave 1, input 0 float32 low_first".
  const std::string& description() const noexcept;

 private:
  struct Impl;
  explicit GaugeServer(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lever::hil::devices
