#pragma once
// The lever's motor on a Linux board: the torque's magnitude as the duty cycle of a sysfs PWM channel, its sign
// on a direction line, the driver's enable and fault lines through libgpiod 1.6; a MotorPort for the core.
//
// The motor stops (enable line deasserted, then duty 0 with the PWM kept enabled: the kernel's PWM documentation
// leaves a disabled PWM's output undefined, and duty 0 enabled is the defined inactive level, whatever the
// polarity) on every way out that runs code in this process: the destructor; exit() with the motor still open (an
// atexit hook); and, through emergency_stop_all(), a signal handler (install_motor_stop_signal_handlers() in
// motor_stop_signals.hpp). What stops it when the process cannot run code (kill -9, a kernel panic, power) is the
// board's: docs/board-motor.md.
#include <cstdint>
#include <memory>
#include <string>

#include "lever/board/motor_guard.hpp"
#include "lever/board/pwm_motor_config.hpp"
#include "lever/board/result.hpp"
#include "lever/fw/hal.hpp"

namespace lever::board {

struct PwmMotorStats {
  std::uint64_t commands = 0;
  std::uint64_t failed_commands = 0;    // commands with a write to the PWM or a line that failed
  std::uint64_t fault_read_errors = 0;  // fault line event reads that failed (each reported as a fault)
  std::uint32_t duty_ns = 0;            // as last commanded
  bool negative = false;
  bool enabled = false;
};

class PwmMotor {
 public:
  // Commands: the duty is written at least this often, changed or not, so that a PWM channel gone under a lever
  // at rest fails a write within as many periods (and the motor is released in that command).
  static constexpr unsigned kConfirmEvery = 10;

  // Validates the config, sets up the PWM channel (SysfsPwm: exported if needed, duty 0, disabled while period
  // and polarity are set, then enabled at duty 0), requests the lines (enable and direction deasserted), and registers
  // for the emergency stop. Fails naming the file or line and the reason; at most kMaxStoppableMotors (8) are open at a
  // time.
  static Result<PwmMotor> open(const PwmMotorConfig& config);

  // Move-only. A moved-from motor owns nothing: it may only be destroyed or assigned to. Assigning to a motor
  // stops the one it held.
  PwmMotor(PwmMotor&&) noexcept;
  PwmMotor& operator=(PwmMotor&&) noexcept;
  PwmMotor(const PwmMotor&) = delete;
  PwmMotor& operator=(const PwmMotor&) = delete;
  ~PwmMotor();

  // MotorPort. Enabled: direction (through zero duty when the sign changes), duty, PWM enable, then the
  // driver's enable line, each only once the one before it was written: a failed write releases the motor in
  // the same command and nothing after it is raised. Disabled: the enable line first, then duty 0 with the PWM
  // enabled. Only values that changed are written, each with one pwrite or one ioctl on a file opened at open();
  // no allocation. After an emergency stop every command is a disabled one; a command that was writing when the
  // stop came stops the motor again at its end.
  void command(const fw::MotorCommand& command) noexcept;
  // The fault line asserted, the line unreadable, the last command's writes failed, or an emergency stop.
  bool driver_fault() noexcept;

  const PwmMotorStats& stats() const noexcept;
  // "pwmchip0/pwm1 20000 Hz enable_line=gpiochip1:3 ...", for the log line at start.
  const std::string& description() const noexcept;

  // The files and line request the motor guard keeps a copy of (motor_guard.hpp).
  MotorGuardHandles guard_handles() const noexcept;
  // Someone else (the motor guard) stopped this motor: every value is written again at the next command, none
  // taken as already there.
  void note_external_stop() noexcept;

  // Deasserts the enable line and writes duty 0 and enable 1 (the inactive state) to every open motor in this
  // process, and latches: their later commands are disabled ones. A command in progress on another thread (the
  // loop's, on a multicore board) is waited for first, at most 100 ms, so that none of its writes lands after the
  // stop's and undoes it when the process dies right after (a crash handler). Async-signal-safe: pwrite on files
  // opened beforehand, atomics, clock_gettime, sched_yield and the line's ioctl (its request is a file descriptor
  // of this process).
  static void emergency_stop_all() noexcept;

 private:
  struct Impl;
  explicit PwmMotor(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

static_assert(fw::MotorPort<PwmMotor>);

}  // namespace lever::board
