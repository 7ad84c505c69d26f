#include "lever/hil/devices/gauge_server.hpp"

#include <modbus.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <mutex>
#include <optional>
#include <thread>
#include <variant>
#include <vector>

#include "device_symlink.hpp"
#include "lever/hil/devices/register_encode.hpp"
#include "pty_pair.hpp"
#include "tcp_listener.hpp"

namespace lever::hil::devices {

namespace {

using board::Error;
using board::ModbusRtuEndpoint;
using board::ModbusTcpEndpoint;
using board::RegisterFunction;
using board::UniqueFd;

struct ContextFree {
  void operator()(modbus_t* context) const noexcept {
    // The descriptors belong to the server (UniqueFd), not to libmodbus.
    modbus_set_socket(context, -1);
    modbus_free(context);
  }
};
struct MappingFree {
  void operator()(modbus_mapping_t* mapping) const noexcept { modbus_mapping_free(mapping); }
};

// A request is read only once poll() saw its first bytes, so this bounds nothing but a frame that stops
// half-way; libmodbus's byte timeout (500 ms) covers the gaps inside one.
constexpr std::uint32_t kIndicationTimeoutUs = 100'000;

std::string describe_map(const board::GaugeRegisterMap& map) {
  std::string text = std::string(board::name(map.function)) + " " + std::to_string(map.address) + " " +
                     std::string(board::name(map.type));
  if (board::register_count(map.type) == 2) text += " " + std::string(board::name(map.word_order));
  return text;
}

Error modbus_failure(const std::string& what) {
  const int err = errno;
  return Error{"gauge server: " + what + ": " + modbus_strerror(err), err};
}

}  // namespace

struct GaugeServer::Impl {
  board::GaugeRegisterMap map;
  std::unique_ptr<modbus_t, ContextFree> context;
  std::mutex mapping_mutex;  // set_force() writes the registers while the thread replies from them
  std::unique_ptr<modbus_mapping_t, MappingFree> mapping;
  std::atomic<bool> muted{false};
  std::atomic<std::uint64_t> requests{0};
  std::atomic<std::uint64_t> replies{0};
  std::atomic<std::uint64_t> connections{0};
  std::atomic<std::int64_t> last_reply_ns{0};

  // TCP
  UniqueFd listener;
  UniqueFd connection;
  int port = 0;
  // RTU
  std::optional<PtyPair> pty;
  std::optional<DeviceSymlink> symlink;

  UniqueFd wake;  // an eventfd: the destructor's way into the thread's poll()
  std::string description;
  std::jthread thread;

  ~Impl() {
    if (thread.joinable()) {
      thread.request_stop();
      const std::uint64_t one = 1;
      [[maybe_unused]] const auto ignored = ::write(wake.get(), &one, sizeof one);
      thread.join();
    }
  }

  void handle(const std::uint8_t* request, int length) {
    requests.fetch_add(1, std::memory_order_relaxed);
    if (muted.load(std::memory_order_relaxed)) return;
    std::lock_guard lock(mapping_mutex);
    if (modbus_reply(context.get(), request, length, mapping.get()) > 0) {
      // steady_clock is CLOCK_MONOTONIC on Linux: comparable with the kernel's time stamps.
      last_reply_ns.store(
          std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
              .count(),
          std::memory_order_relaxed);
      replies.fetch_add(1, std::memory_order_relaxed);
    }
  }

  void drop_connection() {
    modbus_set_socket(context.get(), -1);
    connection.reset();
  }

  // One connection at a time, and the newest wins: a client whose host vanished without closing its
  // connection leaves one that looks alive forever, and a server that kept serving it would never serve the
  // client's restart.
  void run_tcp(const std::stop_token& stop) {
    std::vector<std::uint8_t> request(MODBUS_TCP_MAX_ADU_LENGTH);
    while (!stop.stop_requested()) {
      pollfd fds[3] = {{wake.get(), POLLIN, 0}, {listener.get(), POLLIN, 0}, {connection.get(), POLLIN, 0}};
      if (::poll(fds, connection ? 3 : 2, -1) < 0) continue;
      if (stop.stop_requested()) return;
      if (connection && fds[2].revents != 0) {
        const int length = modbus_receive(context.get(), request.data());
        if (length > 0) {
          handle(request.data(), length);
        } else if (length == -1 && errno != ETIMEDOUT) {
          drop_connection();  // closed or reset by the client, or a stream we can no longer frame
        }
      }
      if ((fds[1].revents & POLLIN) != 0) {
        const int fd = ::accept4(listener.get(), nullptr, nullptr, SOCK_CLOEXEC);
        if (fd < 0) continue;
        const int on = 1;
        ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &on, sizeof on);
        drop_connection();
        connection.reset(fd);
        modbus_set_socket(context.get(), fd);
        connections.fetch_add(1, std::memory_order_relaxed);
      }
    }
  }

