#pragma once
// Where the lever's quadrature encoder is wired: a GPIO chip and its A, B and optional index (Z) lines, as the
// board's config names them.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "lever/board/line_ref.hpp"

namespace lever::board {

struct GpioEncoderConfig {
  // "/dev/gpiochip2" (a path), "gpiochip2" (a name), or the chip's label ("20ac000.gpio", "enc").
  std::string chip;
  LineRef line_a;
  LineRef line_b;
  std::optional<LineRef> line_z;
  bool active_low = false;            // all three lines; the levels and edge types the decoder sees are then inverted
  std::string consumer = "lever-fw";  // shown by gpioinfo; the kernel keeps 31 characters
  // How long an edge may take to show: from the level change to its timestamp (interrupt latency), and from
  // the timestamp to the event FIFO (the kernel's interrupt thread). Edges younger than this wait for the next
  // drain (the other line may still deliver an older one), and a line read within this time of an edge may
  // show either level without counting as a loss.
  std::uint32_t edge_latency_us = 50;

  // Every problem, each naming its field ("line_b: ..."); empty when the config can be opened.
  std::vector<std::string> validate() const;
};

}  // namespace lever::board
