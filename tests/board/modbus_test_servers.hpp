#pragma once
// Real Modbus servers for the gauge's tests, built from libmodbus's own server API (modbus_receive,
// modbus_reply, modbus_mapping_new), each on its own thread: one on TCP loopback, one on a pseudo-terminal
// pair for RTU. Plus a hand-written RTU responder whose only purpose is to send frames with a bad CRC.
#include <modbus.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <thread>

#include "lever/board/unique_fd.hpp"

namespace lever::test {

enum class ServerBehaviour : std::uint8_t {
  answer,  // modbus_reply: the registers, or an exception for an address outside the mapping
  mute,    // read each request and never answer, as an amplifier that hangs
  late,    // answer each request late_delay() after it came (kLateAnswerDelay unless set), as an amplifier that stalls
};
inline constexpr std::chrono::milliseconds kLateAnswerDelay{80};

// The register tables and behaviour every server shares; tests change them while the server runs.
class ModbusTestServer {
 public:
  // Holding and input registers 0..register_count-1, all zero.
  explicit ModbusTestServer(int register_count);
  ModbusTestServer(const ModbusTestServer&) = delete;
  ModbusTestServer& operator=(const ModbusTestServer&) = delete;

  void set_holding(int address, std::span<const std::uint16_t> words);
  void set_input(int address, std::span<const std::uint16_t> words);
  void set_behaviour(ServerBehaviour behaviour) { behaviour_.store(behaviour); }
  // The next `requests` requests are read and never answered (a response lost on the way), then the server
  // behaves as set again.
  void drop_next(int requests) { to_drop_.store(requests); }
  int drops_left() const { return to_drop_.load(); }
  // The next `requests` requests are answered with a Modbus exception (server busy).
  void refuse_next(int requests) { to_refuse_.store(requests); }
  int refusals_left() const { return to_refuse_.load(); }
  void set_late_delay(std::chrono::milliseconds delay) { late_delay_ms_.store(delay.count()); }
  std::uint64_t requests_received() const { return received_.load(); }

 protected:
  ~ModbusTestServer() = default;
  // Called by the server thread with a complete request.
  void handle(modbus_t* context, const std::uint8_t* request, int length);

 private:
  struct MappingFree {
    void operator()(modbus_mapping_t* mapping) const { modbus_mapping_free(mapping); }
  };
  std::mutex mutex_;  // the test thread writes registers while the server thread replies from them
  std::unique_ptr<modbus_mapping_t, MappingFree> mapping_;
  std::atomic<ServerBehaviour> behaviour_{ServerBehaviour::answer};
  std::atomic<std::uint64_t> received_{0};
  std::atomic<int> to_drop_{0};
  std::atomic<int> to_refuse_{0};
  std::atomic<std::chrono::milliseconds::rep> late_delay_ms_{kLateAnswerDelay.count()};
};

// Modbus TCP on a loopback address. Destroying it closes the listening socket and the connection.
class TcpTestServer final : public ModbusTestServer {
 public:
  // port 0: any free port (port() tells which).
  explicit TcpTestServer(const std::string& host = "127.0.0.1", int port = 0, int register_count = 16);
  ~TcpTestServer();
  int port() const { return port_; }

 private:
  void run(const std::stop_token& stop);
  modbus_t* context_;
  board::UniqueFd listener_;
  int port_ = 0;
  std::jthread thread_;
};

// A pseudo-terminal pair in raw mode: the test's device end is the slave path, which the gauge opens; the
// master end plays the amplifier. The slave is also held open here, so the master never sees a hangup while
// the gauge closes and reopens it.
class PtyPair {
 public:
  PtyPair();
  int master() const { return master_.get(); }
  const std::string& slave_path() const { return slave_path_; }

 private:
  board::UniqueFd master_;
  board::UniqueFd slave_held_open_;
  std::string slave_path_;
};

// Modbus RTU on the master end of a pty pair.
class RtuTestServer final : public ModbusTestServer {
 public:
  explicit RtuTestServer(int slave_id = 1, int register_count = 16);
  ~RtuTestServer();
  const std::string& device() const { return pty_.slave_path(); }

 private:
  void run(const std::stop_token& stop);
  PtyPair pty_;
  modbus_t* context_;
  std::jthread thread_;
};

// Answers read-register requests on a pty with `words`, by hand, and spoils the CRC of every other answer
// (the first included), with a few bytes of noise after it: the gauge must count the bad ones, drop the
// noise, and take the good ones.
class BadCrcRtuResponder {
 public:
  BadCrcRtuResponder(std::uint16_t word0, std::uint16_t word1);
  ~BadCrcRtuResponder();
  const std::string& device() const { return pty_.slave_path(); }
  std::uint64_t corrupted_sent() const { return corrupted_.load(); }
  std::uint64_t good_sent() const { return good_.load(); }

 private:
  void run(const std::stop_token& stop);
  PtyPair pty_;
  std::uint16_t words_[2];
  std::atomic<std::uint64_t> corrupted_{0};
  std::atomic<std::uint64_t> good_{0};
  std::jthread thread_;
};

// CRC-16/MODBUS, written out here so the responder does not borrow libmodbus's.
std::uint16_t modbus_crc16(std::span<const std::uint8_t> bytes);

}  // namespace lever::test
