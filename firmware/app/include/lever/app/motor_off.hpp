#pragma once
// lever-fw --motor-off: the board's motor stopped by a process of its own, for the service manager to run after
// lever-fw has ended however it ended (ExecStopPost=, packaging/systemd/lever-fw@.service): a SIGKILL or a hung
// kernel thread leaves the PWM at its last duty, since sysfs belongs to the kernel (docs/board-motor.md).
#include <string>

namespace lever::app {

// Stops the motor the configuration's [board.motor] keys name, whatever else in the file is wrong (each other
// problem is said on stderr and changes nothing). When those keys cannot be read (the file unreadable, cut in
// half, a motor key wrong), the motor the state file names (motor_state.hpp; `state_path` empty: none); when
// both can be read and name different motors, both (the configuration was edited under the running lever).
//
// A stop is an open of the motor: the PWM disabled at duty 0 (written before anything else, so a GPIO line that
// cannot be had does not keep the PWM running), then the enable and direction lines requested deasserted;
// closing it leaves them so. Returns the process's exit code: 0 every motor named was stopped, 1 one could not
// be (or none could be named), the reason on stderr; the PWM writes that went through stand.
int motor_off(const std::string& config_path, const std::string& state_path);

}  // namespace lever::app
