#pragma once
// Opening a GPIO chip and finding its lines through libgpiod 1.6, as every GPIO backend here does it, with the
// words their error messages share.
#include <gpiod.h>

#include <cstddef>
#include <memory>
#include <string>

#include "lever/board/line_ref.hpp"

namespace lever::board {

struct ChipCloser {
  // Closing the chip also releases every line requested through it.
  void operator()(gpiod_chip* chip) const noexcept { gpiod_chip_close(chip); }
};
using ChipPtr = std::unique_ptr<gpiod_chip, ChipCloser>;

// The kernel's consumer label holds 32 bytes with the terminating zero; a longer one is cut silently.
inline constexpr std::size_t kMaxGpioConsumer = 31;

// A path, a gpiochipN name, or else a label; nullptr with errno set when none opens. libgpiod's own lookup
// would also take a bare number, which a config should not mean silently.
ChipPtr open_gpio_chip(const std::string& chip);

// "gpiochip1 [enc]", for messages.
std::string describe_chip(gpiod_chip* chip);

// The line `ref` names on `chip`; nullptr with errno set when there is none.
gpiod_line* find_gpio_line(gpiod_chip* chip, const LineRef& ref);
// Why find_gpio_line() found nothing: "no such line (the chip has 3)", "no line of that name on this chip".
std::string missing_line_reason(gpiod_chip* chip, const LineRef& ref);
// After a request failed with `err`: ", used by \"name\"" when the line is busy and its user is known.
std::string line_user_if_busy(gpiod_line* line, int err);

// The v1 interface's per-line event FIFO (gpiolib-cdev.c: DECLARE_KFIFO(events, struct gpioevent_data, 16); when
// full, the newest events are dropped). A read asking for this many that gets them all has found the FIFO full.
inline constexpr unsigned kKernelEventFifo = 16;

// The event file of a line requested for its edges, made non-blocking, so that a step never waits for an edge;
// -1 with errno set when that failed.
int nonblocking_event_fd(gpiod_line* line);

}  // namespace lever::board
