#include "gpio_chip.hpp"

#include <fcntl.h>

#include <cerrno>

namespace lever::board {

ChipPtr open_gpio_chip(const std::string& chip) {
  if (chip.empty()) {
    errno = EINVAL;
    return nullptr;
  }
  if (chip.front() == '/') return ChipPtr(gpiod_chip_open(chip.c_str()));
  if (chip.rfind("gpiochip", 0) == 0) {
    if (gpiod_chip* c = gpiod_chip_open_by_name(chip.c_str())) return ChipPtr(c);
  }
  return ChipPtr(gpiod_chip_open_by_label(chip.c_str()));
}

std::string describe_chip(gpiod_chip* chip) {
  return std::string(gpiod_chip_name(chip)) + " [" + gpiod_chip_label(chip) + "]";
}

gpiod_line* find_gpio_line(gpiod_chip* chip, const LineRef& ref) {
  return ref.is_offset() ? gpiod_chip_get_line(chip, ref.offset_value())
                         : gpiod_chip_find_line(chip, ref.name_value().c_str());
}

std::string missing_line_reason(gpiod_chip* chip, const LineRef& ref) {
  if (ref.is_offset()) return "no such line (the chip has " + std::to_string(gpiod_chip_num_lines(chip)) + ")";
  return "no line of that name on this chip";
}

std::string line_user_if_busy(gpiod_line* line, int err) {
  if (err == EBUSY && gpiod_line_update(line) == 0 && gpiod_line_consumer(line) != nullptr) {
    return std::string(", used by \"") + gpiod_line_consumer(line) + "\"";
  }
  return {};
}

int nonblocking_event_fd(gpiod_line* line) {
  const int fd = gpiod_line_event_get_fd(line);
  if (fd < 0) return -1;
  const int flags = ::fcntl(fd, F_GETFL);
  if (flags < 0 || ::fcntl(fd, F_SETFL, flags | O_NONBLOCK) < 0) return -1;
  return fd;
}

}  // namespace lever::board
