#include "modbus_context.hpp"

#include <cerrno>
#include <string>
#include <variant>

namespace lever::board {
namespace {

Error failure(const std::string& what) {
  const int saved = errno;
  return Error{what + ": " + modbus_strerror(saved), saved};
}

modbus_t* new_context(const ModbusTcpEndpoint& tcp) {
  // The protocol-independent constructor, so an IPv6 amplifier works too; validate() allowed numeric hosts only.
  return modbus_new_tcp_pi(tcp.host.c_str(), std::to_string(tcp.port).c_str());
}

modbus_t* new_context(const ModbusRtuEndpoint& rtu) {
  return modbus_new_rtu(rtu.device.c_str(), rtu.baud, static_cast<char>(rtu.parity), rtu.data_bits, rtu.stop_bits);
}

int slave_of(const ModbusTcpEndpoint& tcp) { return tcp.unit_id; }
int slave_of(const ModbusRtuEndpoint& rtu) { return rtu.slave_id; }

}  // namespace

Result<ModbusContext> make_modbus_context(const ModbusGaugeConfig& config) {
  ModbusContext context(std::visit([](const auto& endpoint) { return new_context(endpoint); }, config.transport));
  if (!context) return failure("modbus: cannot create the context");
  const int slave = std::visit([](const auto& endpoint) { return slave_of(endpoint); }, config.transport);
  if (modbus_set_slave(context.get(), slave) == -1) return failure("modbus: slave/unit id " + std::to_string(slave));

  const auto timeout_us = config.response_timeout.count();
  if (modbus_set_response_timeout(context.get(), static_cast<std::uint32_t>(timeout_us / 1'000'000),
                                  static_cast<std::uint32_t>(timeout_us % 1'000'000)) == -1) {
    return failure("modbus: response timeout");
  }
  // Without a byte timeout libmodbus gives the whole response the response timeout, first byte to last: one
  // bound for a read, instead of a response timeout plus 500 ms (its default) per straggling byte.
  if (modbus_set_byte_timeout(context.get(), 0, 0) == -1) return failure("modbus: byte timeout");
  // The gauge closes, backs off and reconnects itself; libmodbus's own recovery would sleep and retry inside a
  // read, out of sight of the counters and of a stop request.
  if (modbus_set_error_recovery(context.get(), MODBUS_ERROR_RECOVERY_NONE) == -1) {
    return failure("modbus: error recovery");
  }
  return context;
}

}  // namespace lever::board
