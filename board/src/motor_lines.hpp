#pragma once
// The motor driver's GPIO lines: enable and direction as outputs, the fault output as an input, each optional. Found
// through libgpiod 1.6; the outputs requested with the kernel's line-handle ioctl itself, so that their request is a
// file descriptor this process can share: the motor guard (motor_guard.hpp) holds a copy of the enable line's and
// deasserts it when the lever dies, and a signal handler can set it (an ioctl, async-signal-safe). Requested at open
// with enable and direction deasserted; released when the last holder of the request closes it (the kernel then
// leaves an output's level to the GPIO controller: docs/board-motor.md).
#include <gpiod.h>

#include <optional>
#include <string>

#include "gpio_chip.hpp"
#include "lever/board/pwm_motor_config.hpp"
#include "lever/board/result.hpp"
#include "lever/board/unique_fd.hpp"

namespace lever::board {

class MotorLines {
 public:
  static Result<MotorLines> open(const PwmMotorConfig& config);

  // Each sets its line only when the value differs from the last one set; true with no such line; false
  // when setting failed (the level is then unknown, and the next call sets it again).
  bool set_enabled(bool enabled) noexcept;
  bool set_negative(bool negative) noexcept;
  // The next set_* writes whatever it wrote before: another process (the motor guard) may have set the lines since.
  void forget_written() noexcept;
  // The fault input's asserted state as its edge events say (false with no fault line; empty when they could not
  // be read): no call reads the line's value, which on a driver that sleeps (gpio-sim, an I2C or SPI expander)
  // takes the chip's mutex, so the loop never waits on another holder of it (docs/board-motor.md).
  std::optional<bool> fault() noexcept;

  // The enable line's request (-1: none): GPIOHANDLE_SET_LINE_VALUES_IOCTL with 0 deasserts it, active-low or not.
  int enable_request_fd() const noexcept { return enable_ ? enable_->request.get() : -1; }

  // " enable=gpiochip1[motor]:3 direction=... fault=...", for the log line at start.
  const std::string& description() const noexcept { return description_; }

 private:
  MotorLines() = default;

  struct Output {
    UniqueFd request;             // the line handle; the line is the request's only line
    std::optional<bool> written;  // the last value set, asserted = true
  };
  struct Input {
    ChipPtr chip;  // one per line: the lines of a driver may sit on different chips
    gpiod_line* line = nullptr;
    int events_fd = -1;  // the line's edge events, non-blocking; owned by the line's request
    bool asserted = false;
  };
  static bool set(std::optional<Output>& line, bool asserted) noexcept;

  std::optional<Output> enable_;
  std::optional<Output> direction_;
  std::optional<Input> fault_;
  std::string description_;
};

// One line handle's only line set, asserted or not: one ioctl, async-signal-safe; false when it failed.
bool set_line_request(int request_fd, bool asserted) noexcept;

}  // namespace lever::board
