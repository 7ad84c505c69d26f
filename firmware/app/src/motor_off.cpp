#include "lever/app/motor_off.hpp"

#include <fmt/format.h>

#include <optional>

#include "lever/app/fw_config.hpp"
#include "lever/app/motor_state.hpp"
#include "lever/board/pwm_motor.hpp"

namespace lever::app {
namespace {

constexpr int kStopped = 0;
constexpr int kNotStopped = 1;

// The hardware a motor configuration drives: two that agree here are the same motor.
bool same_motor(const board::PwmMotorConfig& a, const board::PwmMotorConfig& b) {
  const auto line = [](const std::optional<board::MotorLineConfig>& l) {
    return l ? fmt::format("{}:{}", l->chip, l->line.describe()) : std::string();
  };
  return a.sysfs_root == b.sysfs_root && a.pwm_chip == b.pwm_chip && a.pwm_channel == b.pwm_channel &&
         line(a.enable_line) == line(b.enable_line) && line(a.direction_line) == line(b.direction_line);
}

int stop(const board::PwmMotorConfig& config, const std::string& named_by) {
  auto motor = board::PwmMotor::open(config);
  if (!motor) {
    fmt::print(stderr, "lever-fw: --motor-off: cannot stop the motor {} names: {}\n", named_by, motor.error().message);
    return kNotStopped;
  }
  fmt::print(stderr,
             "lever-fw: --motor-off: {} (named by {}): PWM at duty 0 (enabled: the inactive level), enable line off\n",
             motor.value().description(), named_by);
  return kStopped;
}

int not_stopped(const std::string& why) {
  fmt::print(stderr, "lever-fw: --motor-off: the motor is NOT stopped: {}\n", why);
  return kNotStopped;
}

std::string described(const MotorStateWriter& w) {
  return fmt::format("pid {}, {}", w.pid,
                     w.invocation_id.empty() ? std::string("outside a unit") : "invocation " + w.invocation_id);
}

}  // namespace

int motor_off(const std::string& config_path, const std::string& state_path) {
  const MotorStateWriter self = this_run();
  const bool under_unit = !self.invocation_id.empty();

  if (state_path.empty()) {
    const MotorKeys keys = load_motor_keys(config_path);
    for (const auto& p : keys.problems) fmt::print(stderr, "lever-fw: --motor-off: the configuration: {}\n", p);
    if (!keys.motor) return not_stopped("the configuration's motor keys do not name a motor, and no --motor-state");
    if (!keys.problems.empty()) fmt::print(stderr, "lever-fw: --motor-off: its motor keys read, the rest ignored\n");
    return stop(*keys.motor, "the configuration " + config_path);
  }

  // With a state path, the state alone names the motor: the configuration's may be one this run never opened
  // (edited since, cut short into its defaults, or the run died before its start), and stopping that could
  // disable another lever's PWM under it.
  const MotorState state = read_motor_state(state_path);
  if (!state.found) {
    if (under_unit) {
      // The state is written before anything is opened: without one this run reached no open, so no motor of
      // its own runs. Not a failure of the stop (the main process's own exit says what went wrong).
      fmt::print(stderr,
                 "lever-fw: --motor-off: nothing to stop: this run (invocation {}) wrote no motor state {}, so it "
                 "opened no motor (the state is written before anything is opened); the configuration's motor is "
                 "not this run's and is left alone\n",
                 self.invocation_id, state_path);
      return kStopped;
    }
    return not_stopped("no motor state " + state_path +
                       ": with --motor-state the state names the motor, and outside a unit (no $INVOCATION_ID) a "
                       "missing one cannot mean that nothing was opened; the configuration's motor is left alone "
                       "(without --motor-state it is the one stopped)");
  }
  for (const auto& p : state.problems) fmt::print(stderr, "lever-fw: --motor-off: the motor state: {}\n", p);
  if (!state.motor) {
    return not_stopped("the motor state " + state_path +
                       " names no motor (it is written whole, so this is not a lever's); the configuration's motor "
                       "is not stopped in its place");
  }
  if (!state.writer.boot_id.empty() && !self.boot_id.empty() && state.writer.boot_id != self.boot_id) {
    return not_stopped(
        fmt::format("the motor state {} is STALE: written by {} in another boot ({}, this one {}); "
                    "its motor was reset with the board since",
                    state_path, described(state.writer), state.writer.boot_id, self.boot_id));
  }
  if (under_unit && state.writer.invocation_id != self.invocation_id) {
    return not_stopped(fmt::format(
        "the motor state {} is STALE: written by another run ({}), not this one (invocation {}); this run wrote "
        "none, so it opened nothing, and the motor that state names is not its own to stop (RuntimeDirectory"
        "Preserve=restart keeps an earlier run's state; another lever-fw may have written it)",
        state_path, described(state.writer), self.invocation_id));
  }

  const MotorKeys keys = load_motor_keys(config_path);
  for (const auto& p : keys.problems) fmt::print(stderr, "lever-fw: --motor-off: the configuration: {}\n", p);
  if (keys.motor && !same_motor(*keys.motor, *state.motor)) {
    fmt::print(stderr,
               "lever-fw: --motor-off: the configuration names another motor than the one this lever ran, which "
               "its motor state names: that one is stopped, the configuration's is left alone\n");
  }
  return stop(*state.motor, "the motor state " + state_path);
}

}  // namespace lever::app
