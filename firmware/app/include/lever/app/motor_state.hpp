#pragma once
// The motor state file: the [board.motor] keys of the configuration a running lever-fw opened its motor with,
// written once at start, before the motor is opened (--motor-state; the unit's /run/lever/<instance>/motor). It is
// what `lever-fw --motor-off` stops: the motor this lever ran, whatever the configuration says by then (edited,
// cut in half, unreadable).
#include <string>

#include "lever/app/fw_config.hpp"

namespace lever::app {

// Writes the file whole or not at all (a temporary file beside it, then rename). Empty on success, else why not.
std::string write_motor_state(const std::string& path, const FwConfig& config);

}  // namespace lever::app
