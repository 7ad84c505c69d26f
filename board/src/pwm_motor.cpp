#include "lever/board/pwm_motor.hpp"

#include <cerrno>
#include <utility>

#include "lever/board/config_error.hpp"
#include "lever/board/torque_to_duty.hpp"
#include "motor_lines.hpp"
#include "motor_stop_registry.hpp"
#include "sysfs_pwm.hpp"

namespace lever::board {

struct PwmMotor::Impl {
  SysfsPwm pwm;
  MotorLines lines;
  TorqueToDuty map;
  int stop_slot;
  PwmMotorStats stats;
  bool last_command_failed = false;
  unsigned commands_since_confirm = 0;
  std::string description;

  Impl(SysfsPwm p, MotorLines l, const PwmMotorConfig& config, int slot, std::string d)
      : pwm(std::move(p)), lines(std::move(l)), map(config), stop_slot(slot), description(std::move(d)) {}
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  // Stopped before leaving the emergency stop's table: no moment without one or the other. The files close
  // after this body, once the table no longer holds them.
  ~Impl() {
    lines.set_enabled(false);
    pwm.stop();
    unregister_motor_stop(stop_slot);
  }

  bool drive(DutySetpoint setpoint) noexcept {
    if (setpoint.duty_ns > 0 && setpoint.negative != stats.negative) {
      // Through zero: the new direction never runs at the old duty, nor the old direction at the new one; and
      // a direction that could not be set gets no duty at all.
      if (!pwm.set_duty_ns(0) || !lines.set_negative(setpoint.negative)) return false;
      stats.negative = setpoint.negative;
    }
    // Each step only after the one before it took: a PWM in an unknown state is never enabled, nor the driver
    // behind it.
    return pwm.set_duty_ns(setpoint.duty_ns) && pwm.set_enabled(true) && lines.set_enabled(true);
  }

  // The driver's enable line first (the fastest way to stop it), then the PWM's inactive state: duty 0 with the
  // channel enabled, never disabled (SysfsPwm::stop says why).
  bool release() noexcept {
    bool ok = lines.set_enabled(false);
    ok &= pwm.set_duty_ns(0);
    ok &= pwm.set_enabled(true);
    return ok;
  }

  // After an emergency stop that came while this command wrote: its writes, whatever the last ones were.
  void stop_again() noexcept {
    lines.set_enabled(false);
    pwm.stop();
  }
};

PwmMotor::PwmMotor(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
PwmMotor::PwmMotor(PwmMotor&&) noexcept = default;
PwmMotor& PwmMotor::operator=(PwmMotor&&) noexcept = default;
PwmMotor::~PwmMotor() = default;

Result<PwmMotor> PwmMotor::open(const PwmMotorConfig& config) {
  if (const auto problems = config.validate(); !problems.empty()) return config_error("motor config", problems);
  auto pwm = SysfsPwm::open(config);
  if (!pwm) return pwm.error();
  auto lines = MotorLines::open(config);
  if (!lines) return lines.error();
  const int slot =
      register_motor_stop(pwm.value().duty_fd(), pwm.value().enable_fd(), lines.value().enable_request_fd());
  if (slot < 0) {
    return Error{"motor " + pwm.value().description() + ": " + std::to_string(kMaxStoppableMotors) +
                     " motors are open already (the emergency stop has room for no more)",
                 EMFILE};
  }
  std::string description = pwm.value().description() + " " + std::to_string(1'000'000'000u / config.period_ns) +
                            " Hz" + (config.pwm_inversed ? " inversed" : "") + lines.value().description();
  return PwmMotor(
      std::make_unique<Impl>(std::move(pwm.value()), std::move(lines.value()), config, slot, std::move(description)));
}

void PwmMotor::command(const fw::MotorCommand& command) noexcept {
  if (!impl_) return;
  Impl& m = *impl_;
  ++m.stats.commands;
  begin_motor_command(m.stop_slot);
  const bool enable = command.enable && !emergency_stop_latched();
  const DutySetpoint setpoint = enable ? m.map(command.torque_nm) : DutySetpoint{};
  // Only changed values are written, so a lever at rest writes nothing and would not notice its PWM channel
  // gone (unexported, its driver unbound) until the duty changed; every kConfirmEvery-th command writes it.
  // The enable is confirmed by reading it back: it is written only when it changes, and another process may
  // write it (another instance's --motor-off). One that differs from this lever's last write counts as a failed
  // write: the motor is released in this command, not driven first, and driver_fault() reports it.
  bool enable_held = true;
  if (++m.commands_since_confirm >= kConfirmEvery) {
    m.commands_since_confirm = 0;
    m.pwm.confirm_duty_next();
    enable_held = m.pwm.enable_as_written();
  }
  bool ok = (enable && enable_held ? m.drive(setpoint) : m.release()) && enable_held;
  // A duty that could not be written is not driven: the driver goes off in this call, a period before the core
  // would see driver_fault() and latch motor_driver, and never stays enabled behind a PWM in an unknown state.
  bool driven = enable && ok;
  if (enable && !ok) m.release();
  if (enable && emergency_stop_latched()) {
    m.stop_again();
    driven = false;
  }
  end_motor_command(m.stop_slot);
  m.stats.duty_ns = driven ? setpoint.duty_ns : 0;
  m.stats.enabled = driven;
  m.last_command_failed = !ok;
  if (!ok) ++m.stats.failed_commands;
}

bool PwmMotor::driver_fault() noexcept {
  if (!impl_) return true;
  Impl& m = *impl_;
  const std::optional<bool> fault = m.lines.fault();
  if (!fault) ++m.stats.fault_read_errors;
  return !fault || *fault || m.last_command_failed || emergency_stop_latched();
}

const PwmMotorStats& PwmMotor::stats() const noexcept {
  static const PwmMotorStats none{};
  return impl_ ? impl_->stats : none;
}

const std::string& PwmMotor::description() const noexcept {
  static const std::string moved = "(moved from)";
  return impl_ ? impl_->description : moved;
}

MotorGuardHandles PwmMotor::guard_handles() const noexcept {
  if (!impl_) return {};
  return {impl_->pwm.duty_fd(), impl_->pwm.enable_fd(), impl_->lines.enable_request_fd()};
}

void PwmMotor::note_external_stop() noexcept {
  if (!impl_) return;
  impl_->pwm.forget_written();
  impl_->lines.forget_written();
}

void PwmMotor::emergency_stop_all() noexcept { emergency_stop_registered_motors(); }

}  // namespace lever::board
