#pragma once
// One Linux PWM channel through sysfs (<root>/class/pwm/pwmchipN/pwmM/): exported and configured once, then
// driven by writes on the two files the loop needs, held open. The motor's magnitude channel.
#include <cstdint>
#include <optional>
#include <string>

#include "lever/board/pwm_motor_config.hpp"
#include "lever/board/result.hpp"
#include "lever/board/unique_fd.hpp"

namespace lever::board {

class SysfsPwm {
 public:
  // Exports the channel unless pwmM/ is there already (left exported by an earlier run or a boot script: it
  // is taken over as found), waits for its attributes, and writes duty_cycle 0, enable 0, period, polarity and
  // enable 1, in the order the kernel accepts from any earlier state: the channel is left enabled at duty 0.
  static Result<SysfsPwm> open(const PwmMotorConfig& config);

  // Each writes only when the value differs from the last one written; false when the write failed (the
  // value is then unknown, and the next call writes again). One pwrite, no allocation.
  bool set_duty_ns(std::uint32_t ns) noexcept;
  bool set_enabled(bool enabled) noexcept;
  // The next set_duty_ns writes even the value last written: the kernel's PWM core takes an unchanged state
  // without touching the hardware, and the write proves the channel is still there.
  void confirm_duty_next() noexcept { duty_written_.reset(); }
  // The next writes happen whatever was written before: another process (the motor guard) may have written since.
  void forget_written() noexcept {
    duty_written_.reset();
    enabled_written_.reset();
  }
  // The enable attribute read back (one pread, no allocation) against the value last written: another process
  // may write it (another instance's --motor-off), and the write-once cache would never see it. False when it
  // differs or cannot be read; the value last written is then forgotten, as after a failed write, so that the
  // next set_enabled writes again. True when no value is known to compare with.
  bool enable_as_written() noexcept;
  // The inactive state: duty 0, then enabled, written whatever was written before. Not disabled: the kernel's
  // PWM documentation leaves a disabled channel's output undefined (some controllers hold the pin where it was,
  // others drive it low, which an inverting board turns into full duty at the driver); enabled at duty 0 the pin
  // sits at its inactive level whatever the polarity.
  void stop() noexcept;

  // For the emergency stop, which writes to them from a signal handler.
  int duty_fd() const noexcept { return duty_.get(); }
  int enable_fd() const noexcept { return enable_.get(); }
  const std::string& description() const noexcept { return description_; }  // "pwmchip0/pwm1"

 private:
  SysfsPwm(UniqueFd duty, UniqueFd enable, std::string description) noexcept;

  UniqueFd duty_;
  UniqueFd enable_;
  std::optional<std::uint32_t> duty_written_;
  std::optional<bool> enabled_written_;
  std::string description_;
};

}  // namespace lever::board
