#pragma once
// The torque the core asks for, as the PWM duty and direction the sign-magnitude driver takes
// (PwmMotorConfig says how). Pure arithmetic, so it is tested apart from any file.
#include <cstdint>

#include "lever/board/pwm_motor_config.hpp"

namespace lever::board {

struct DutySetpoint {
  std::uint32_t duty_ns = 0;  // 0..period_ns
  bool negative = false;      // meaningful only with duty_ns > 0: at zero duty the direction does not matter
};

class TorqueToDuty {
 public:
  explicit TorqueToDuty(const PwmMotorConfig& config) noexcept;

  // A torque inside the deadband, a NaN, and (with positive_torque_only) a negative torque give zero duty;
  // beyond max_duty the duty stays at max_duty.
  DutySetpoint operator()(double torque_nm) const noexcept;

  double torque_at_full_duty_nm() const noexcept { return full_duty_nm_; }

 private:
  double full_duty_nm_;
  double max_duty_;
  double deadband_nm_;
  double period_ns_;
  bool positive_only_;
};

}  // namespace lever::board
