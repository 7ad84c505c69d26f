#pragma once
// The motor driver's GPIO lines through libgpiod 1.6: enable and direction as outputs, the fault output as an
// input, each optional. Requested at open with enable and direction deasserted; released when this object
// goes (the kernel then leaves an output's level to the GPIO controller: docs/board-motor.md).
#include <gpiod.h>

#include <optional>
#include <string>

#include "gpio_chip.hpp"
#include "lever/platform/pwm_motor_config.hpp"
#include "lever/platform/result.hpp"

namespace lever::platform {

class MotorLines {
 public:
  static Result<MotorLines> open(const PwmMotorConfig& config);

  // Each sets its line only when the value differs from the last one set; true with no such line; false
  // when setting failed (the level is then unknown, and the next call sets it again).
  bool set_enabled(bool enabled) noexcept;
  bool set_negative(bool negative) noexcept;
  // The fault input's asserted state; false with no fault line; empty when it could not be read.
  std::optional<bool> fault() noexcept;

  // " enable=gpiochip1[motor]:3 direction=... fault=...", for the log line at start.
  const std::string& description() const noexcept { return description_; }

 private:
  MotorLines() = default;

  struct Line {
    ChipPtr chip;  // one per line: the lines of a driver may sit on different chips
    gpiod_line* line = nullptr;
    std::optional<bool> written;  // outputs: the last value set, asserted = true
  };
  bool set(std::optional<Line>& line, bool asserted) noexcept;

  std::optional<Line> enable_;
  std::optional<Line> direction_;
  std::optional<Line> fault_;
  std::string description_;
};

}  // namespace lever::platform
