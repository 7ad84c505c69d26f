#include "motor_lines.hpp"

#include <fcntl.h>
#include <linux/gpio.h>
#include <sys/ioctl.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>

namespace lever::board {

namespace {

Error os_error(int err, std::string message) { return Error{std::move(message) + ": " + std::strerror(err), err}; }

enum class Direction { output, input };

struct Found {
  ChipPtr chip;
  gpiod_line* line = nullptr;
  std::string where;  // "motor enable_line (MOT_EN on gpiochip2 [motor])"
};

Result<Found> find(const char* field, const MotorLineConfig& config) {
  ChipPtr chip = open_gpio_chip(config.chip);
  if (!chip) {
    const int err = errno;
    return os_error(err, std::string("motor ") + field + ": cannot open chip \"" + config.chip +
                             "\" (no such path, name or label?)");
  }
  std::string where =
      std::string("motor ") + field + " (" + config.line.describe() + " on " + describe_chip(chip.get()) + ")";
  gpiod_line* line = find_gpio_line(chip.get(), config.line);
  if (line == nullptr) {
    const int err = errno;
    return os_error(err, where + ": " + missing_line_reason(chip.get(), config.line));
  }
  return Found{std::move(chip), line, std::move(where)};
}

// libgpiod 1.6 keeps an output's request to itself; the same ioctl it makes, made here, gives the request as a file
// descriptor. Deasserted from the request on: the driver stays off and the sign positive until a command says so.
Result<UniqueFd> request_output(const Found& found, const MotorLineConfig& config, const std::string& consumer) {
  const std::string device = std::string("/dev/") + gpiod_chip_name(found.chip.get());
  UniqueFd chip(::open(device.c_str(), O_RDWR | O_CLOEXEC));
  if (!chip) {
    const int err = errno;
    return os_error(err, found.where + ": cannot open " + device);
  }
  gpiohandle_request request{};
  request.lineoffsets[0] = gpiod_line_offset(found.line);
  request.lines = 1;
  request.flags = GPIOHANDLE_REQUEST_OUTPUT | (config.active_low ? GPIOHANDLE_REQUEST_ACTIVE_LOW : 0);
  request.default_values[0] = 0;
  const std::size_t n = std::min(consumer.size(), sizeof request.consumer_label - 1);
  std::memcpy(request.consumer_label, consumer.data(), n);
  if (::ioctl(chip.get(), GPIO_GET_LINEHANDLE_IOCTL, &request) < 0) {
    const int err = errno;
    return os_error(err, found.where + ": cannot request it as an output" + line_user_if_busy(found.line, err));
  }
  return UniqueFd(request.fd);
}

std::string describe(const char* field, const Found& found, const MotorLineConfig& config) {
  return std::string(" ") + field + "=" + gpiod_chip_name(found.chip.get()) + ":" +
         std::to_string(gpiod_line_offset(found.line)) + (config.active_low ? "(active-low)" : "");
}

}  // namespace

Result<MotorLines> MotorLines::open(const PwmMotorConfig& config) {
  MotorLines lines;
  struct Wanted {
    const char* field;
    const std::optional<MotorLineConfig>* config;
    std::optional<Output>* slot;
  };
  for (const Wanted& w : {Wanted{"enable_line", &config.enable_line, &lines.enable_},
                          Wanted{"direction_line", &config.direction_line, &lines.direction_}}) {
    if (!*w.config) continue;
    auto found = find(w.field, **w.config);
    if (!found) return found.error();
    auto request = request_output(found.value(), **w.config, config.consumer);
    if (!request) return request.error();
    w.slot->emplace(Output{std::move(request.value()), false});
    lines.description_ += describe(w.field, found.value(), **w.config);
  }
  if (config.fault_line) {
    auto found = find("fault_line", *config.fault_line);
    if (!found) return found.error();
    Found& f = found.value();
    const int flags = config.fault_line->active_low ? GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW : 0;
    if (gpiod_line_request_both_edges_events_flags(f.line, config.consumer.c_str(), flags) < 0) {
      const int err = errno;
      return os_error(err, f.where + ": cannot request its edge events" + line_user_if_busy(f.line, err));
    }
    const int fd = nonblocking_event_fd(f.line);
    if (fd < 0) {
      const int err = errno;
      return os_error(err, f.where + ": cannot make its events non-blocking");
    }
    // After the request, so every change after this read is also an event; one between the request and the read
    // is in both, and its event's type is the level after it.
    const int level = gpiod_line_get_value(f.line);
    if (level < 0) {
      const int err = errno;
      return os_error(err, f.where + ": cannot read its level");
    }
    lines.description_ += describe("fault_line", f, *config.fault_line);
    lines.fault_.emplace(Input{std::move(f.chip), f.line, fd, level != 0});
  }
  return lines;
}

bool MotorLines::set(std::optional<Output>& line, bool asserted) noexcept {
  if (!line) return true;
  if (line->written == asserted) return true;
  if (!set_line_request(line->request.get(), asserted)) {
    line->written.reset();
    return false;
  }
  line->written = asserted;
  return true;
}

bool MotorLines::set_enabled(bool enabled) noexcept { return set(enable_, enabled); }

bool MotorLines::set_negative(bool negative) noexcept { return set(direction_, negative); }

void MotorLines::forget_written() noexcept {
  if (enable_) enable_->written.reset();
  if (direction_) direction_->written.reset();
}

std::optional<bool> MotorLines::fault() noexcept {
  if (!fault_) return false;
  Input& in = *fault_;
  std::array<gpiod_line_event, kKernelEventFifo> events{};
  for (;;) {
    const int n = gpiod_line_event_read_fd_multiple(in.events_fd, events.data(), kKernelEventFifo);
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK) break;
      return std::nullopt;
    }
    // Both edges are requested, so the kernel types each event by the (logical) level it read after the edge.
    if (n > 0) in.asserted = events[static_cast<std::size_t>(n) - 1].event_type == GPIOD_LINE_EVENT_RISING_EDGE;
    if (static_cast<unsigned>(n) < kKernelEventFifo) break;
    // A full FIFO dropped the newest edges, the ones that say the level now: read it once, the one value read on
    // this path (a driver's fault output that changes 16 times between two steps is a fault of its own).
    const int value = gpiod_line_get_value(in.line);
    if (value < 0) return std::nullopt;
    in.asserted = value != 0;
  }
  return in.asserted;
}

bool set_line_request(int request_fd, bool asserted) noexcept {
  gpiohandle_data data{};
  data.values[0] = asserted ? 1 : 0;
  return ::ioctl(request_fd, GPIOHANDLE_SET_LINE_VALUES_IOCTL, &data) == 0;
}

}  // namespace lever::board
