#pragma once
// How the lever's motor driver is wired to the board: a Linux PWM channel (sysfs) for the torque's magnitude,
// GPIO lines for the driver's enable, the torque's sign and its fault output, and the numbers that turn a
// torque into a duty cycle.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "lever/board/line_ref.hpp"

namespace lever::board {

// One GPIO line of the motor driver. `active_low`: the line is asserted at the low level (an nFAULT output, an
// inverting buffer); what "asserted" means is said where the line is configured.
struct MotorLineConfig {
  std::string chip;  // "/dev/gpiochip2" (a path), "gpiochip2" (a name), or the chip's label
  LineRef line;
  bool active_low = false;
};

// Sign-magnitude drive: the duty cycle carries |torque| and the direction line its sign. The other common
// convention, a signed duty around 50 % (locked antiphase), is not offered: there a stopped or disabled PWM
// output (a held low level) is full torque one way, while here it is no torque (docs/board-motor.md).
struct PwmMotorConfig {
  // <sysfs_root>/class/pwm/pwmchip<pwm_chip>/pwm<pwm_channel>/; tests point sysfs_root at a tree of their own.
  std::string sysfs_root = "/sys";
  unsigned pwm_chip = 0;
  unsigned pwm_channel = 0;
  std::uint32_t period_ns = 50'000;  // 20 kHz: above hearing, and what H-bridge drivers commonly take
  bool pwm_inversed = false;         // polarity "inversed": the board inverts the PWM on its way to the driver
  // How long pwmM/ may take to appear after export, its attributes included (udev may change their owner).
  std::uint32_t export_timeout_ms = 1'000;

  // Torque to duty, for a driver that regulates its current to full_scale_current_a times the duty:
  // duty = |torque| / (gear_ratio * torque_constant_nm_per_a * full_scale_current_a), at most max_duty.
  double torque_constant_nm_per_a = 0.0;  // the motor's Kt
  double gear_ratio = 1.0;                // lever torque per motor torque
  double full_scale_current_a = 0.0;      // the driver's current at 100 % duty
  double max_duty = 0.95;                 // the duty never goes above this fraction of the period
  double deadband_nm = 0.0;               // a torque smaller than this in magnitude gives zero duty

  std::optional<MotorLineConfig> enable_line;     // output; asserted: the driver is enabled
  std::optional<MotorLineConfig> direction_line;  // output; asserted: negative torque
  std::optional<MotorLineConfig> fault_line;      // input; asserted: the driver reports a fault
  // Without a direction line the sign has nowhere to go: this must then say so, and negative torques give
  // zero duty (bring-up of the PWM alone, a spring-returned test stand).
  bool positive_torque_only = false;
  std::string consumer = "lever-motor";  // shown by gpioinfo; the kernel keeps 31 characters

  // Every problem, each naming its field ("max_duty: ..."); empty when the config can be opened.
  std::vector<std::string> validate() const;
};

}  // namespace lever::board
