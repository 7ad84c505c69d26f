#include "lever/app/motor_off.hpp"

#include <fmt/format.h>

#include "lever/platform/pwm_motor.hpp"

namespace lever::app {

int motor_off(const FwConfig& config) {
  auto motor = platform::PwmMotor::open(motor_config(config.board));
  if (!motor) {
    fmt::print(stderr, "lever-fw: --motor-off: cannot open the motor: {}\n", motor.error().message);
    return 1;
  }
  fmt::print(stderr, "lever-fw: --motor-off: {}: PWM disabled at duty 0, enable line off\n",
             motor.value().description());
  return 0;
}

}  // namespace lever::app
