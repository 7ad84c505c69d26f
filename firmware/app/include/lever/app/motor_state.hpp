#pragma once
// The motor state file: the [board.motor] keys of the configuration a running lever-fw opened its motor with,
// and the run that wrote it, written once at start, before the motor is opened (--motor-state; the unit's
// /run/lever/<instance>/motor). It is what `lever-fw --motor-off` stops: the motor this lever ran, whatever the
// configuration says by then (edited, cut in half, unreadable). The run is named because the file outlives it
// (RuntimeDirectoryPreserve=restart keeps the previous run's): --motor-off under the unit acts on its own
// invocation's state only.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "lever/app/fw_config.hpp"

namespace lever::app {

// The run that wrote a state.
struct MotorStateWriter {
  std::string invocation_id;  // systemd's $INVOCATION_ID, the same for a unit's ExecStart and ExecStopPost; ""
                              // outside a unit
  std::string boot_id;        // /proc/sys/kernel/random/boot_id; "" where it is hidden (the unit's ProcSubset=pid)
  std::int64_t pid = 0;       // for the messages: a pid is reused, the invocation and the boot are not
};
MotorStateWriter this_run();

// Writes the file whole or not at all (a temporary file beside it, then rename). Empty on success, else why not.
std::string write_motor_state(const std::string& path, const FwConfig& config);

struct MotorState {
  bool found = false;  // the file is there (it may still name no motor)
  // Empty: the file names no motor, `problems` say why. A state is whole or it is none: every [board.motor] key
  // and the writer's three, nothing wrong with any, since the lever writes them all at once; a file short of one
  // (empty, cut, another program's) would otherwise name the defaults' motor.
  std::optional<board::PwmMotorConfig> motor;
  MotorStateWriter writer;
  std::vector<std::string> problems;
};
MotorState read_motor_state(const std::string& path);

}  // namespace lever::app
