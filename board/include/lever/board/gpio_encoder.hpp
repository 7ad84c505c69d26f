#pragma once
// The lever's quadrature encoder on a Linux board: edge events of the A and B lines (and the rising edges of
// the index line) through libgpiod 1.6, the GPIO v1 kernel interface, handed to the core as an
// EdgeEncoderPort. Decoding and loss detection are EdgeTracker's (edge_tracker.hpp); this class owns the chip
// and the line requests and does the reads: the edge events on the caller's thread, the A/B values for the
// level checks on a thread of its own (SCHED_OTHER), because a value read may wait on the GPIO driver's lock.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "lever/board/edge_tracker.hpp"
#include "lever/board/gpio_encoder_config.hpp"
#include "lever/board/result.hpp"
#include "lever/fw/hal.hpp"

namespace lever::board {

class GpioEncoder {
 public:
  // Opens the chip, requests both edges of A and B (rising of Z) as inputs, non-blocking, reads the A/B levels
  // to start from, and starts the thread that reads them for the level checks. Fails, naming the chip, the line
  // and the reason, when any step does.
  static Result<GpioEncoder> open(const GpioEncoderConfig& config);

  // Move-only: the chip and the line requests have one owner. A moved-from encoder owns nothing and drains
  // nothing; it may only be destroyed or assigned to.
  GpioEncoder(GpioEncoder&&) noexcept;
  GpioEncoder& operator=(GpioEncoder&&) noexcept;
  GpioEncoder(const GpioEncoder&) = delete;
  GpioEncoder& operator=(const GpioEncoder&) = delete;
  ~GpioEncoder();

  // EdgeEncoderPort: every pending event of the three lines, merged by kernel time, as the A/B levels after
  // each edge; `lost` non-zero when edges were lost. Never blocks, never allocates, never reads a value: a few
  // system calls (one read per line while events come, one eventfd write to ask the reader for a level check,
  // whose answer a later drain takes if no A/B edge came in between).
  fw::EdgeDrain drain_edges(fw::EncoderEdge* out, std::size_t capacity) noexcept;

  fw::AbState levels() const noexcept;  // as tracked, after the last delivered edge
  const EdgeStats& stats() const noexcept;
  // "gpiochip1 [enc] A=0 B=1 Z=2", for the log line at start.
  const std::string& description() const noexcept;

 private:
  struct Impl;
  explicit GpioEncoder(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

static_assert(fw::EdgeEncoderPort<GpioEncoder>);

}  // namespace lever::board
