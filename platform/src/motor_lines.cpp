#include "motor_lines.hpp"

#include <cerrno>
#include <cstring>

namespace lever::platform {

namespace {

Error os_error(int err, std::string message) { return Error{std::move(message) + ": " + std::strerror(err), err}; }

enum class Direction { output, input };

struct Requested {
  ChipPtr chip;
  gpiod_line* line = nullptr;
  std::string text;
};

// Outputs start deasserted: the driver stays off and the sign positive until the first command says otherwise.
Result<Requested> request(const char* field, const MotorLineConfig& config, Direction direction,
                          const std::string& consumer) {
  ChipPtr chip = open_gpio_chip(config.chip);
  if (!chip) {
    const int err = errno;
    return os_error(err, std::string("motor ") + field + ": cannot open chip \"" + config.chip +
                             "\" (no such path, name or label?)");
  }
  const std::string chip_text = describe_chip(chip.get());
  const std::string where = std::string("motor ") + field + " (" + config.line.describe() + " on " + chip_text + ")";
  gpiod_line* line = find_gpio_line(chip.get(), config.line);
  if (line == nullptr) {
    const int err = errno;
    return os_error(err, where + ": " + missing_line_reason(chip.get(), config.line));
  }
  const int flags = config.active_low ? GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW : 0;
  const int rc = direction == Direction::output ? gpiod_line_request_output_flags(line, consumer.c_str(), flags, 0)
                                                : gpiod_line_request_input_flags(line, consumer.c_str(), flags);
  if (rc < 0) {
    const int err = errno;
    return os_error(err, where + ": cannot request it as an " + (direction == Direction::output ? "output" : "input") +
                             line_user_if_busy(line, err));
  }
  std::string text = std::string(field) + "=" + gpiod_chip_name(chip.get()) + ":" +
                     std::to_string(gpiod_line_offset(line)) + (config.active_low ? "(active-low)" : "");
  return Requested{std::move(chip), line, std::move(text)};
}

}  // namespace

Result<MotorLines> MotorLines::open(const PwmMotorConfig& config) {
  MotorLines lines;
  struct Wanted {
    const char* field;
    const std::optional<MotorLineConfig>* config;
    Direction direction;
    std::optional<Line>* slot;
  };
  for (const Wanted& w : {Wanted{"enable_line", &config.enable_line, Direction::output, &lines.enable_},
                          Wanted{"direction_line", &config.direction_line, Direction::output, &lines.direction_},
                          Wanted{"fault_line", &config.fault_line, Direction::input, &lines.fault_}}) {
    if (!*w.config) continue;
    auto requested = request(w.field, **w.config, w.direction, config.consumer);
    if (!requested) return requested.error();
    Requested& r = requested.value();
    std::optional<bool> written;
    if (w.direction == Direction::output) written = false;
    w.slot->emplace(Line{std::move(r.chip), r.line, written});
    lines.description_ += " " + r.text;
  }
  return lines;
}

bool MotorLines::set(std::optional<Line>& line, bool asserted) noexcept {
  if (!line) return true;
  if (line->written == asserted) return true;
  if (gpiod_line_set_value(line->line, asserted ? 1 : 0) < 0) {
    line->written.reset();
    return false;
  }
  line->written = asserted;
  return true;
}

bool MotorLines::set_enabled(bool enabled) noexcept { return set(enable_, enabled); }

bool MotorLines::set_negative(bool negative) noexcept { return set(direction_, negative); }

std::optional<bool> MotorLines::fault() noexcept {
  if (!fault_) return false;
  const int value = gpiod_line_get_value(fault_->line);
  if (value < 0) return std::nullopt;
  return value != 0;
}

}  // namespace lever::platform
