#pragma once
// What a failed libmodbus call means for the connection, from its errno.
#include <cstdint>

namespace lever::platform {

enum class ModbusFailure : std::uint8_t {
  timeout,    // ETIMEDOUT: no (complete) response in time; a late one could still arrive, so reconnect
  bad_crc,    // EMBBADCRC: a corrupted RTU frame; the line works, flush and go on
  exception,  // EMBXILFUN..EMBXGTAR: the device answered with a Modbus exception; the link is fine
  protocol,   // a well-formed but wrong answer (other slave, wrong length or transaction id): flush, go on
  link,       // anything else (reset, broken pipe, I/O error): the connection is gone, reconnect
};

ModbusFailure classify_modbus_errno(int errno_value) noexcept;

// Whether the connection must be closed and reopened after this failure.
constexpr bool needs_reconnect(ModbusFailure failure) noexcept {
  return failure == ModbusFailure::timeout || failure == ModbusFailure::link;
}

}  // namespace lever::platform
