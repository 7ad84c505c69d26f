#pragma once
// One line of a gpio-sim chip as the simulated world reaches it, from the outside: its sysfs
// sim_gpio<offset>/value shows the line's level (what a consumer drives on an output, the pull on an input),
// and writing pull-up or pull-down to sim_gpio<offset>/pull drives an input as the wire from a device would.
// Both files are kept open, and each access is one pread or pwrite: the world touches them every tick.
#include <optional>
#include <string>

#include "lever/board/line_ref.hpp"
#include "lever/board/result.hpp"
#include "lever/board/unique_fd.hpp"

namespace lever::hil::devices {

class SimLine {
 public:
  // `chip` as the board's config gives it (a path, a gpiochipN name, or a label), `line` by name or offset;
  // `field` names the config field in messages ("line_a", "fault_line"). Fails unless the chip is a gpio-sim
  // chip (a sysfs directory /sys/devices/platform/gpio-sim.*/gpiochipN/) and the line is on it.
  static board::Result<SimLine> open(const std::string& chip, const board::LineRef& line, const std::string& field);

  // The physical level; empty when the file could not be read.
  std::optional<bool> level() const noexcept;
  // Sets the pull, so the level of a line no consumer drives as an output. False when the write failed.
  bool drive(bool high) noexcept;

  unsigned offset() const noexcept { return offset_; }
  const std::string& description() const noexcept { return description_; }            // "gpiochip1 [enc] 0"
  const std::string& chip_description() const noexcept { return chip_description_; }  // "gpiochip1 [enc]"

 private:
  SimLine() = default;
  board::UniqueFd value_;
  board::UniqueFd pull_;
  unsigned offset_ = 0;
  std::string description_;
  std::string chip_description_;
};

}  // namespace lever::hil::devices
