#pragma once
// lever-fw --motor-off: the board's motor stopped by a process of its own, for the service manager to run after
// lever-fw has ended however it ended (ExecStopPost=, packaging/systemd/lever-fw@.service): a SIGKILL or a hung
// kernel thread leaves the PWM at its last duty, since sysfs belongs to the kernel (docs/board-motor.md).
#include <string>

namespace lever::app {

// Stops the motor the lever ran: the one its motor state names (motor_state.hpp; `state_path` empty: none), when
// that file is there and readable, since the configuration may have changed under the running lever (a file cut
// short can even be valid TOML, its motor keys then the defaults: another motor, maybe another lever's); a
// configuration that names another motor is said on stderr and its motor left alone. Without a state, the motor
// the configuration's [board.motor] keys name, whatever else in the file is wrong (each other problem is said on
// stderr and changes nothing).
//
// A stop is an open of the motor: the PWM at duty 0, left enabled there, its inactive level (written before
// anything else, so a GPIO line that cannot be had does not keep the PWM running), then the enable and direction lines requested deasserted;
// closing it leaves them so. Returns the process's exit code: 0 the motor was stopped, 1 it could not be (or no
// motor could be named), the reason on stderr; the PWM writes that went through stand.
int motor_off(const std::string& config_path, const std::string& state_path);

}  // namespace lever::app
