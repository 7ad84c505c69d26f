#include "modbus_test_servers.hpp"

#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <thread>
#include <vector>

namespace lever::test {
namespace {

[[noreturn]] void fail(const std::string& what) { throw std::runtime_error(what + ": " + std::strerror(errno)); }

// How long a server thread waits for a request before it looks at its stop token again.
constexpr std::uint32_t kIndicationPollUs = 10'000;

bool readable(int fd, int timeout_ms) {
  pollfd entry{fd, POLLIN, 0};
  return ::poll(&entry, 1, timeout_ms) == 1 && (entry.revents & POLLIN) != 0;
}

void make_raw(int fd) {
  termios settings{};
  if (::tcgetattr(fd, &settings) != 0) fail("tcgetattr");
  ::cfmakeraw(&settings);
  if (::tcsetattr(fd, TCSANOW, &settings) != 0) fail("tcsetattr");
}

}  // namespace

// ---- ModbusTestServer ----

ModbusTestServer::ModbusTestServer(int register_count)
    : mapping_(modbus_mapping_new(0, 0, register_count, register_count)) {
  if (!mapping_) fail("modbus_mapping_new");
}

void ModbusTestServer::set_holding(int address, std::span<const std::uint16_t> words) {
  std::lock_guard lock(mutex_);
  for (std::size_t i = 0; i < words.size(); ++i) mapping_->tab_registers[address + static_cast<int>(i)] = words[i];
}

void ModbusTestServer::set_input(int address, std::span<const std::uint16_t> words) {
  std::lock_guard lock(mutex_);
  for (std::size_t i = 0; i < words.size(); ++i) {
    mapping_->tab_input_registers[address + static_cast<int>(i)] = words[i];
  }
}

void ModbusTestServer::handle(modbus_t* context, const std::uint8_t* request, int length) {
  received_.fetch_add(1);
  const ServerBehaviour behaviour = behaviour_.load();
  if (behaviour == ServerBehaviour::mute) return;
  for (int left = to_drop_.load(); left > 0;)
    if (to_drop_.compare_exchange_weak(left, left - 1)) return;
  if (behaviour == ServerBehaviour::late) std::this_thread::sleep_for(std::chrono::milliseconds(late_delay_ms_.load()));
  for (int left = to_refuse_.load(); left > 0;) {
    if (to_refuse_.compare_exchange_weak(left, left - 1)) {
      modbus_reply_exception(context, request, MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY);
      return;
    }
  }
  std::lock_guard lock(mutex_);
  modbus_reply(context, request, length, mapping_.get());
}

// ---- TcpTestServer ----

TcpTestServer::TcpTestServer(const std::string& host, int port, int register_count)
    : ModbusTestServer(register_count), context_(modbus_new_tcp_pi(host.c_str(), std::to_string(port).c_str())) {
  if (context_ == nullptr) fail("modbus_new_tcp_pi");
  listener_.reset(modbus_tcp_pi_listen(context_, 1));
  if (!listener_) {
    modbus_free(context_);
    fail("modbus_tcp_pi_listen " + host + " port " + std::to_string(port));
  }
  sockaddr_storage bound{};
  socklen_t length = sizeof bound;
  ::getsockname(listener_.get(), reinterpret_cast<sockaddr*>(&bound), &length);
  port_ = bound.ss_family == AF_INET6 ? ntohs(reinterpret_cast<sockaddr_in6*>(&bound)->sin6_port)
                                      : ntohs(reinterpret_cast<sockaddr_in*>(&bound)->sin_port);
  modbus_set_indication_timeout(context_, 0, kIndicationPollUs);
  thread_ = std::jthread([this](std::stop_token stop) { run(stop); });
}

TcpTestServer::~TcpTestServer() {
  thread_.request_stop();
  thread_.join();
  // The listener first: a client that sees its connection close and reconnects at once must be refused.
  listener_.reset();
  modbus_close(context_);  // the accepted connection, if any
  modbus_free(context_);
}

void TcpTestServer::run(const std::stop_token& stop) {
  std::vector<std::uint8_t> request(MODBUS_TCP_MAX_ADU_LENGTH);
  while (!stop.stop_requested()) {
    if (!readable(listener_.get(), 10)) continue;
    int listener = listener_.get();
    if (modbus_tcp_pi_accept(context_, &listener) == -1) continue;
    while (!stop.stop_requested()) {
      const int length = modbus_receive(context_, request.data());
      if (length > 0) {
        handle(context_, request.data(), length);
      } else if (length == -1 && errno != ETIMEDOUT) {
        break;  // the client closed or reset the connection: wait for the next one
      }
    }
    // Stopping, the connection stays open for the destructor to close after the listener: closed here, a client
    // reconnecting at once would reach the listener still open and count a connection that dies unanswered.
    if (stop.stop_requested()) return;
    modbus_close(context_);
  }
}

// ---- PtyPair ----

PtyPair::PtyPair() : master_(::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC)) {
  if (!master_) fail("posix_openpt");
  if (::grantpt(master_.get()) != 0) fail("grantpt");
  if (::unlockpt(master_.get()) != 0) fail("unlockpt");
  const char* name = ::ptsname(master_.get());
  if (name == nullptr) fail("ptsname");
  slave_path_ = name;
  slave_held_open_.reset(::open(slave_path_.c_str(), O_RDWR | O_NOCTTY | O_CLOEXEC));
  if (!slave_held_open_) fail("open " + slave_path_);
  // No echo, no line editing, no CR/LF translation: the bytes of a frame pass as they are.
  make_raw(slave_held_open_.get());
  make_raw(master_.get());
}

