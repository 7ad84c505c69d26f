#pragma once
// A quadrature encoder on a gpio-sim chip, for a board's program reading it with board::GpioEncoder from
// the same GpioEncoderConfig: a thread of its own moves the A and B lines one Gray-code step at a time (by
// their sysfs pull files, so the reader gets real kernel edge events) toward the count the simulated world
// sets each tick, and raises the index line Z while the count is at the index position.
//
// Never skips a state: a jump of two states is, to the reader, an edge it lost. When the world moves faster
// than max_edge_rate_hz allows (or the thread is held up), the lines run behind the target and catch up at
// that rate; stats().max_backlog says how far behind they got. The rate bounds how fast the reader's FIFOs
// fill (16 events a line in the v1 interface): a board's program draining every 1 ms keeps up with 20 kHz.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "lever/board/gpio_encoder_config.hpp"
#include "lever/board/result.hpp"

namespace lever::hil::devices {

struct EncoderLinesOptions {
  double max_edge_rate_hz = 20000;  // A/B edges per second at most; above 0
  // The count at which Z is asserted (a real index is gated to one quadrature state): the reader sees it rise
  // whenever the count arrives there, from either side. No index pulses without it, or without line_z.
  std::optional<std::int64_t> index_at_count;
};

struct EncoderLinesStats {
  std::uint64_t edges = 0;         // A/B level changes written
  std::int64_t count = 0;          // where the lines are now, in edges from where they were at open()
  std::uint64_t max_backlog = 0;   // the largest |target - count| seen by set_count()
  std::uint64_t index_pulses = 0;  // Z assertions
  std::uint64_t write_errors = 0;  // pull writes that failed (retried 1 ms later)
  std::int64_t last_edge_ns = 0;   // CLOCK_MONOTONIC when the newest edge was written (0: none yet)
};

class EncoderLines {
 public:
  // Resolves the chip (path, gpiochipN or label) and the lines (name or offset) as GpioEncoder does; fails
  // unless they are on a gpio-sim chip. Count 0 is wherever the A/B lines are now (their pulls are set to
  // their current levels); Z is driven to match the count. Then starts the thread.
  static board::Result<EncoderLines> open(const board::GpioEncoderConfig& config, EncoderLinesOptions options = {});

  EncoderLines(EncoderLines&&) noexcept;
  EncoderLines& operator=(EncoderLines&&) noexcept;
  EncoderLines(const EncoderLines&) = delete;
  EncoderLines& operator=(const EncoderLines&) = delete;
  ~EncoderLines();  // stops the thread at once; the lines stay where they are

  // Where the lines should go, in edges (4 per quadrature cycle; forward is Gray order 00 01 11 10 of the A/B
  // levels the reader sees, active_low applied). Lock-free; from any thread, typically the world's tick.
  void set_count(std::int64_t target) noexcept;
  EncoderLinesStats stats() const noexcept;
  // "gpiochip1 [enc] A=0 B=1 Z=2, 20000 edges/s, index at 100"
  const std::string& description() const noexcept;

 private:
  struct Impl;
  explicit EncoderLines(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lever::hil::devices
