#pragma once
// The motor driver as the simulated world sees it: what the board's program (board::PwmMotor, from the same
// PwmMotorConfig) drives, read back as a torque. The PWM side is a sysfs tree of regular files under the
// config's sysfs_root, which this makes and PwmMotor writes unchanged; the enable, direction and fault lines
// are lines of a gpio-sim chip, whose sysfs attributes show what PwmMotor drives and let the world drive the
// fault input.
//
// Without lines in the config no gpio-sim is needed (a host test, a PWM bring-up config).
#include <cstdint>
#include <memory>
#include <string>

#include "lever/board/pwm_motor_config.hpp"
#include "lever/board/result.hpp"

namespace lever::hil::devices {

struct MotorReading {
  // The driver's torque: duty * full_scale_current_a * torque_constant_nm_per_a * gear_ratio (the inverse of
  // the board layer's TorqueToDuty), negative when the direction line is asserted; 0 unless `enabled`.
  double torque_nm = 0.0;
  bool enabled = false;   // the driver's enable line asserted (always, without one); the PWM's enable flag is not
                          // asked: a disabled PWM's pin is undefined, and may hold high
  double duty = 0.0;      // the fraction of the period the driver's input is high: the PWM pin's output (enabled,
                          // duty_cycle / period, 1 - that inversed; disabled, held high if it was high at all),
                          // turned over when the board inverts it (pwm_inversed)
  bool negative = false;  // the direction line asserted (false without one)
};

// What the board's GPIO controller does with an output its program released (closed, or the program died): most
// SoC controllers keep driving its last level, which is the hazard the unit's ExecStopPost exists for; a
// controller that frees a pin to an input leaves it to the board's resistor. gpio-sim does the latter (its
// `free` sets the line to its pull); `hold` makes it do the former.
enum class ReleasedLines {
  hold,  // the enable and direction lines keep their last level: their pull follows what the program drives
  pull,  // they fall to the board's resistor (deasserted)
};

class MotorReadback {
 public:
  // Validates the config as PwmMotor does; refuses a sysfs_root that is /sys or under it; makes the PWM tree
  // (make_fake_pwm_channel: what exists is kept, what is missing made disabled); finds the lines on their
  // gpio-sim chips; sets the enable and direction lines' pulls to deasserted (the board's resistors: the level
  // they show before any program drives them, and with ReleasedLines::pull again after one is done with them)
  // and drives the fault input deasserted. Fails naming the file or field and the reason.
  //
  // With ReleasedLines::hold each read() that finds an output line at a level its pull does not give sets the
  // pull to it, so that when the program releases the line gpio-sim leaves it there. The level is sampled: one
  // a program drives for less than the time between two reads and then releases is not seen, and the line keeps
  // the level it had before.
  static board::Result<MotorReadback> open(const board::PwmMotorConfig& config,
                                           ReleasedLines released = ReleasedLines::hold);

  MotorReadback(MotorReadback&&) noexcept;
  MotorReadback& operator=(MotorReadback&&) noexcept;
  MotorReadback(const MotorReadback&) = delete;
  MotorReadback& operator=(const MotorReadback&) = delete;
  ~MotorReadback();

  // One pread per attribute and line, on files held open (and a pwrite when a held line's level changed); no
  // allocation. The world calls it every tick. A value that cannot be read or parsed (counted in read_errors())
  // is taken as last read.
  MotorReading read() noexcept;

  // Asserts (or releases) the driver's fault output: drives the fault line to its asserted level (respecting
  // active_low). False when there is no fault line or the write failed.
  bool set_fault(bool asserted) noexcept;

  std::uint64_t read_errors() const noexcept;
  // "pwmchip0/pwm1 under /tmp/hil/top-sys, enable_line gpiochip1 [motor] 0, ..."
  const std::string& description() const noexcept;

 private:
  struct Impl;
  explicit MotorReadback(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lever::hil::devices
