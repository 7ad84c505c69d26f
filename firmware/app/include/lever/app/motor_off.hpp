#pragma once
// lever-fw --motor-off: the board's motor stopped by a process of its own, for the service manager to run after
// lever-fw has ended however it ended (ExecStopPost=, packaging/systemd/lever-fw@.service): a SIGKILL or a hung
// kernel thread leaves the PWM at its last duty, since sysfs belongs to the kernel (docs/board-motor.md).
#include <string>

namespace lever::app {

// Stops the motor the lever ran, named explicitly, never by a default: a key left out of a file is its default,
// and the defaults (pwmchip0/pwm0, gpiochip0) name a motor too, maybe another lever's.
//
// With `state_path` (the unit's), the motor state alone names it (motor_state.hpp), since the configuration may
// have changed under the running lever or name a motor this run never opened:
//   - a whole state of this run: its motor is stopped (a configuration naming another is said, and left alone);
//   - no state under a unit ($INVOCATION_ID set): this run opened nothing (the state is written before anything
//     is opened), so nothing is stopped, exit 0;
//   - no state outside a unit: exit 1, nothing stopped (no invocation to tell "never started" from "wrong path");
//   - a state that names no motor (empty, cut, a key missing or wrong), or a stale one (another invocation's
//     under the unit, or another boot's): exit 1, nothing stopped, the reason on stderr.
// Without `state_path`, the configuration's [board.motor] keys name it, whatever else in the file is wrong (each
// other problem said on stderr), but only when every key that says which hardware it is is there (the PWM chip
// and channel, the three lines, the lines' chip when one is named); otherwise exit 1, nothing stopped.
//
// A stop is an open of the motor: the PWM at duty 0, left enabled there, its inactive level (written before
// anything else, so a GPIO line that cannot be had does not keep the PWM running), then the enable and direction
// lines requested deasserted; closing it leaves them so. Returns the process's exit code: 0 the motor was stopped
// (or, under the unit, this run had none), 1 it could not be or none was named, the reason on stderr; the PWM
// writes that went through stand.
int motor_off(const std::string& config_path, const std::string& state_path);

}  // namespace lever::app
