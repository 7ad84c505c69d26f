#pragma once
// The motor the PwmMotor and MotorGuard tests drive on a temporary sysfs tree (pwm_sysfs_tree.hpp): no lines
// (positive_torque_only; the lines are tested in the kernel rig), 1 Nm at full duty, so the duty in ns is the torque
// in Nm times the 50 us period.
#include <unistd.h>

#include <utility>

#include "lever/board/pwm_motor.hpp"
#include "pwm_sysfs_tree.hpp"

namespace lever::test {

inline constexpr unsigned kPwmTestChip = 2;
inline constexpr unsigned kPwmTestChannel = 1;

inline board::PwmMotorConfig pwm_test_config(const PwmSysfsTree& tree) {
  board::PwmMotorConfig c;
  c.sysfs_root = tree.root();
  c.pwm_chip = kPwmTestChip;
  c.pwm_channel = kPwmTestChannel;
  c.period_ns = 50'000;
  c.torque_constant_nm_per_a = 0.05;
  c.gear_ratio = 10.0;
  c.full_scale_current_a = 2.0;
  c.max_duty = 0.9;
  c.deadband_nm = 0.01;
  c.positive_torque_only = true;
  return c;
}

// In a child: a motor driving 0.3 Nm (duty 15000), so that a stop has something to undo. Exit code 90: it did not
// open; 91: it did not drive.
inline board::PwmMotor driving_motor(const PwmSysfsTree& tree) {
  auto motor = board::PwmMotor::open(pwm_test_config(tree));
  if (!motor) ::_exit(90);
  motor.value().command({0.3, true});
  if (tree.read("duty_cycle") != "15000" || tree.read("enable") != "1") ::_exit(91);
  return std::move(motor).value();
}

}  // namespace lever::test