// ---- RtuTestServer ----

RtuTestServer::RtuTestServer(int slave_id, int register_count)
    : ModbusTestServer(register_count), context_(modbus_new_rtu(pty_.slave_path().c_str(), 115200, 'N', 8, 1)) {
  if (context_ == nullptr) fail("modbus_new_rtu");
  // The server never connects (that would open the slave end); it talks on the master end it is given.
  modbus_set_slave(context_, slave_id);
  modbus_set_socket(context_, pty_.master());
  modbus_set_indication_timeout(context_, 0, kIndicationPollUs);
  thread_ = std::jthread([this](std::stop_token stop) { run(stop); });
}

RtuTestServer::~RtuTestServer() {
  thread_.request_stop();
  thread_.join();
  modbus_set_socket(context_, -1);  // the master end belongs to pty_
  modbus_free(context_);
}

void RtuTestServer::run(const std::stop_token& stop) {
  std::vector<std::uint8_t> request(MODBUS_RTU_MAX_ADU_LENGTH);
  while (!stop.stop_requested()) {
    const int length = modbus_receive(context_, request.data());
    if (length > 0) {
      handle(context_, request.data(), length);
    } else if (length == -1 && errno != ETIMEDOUT) {
      modbus_flush(context_);  // a garbled request: drop what is left of it
    }
  }
}

// ---- BadCrcRtuResponder ----

std::uint16_t modbus_crc16(std::span<const std::uint8_t> bytes) {
  std::uint16_t crc = 0xFFFF;
  for (const std::uint8_t byte : bytes) {
    crc = static_cast<std::uint16_t>(crc ^ byte);
    for (int bit = 0; bit < 8; ++bit) {
      crc = (crc & 1) != 0 ? static_cast<std::uint16_t>((crc >> 1) ^ 0xA001) : static_cast<std::uint16_t>(crc >> 1);
    }
  }
  return crc;
}

BadCrcRtuResponder::BadCrcRtuResponder(std::uint16_t word0, std::uint16_t word1) : words_{word0, word1} {
  thread_ = std::jthread([this](std::stop_token stop) { run(stop); });
}

BadCrcRtuResponder::~BadCrcRtuResponder() {
  thread_.request_stop();
  thread_.join();
}

void BadCrcRtuResponder::run(const std::stop_token& stop) {
  // A read-registers request is 8 bytes: slave, function, address (2), count (2), CRC (2, low byte first).
  constexpr std::size_t kRequestLength = 8;
  std::vector<std::uint8_t> pending;
  bool spoil_next = true;
  while (!stop.stop_requested()) {
    if (!readable(pty_.master(), 10)) continue;
    std::uint8_t chunk[64];
    const ssize_t got = ::read(pty_.master(), chunk, sizeof chunk);
    if (got <= 0) continue;
    pending.insert(pending.end(), chunk, chunk + got);
    while (pending.size() >= kRequestLength) {
      const std::uint8_t slave = pending[0];
      const std::uint8_t function = pending[1];
      const int count = std::min((pending[4] << 8) | pending[5], 2);
      pending.erase(pending.begin(), pending.begin() + kRequestLength);

      std::vector<std::uint8_t> answer{slave, function, static_cast<std::uint8_t>(2 * count)};
      for (int i = 0; i < count; ++i) {
        answer.push_back(static_cast<std::uint8_t>(words_[i] >> 8));
        answer.push_back(static_cast<std::uint8_t>(words_[i] & 0xFF));
      }
      std::uint16_t crc = modbus_crc16(answer);
      if (spoil_next) crc = static_cast<std::uint16_t>(crc ^ 0x0101);
      answer.push_back(static_cast<std::uint8_t>(crc & 0xFF));
      answer.push_back(static_cast<std::uint8_t>(crc >> 8));
      // Line noise after a spoiled frame: unless the reader drops it, it becomes the start of the next answer.
      if (spoil_next) answer.insert(answer.end(), {0xFF, 0x00, 0xAA});
      if (::write(pty_.master(), answer.data(), answer.size()) != static_cast<ssize_t>(answer.size())) continue;
      (spoil_next ? corrupted_ : good_).fetch_add(1);
      spoil_next = !spoil_next;
    }
  }
}

}  // namespace lever::test
