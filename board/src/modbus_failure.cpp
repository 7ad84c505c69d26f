#include "lever/board/modbus_failure.hpp"

#include <modbus.h>

#include <cerrno>

namespace lever::board {

ModbusFailure classify_modbus_errno(int errno_value) noexcept {
  if (errno_value == ETIMEDOUT) return ModbusFailure::timeout;
  if (errno_value == EMBBADCRC) return ModbusFailure::bad_crc;
  if (errno_value >= EMBXILFUN && errno_value <= EMBXGTAR) return ModbusFailure::exception;
  if (errno_value == EMBBADDATA || errno_value == EMBBADEXC || errno_value == EMBUNKEXC || errno_value == EMBMDATA ||
      errno_value == EMBBADSLAVE) {
    return ModbusFailure::protocol;
  }
  return ModbusFailure::link;
}

}  // namespace lever::board
