#pragma once
// lever-fw on a board: the backends opened from the configuration (libgpiod encoder, Modbus strain gauge,
// PWM motor, SocketCAN), the firmware core of the configured role stepped by the real-time loop, a status
// line from a thread of its own. Returns the process's exit code.
#include <atomic>

#include "lever/app/fw_config.hpp"

namespace lever::app {

// `stop` is set by the signal handlers; the loop ends within a period of it, the motor at zero torque and
// disabled.
int run_board(const FwConfig& config, bool stats_json, const std::atomic<bool>& stop);

}  // namespace lever::app
