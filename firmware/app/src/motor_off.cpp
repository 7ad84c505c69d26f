#include "lever/app/motor_off.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <optional>

#include "lever/app/fw_config.hpp"
#include "lever/platform/pwm_motor.hpp"

namespace lever::app {
namespace {

// The hardware a motor configuration drives: two that agree here are the same motor.
bool same_motor(const platform::PwmMotorConfig& a, const platform::PwmMotorConfig& b) {
  const auto line = [](const std::optional<platform::MotorLineConfig>& l) {
    return l ? fmt::format("{}:{}", l->chip, l->line.describe()) : std::string();
  };
  return a.sysfs_root == b.sysfs_root && a.pwm_chip == b.pwm_chip && a.pwm_channel == b.pwm_channel &&
         line(a.enable_line) == line(b.enable_line) && line(a.direction_line) == line(b.direction_line);
}

bool stop(const platform::PwmMotorConfig& config, const char* named_by) {
  auto motor = platform::PwmMotor::open(config);
  if (!motor) {
    fmt::print(stderr, "lever-fw: --motor-off: cannot stop the motor {} names: {}\n", named_by, motor.error().message);
    return false;
  }
  fmt::print(stderr, "lever-fw: --motor-off: {} (named by {}): PWM at duty 0 (enabled: the inactive level), enable line off\n",
             motor.value().description(), named_by);
  return true;
}

}  // namespace

int motor_off(const std::string& config_path, const std::string& state_path) {
  const MotorKeys keys = load_motor_keys(config_path);
  for (const auto& p : keys.problems) fmt::print(stderr, "lever-fw: --motor-off: the configuration: {}\n", p);

  // The state first: it is the running lever's own record of the motor it drove. The configuration may have been
  // changed since (a file cut short can even be valid TOML, its motor keys then the defaults: another motor).
  std::optional<MotorKeys> state;
  if (!state_path.empty() && (!keys.motor || ::access(state_path.c_str(), F_OK) == 0)) {
    state = load_motor_keys(state_path);
    for (const auto& p : state->problems) fmt::print(stderr, "lever-fw: --motor-off: the motor state: {}\n", p);
  }
  if (state && state->motor) {
    if (keys.motor && !same_motor(*keys.motor, *state->motor)) {
      fmt::print(stderr,
                 "lever-fw: --motor-off: the configuration names another motor than the one this lever ran, which "
                 "its motor state names: that one is stopped, the configuration's is left alone\n");
    }
    return stop(*state->motor, ("the motor state " + state_path).c_str()) ? 0 : 1;
  }
  if (keys.motor) {
    if (!keys.problems.empty()) fmt::print(stderr, "lever-fw: --motor-off: its motor keys read, the rest ignored\n");
    return stop(*keys.motor, ("the configuration " + config_path).c_str()) ? 0 : 1;
  }
  fmt::print(stderr,
             "lever-fw: --motor-off: the motor is NOT stopped: the configuration's motor keys cannot be read, {}\n",
             state_path.empty() ? std::string("and no --motor-state names a state file")
                                : "nor the motor state " + state_path + "'s");
  return 1;
}

}  // namespace lever::app
