#pragma once
// The owner of a libmodbus context: closed and freed exactly once, whatever path the gauge leaves by.
#include <modbus.h>

#include <memory>

#include "lever/board/modbus_gauge_config.hpp"
#include "lever/board/result.hpp"

namespace lever::board {

struct ModbusContextDeleter {
  void operator()(modbus_t* context) const noexcept {
    modbus_close(context);  // a no-op when not connected
    modbus_free(context);
  }
};
using ModbusContext = std::unique_ptr<modbus_t, ModbusContextDeleter>;

// A context for the configured transport and slave, with the gauge's response timeout; not yet connected.
// Expects a config that validate() accepted.
Result<ModbusContext> make_modbus_context(const ModbusGaugeConfig& config);

}  // namespace lever::board
