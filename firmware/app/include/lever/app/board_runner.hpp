#pragma once
// lever-fw on a board: the backends opened from the configuration (libgpiod encoder, Modbus strain gauge,
// PWM motor, SocketCAN), the firmware core of the configured role stepped by the real-time loop, a status
// line from a thread of its own. Returns the process's exit code.
#include <atomic>
#include <string>

#include "lever/app/fw_config.hpp"

namespace lever::app {

// `stop` is set by the signal handlers; the loop ends within a period of it, the motor at zero torque and
// disabled. `motor_state`, unless empty, is written (motor_state.hpp) before the motor is opened; a lever that
// cannot write it does not start.
int run_board(const FwConfig& config, bool stats_json, const std::string& motor_state, const std::atomic<bool>& stop);

}  // namespace lever::app
