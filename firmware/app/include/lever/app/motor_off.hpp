#pragma once
// lever-fw --motor-off: the board's motor stopped by a process of its own, for the service manager to run after
// lever-fw has ended however it ended (ExecStopPost=, packaging/systemd/lever-fw@.service): a SIGKILL or a hung
// kernel thread leaves the PWM at its last duty, since sysfs belongs to the kernel (docs/board-motor.md).
#include "lever/app/fw_config.hpp"

namespace lever::app {

// Opens the configured motor, which is the stop: the PWM disabled at duty 0 (written before anything else, so a
// GPIO line that cannot be had does not keep the PWM running), then the enable and direction lines requested
// deasserted; closing it leaves them so. Returns the process's exit code: 0 stopped, 1 the motor could not be
// opened (the reason on stderr; the PWM writes that went through stand).
int motor_off(const FwConfig& config);

}  // namespace lever::app