  void run_rtu(const std::stop_token& stop) {
    std::vector<std::uint8_t> request(MODBUS_RTU_MAX_ADU_LENGTH);
    while (!stop.stop_requested()) {
      pollfd fds[2] = {{wake.get(), POLLIN, 0}, {pty->master(), POLLIN, 0}};
      if (::poll(fds, 2, -1) < 0) continue;
      if (stop.stop_requested()) return;
      if ((fds[1].revents & POLLIN) == 0) {
        // No hangup can come (the slave is held open); anything else would spin, so take a breath.
        if (fds[1].revents != 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
        continue;
      }
      const int length = modbus_receive(context.get(), request.data());
      if (length > 0) {
        handle(request.data(), length);
      } else if (length == -1 && errno != ETIMEDOUT) {
        modbus_flush(context.get());  // a garbled request: drop what is left of it
      }
    }
  }

  board::Result<int> set_up(const ModbusTcpEndpoint& tcp) {
    auto listened = listen_tcp(tcp.host, tcp.port);
    if (!listened) return listened.error();
    listener = std::move(listened.value().fd);
    port = listened.value().port;
    context.reset(modbus_new_tcp_pi(tcp.host.c_str(), std::to_string(port).c_str()));
    if (!context) return modbus_failure("modbus_new_tcp_pi");
    const bool v6 = tcp.host.find(':') != std::string::npos;
    description = "Modbus TCP " + (v6 ? "[" + tcp.host + "]" : tcp.host) + ":" + std::to_string(port) + " unit " +
                  std::to_string(tcp.unit_id);
    return 0;
  }

  board::Result<int> set_up(const ModbusRtuEndpoint& rtu) {
    auto opened = PtyPair::open();
    if (!opened) return Error{"gauge server: " + opened.error().message, opened.error().errno_value};
    pty.emplace(std::move(opened).value());
    context.reset(modbus_new_rtu(pty->slave_path().c_str(), rtu.baud, static_cast<char>(rtu.parity), rtu.data_bits,
                                 rtu.stop_bits));
    if (!context) return modbus_failure("modbus_new_rtu");
    if (modbus_set_slave(context.get(), rtu.slave_id) == -1) {
      return modbus_failure("rtu.slave_id " + std::to_string(rtu.slave_id));
    }
    // The server never connects (that would open the slave end); it talks on the master end.
    modbus_set_socket(context.get(), pty->master());
    auto link = DeviceSymlink::create(rtu.device, pty->slave_path());
    if (!link) return link.error();
    symlink.emplace(std::move(link).value());
    description = "Modbus RTU " + rtu.device + " -> " + pty->slave_path() + " slave " + std::to_string(rtu.slave_id);
    return 0;
  }
};

board::Result<GaugeServer> GaugeServer::open(const board::ModbusGaugeConfig& config) {
  board::ModbusGaugeConfig checked = config;
  if (auto* tcp = std::get_if<ModbusTcpEndpoint>(&checked.transport); tcp != nullptr && tcp->port == 0) {
    tcp->port = 1;  // any free port: valid for a server, not for the client validate() was written for
  }
  if (auto problem = board::validate(checked)) return Error{"gauge server: " + *problem, EINVAL};

  auto impl = std::make_unique<Impl>();
  impl->map = config.registers;
  impl->wake.reset(::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK));
  if (!impl->wake) {
    const int err = errno;
    return Error{std::string("gauge server: eventfd: ") + std::strerror(err), err};
  }
  auto set_up = std::visit([&](const auto& endpoint) { return impl->set_up(endpoint); }, config.transport);
  if (!set_up) return set_up.error();
  if (modbus_set_indication_timeout(impl->context.get(), 0, kIndicationTimeoutUs) == -1) {
    return modbus_failure("indication timeout");
  }

  const int count = board::register_count(config.registers.type);
  const bool holding = config.registers.function == RegisterFunction::holding;
  const auto address = static_cast<unsigned>(config.registers.address);
  impl->mapping.reset(modbus_mapping_new_start_address(0, 0, 0, 0, holding ? address : 0, holding ? count : 0,
                                                       holding ? 0 : address, holding ? 0 : count));
  if (!impl->mapping) return modbus_failure("modbus_mapping_new_start_address");
  impl->description += ", " + describe_map(config.registers);

  GaugeServer server(std::move(impl));
  server.set_force(0.0);
  Impl* self = server.impl_.get();
  if (std::holds_alternative<ModbusTcpEndpoint>(config.transport)) {
    self->thread = std::jthread([self](std::stop_token stop) { self->run_tcp(stop); });
  } else {
    self->thread = std::jthread([self](std::stop_token stop) { self->run_rtu(stop); });
  }
  return server;
}

GaugeServer::GaugeServer(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
GaugeServer::GaugeServer(GaugeServer&&) noexcept = default;
GaugeServer& GaugeServer::operator=(GaugeServer&&) noexcept = default;
GaugeServer::~GaugeServer() = default;

std::uint64_t GaugeServer::set_force(double newtons) noexcept {
  const RegisterWords encoded =
      encode_registers(raw_for_newtons(newtons, impl_->map), impl_->map.type, impl_->map.word_order);
  std::lock_guard lock(impl_->mapping_mutex);
  std::uint16_t* table = impl_->map.function == RegisterFunction::holding ? impl_->mapping->tab_registers
                                                                          : impl_->mapping->tab_input_registers;
  for (int i = 0; i < encoded.count; ++i) table[i] = encoded.words[static_cast<std::size_t>(i)];
  // Replies are counted under the same lock: none in flight now.
  return impl_->replies.load(std::memory_order_relaxed);
}

void GaugeServer::set_muted(bool muted) noexcept { impl_->muted.store(muted, std::memory_order_relaxed); }

GaugeServerCounters GaugeServer::counters() const noexcept {
  return {impl_->requests.load(std::memory_order_relaxed), impl_->replies.load(std::memory_order_relaxed),
          impl_->connections.load(std::memory_order_relaxed), impl_->last_reply_ns.load(std::memory_order_relaxed)};
}

int GaugeServer::port() const noexcept { return impl_->port; }

const std::string& GaugeServer::description() const noexcept { return impl_->description; }

}  // namespace lever::hil::devices
