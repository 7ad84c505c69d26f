#pragma once
// What a failed libmodbus call means for the connection, from its errno.
#include <cstdint>

namespace lever::board {

enum class ModbusFailure : std::uint8_t {
  timeout,    // ETIMEDOUT: no (complete) response in time; a late one could still arrive, so reconnect
  bad_crc,    // EMBBADCRC: a corrupted RTU frame; the line works, flush and go on
  exception,  // EMBXILFUN..EMBXGTAR: the device answered with a Modbus exception; the link is fine
  protocol,   // a well-formed but wrong answer (other slave, wrong length or transaction id): flush, go on
  link,       // anything else (reset, broken pipe, I/O error): the connection is gone, reconnect
};

ModbusFailure classify_modbus_errno(int errno_value) noexcept;

// Whether the connection must be closed and reopened after this failure. After a timeout a late answer may
// still come: on TCP it would arrive while the next request waits, be refused for its transaction id
// (EMBBADDATA), and every answer after it would then be one request late, for good (seen in the test of a
// late server); a fresh connection cannot carry it. On RTU the port is reopened after a wait, so that the late
// answer lands while it is closed.
constexpr bool needs_reconnect(ModbusFailure failure) noexcept {
  return failure == ModbusFailure::timeout || failure == ModbusFailure::link;
}

}  // namespace lever::board
