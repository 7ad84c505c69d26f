#pragma once
// Telling silence from loss on a deadband link: sequence numbers, tick unwrapping and a watchdog.
#include <cstdint>

#include "lever/fw/tick.hpp"

namespace lever::fw {

// Per-direction data sequence numbers (8 bits on the wire).
class SequenceTracker {
 public:
  enum class Verdict : std::uint8_t { first, in_order, after_gap, stale };

  // stale: a duplicate or a frame older than the newest accepted one (reordered); it must not be used, or
  // the receiver's model would go back in time.
  constexpr Verdict observe(std::uint8_t seq) noexcept {
    if (!started_) {
      started_ = true;
      last_ = seq;
      return Verdict::first;
    }
    const auto ahead = static_cast<std::uint8_t>(seq - last_);
    if (ahead == 0 || ahead >= 128) {
      ++stale_;
      return Verdict::stale;
    }
    last_ = seq;
    if (ahead == 1) return Verdict::in_order;
    gaps_ += ahead - 1u;
    return Verdict::after_gap;
  }

  // A new stream from the sender: its next number is the first, whatever it is. The counts stay.
  constexpr void restart() noexcept { started_ = false; }

  constexpr std::uint8_t last() const noexcept { return last_; }
  constexpr std::uint32_t missing() const noexcept { return gaps_; }
  constexpr std::uint32_t stale() const noexcept { return stale_; }

 private:
  bool started_ = false;
  std::uint8_t last_ = 0;
  std::uint32_t gaps_ = 0;
  std::uint32_t stale_ = 0;
};

// The sender's 16-bit tick extended to 64 bits; valid while frames are less than 32 s apart, which the
// periodic refresh guarantees while a stream lives. A tick that does not advance means the sender restarted
// (its restart frame was lost) or the frame predates a reset: the extension then starts over at the new tick
// instead of stepping back, so it only ever grows from a 16-bit start and can neither underflow nor wrap.
class TickUnwrapper {
 public:
  struct Unwrapped {
    Tick tick = 0;
    bool restarted = false;  // the sender's clock did not advance: its earlier samples are another stream
  };

  constexpr Unwrapped unwrap(std::uint16_t tick) noexcept {
    if (!started_) {
      started_ = true;
      last_ = tick;
      extended_ = tick;
      return {extended_, false};
    }
    const auto delta = static_cast<std::int16_t>(static_cast<std::uint16_t>(tick - last_));
    last_ = tick;
    if (delta <= 0) {
      extended_ = tick;
      return {extended_, true};
    }
    extended_ += static_cast<Tick>(delta);
    return {extended_, false};
  }
  constexpr void reset() noexcept { started_ = false; }

 private:
  bool started_ = false;
  std::uint16_t last_ = 0;
  Tick extended_ = 0;
};

// Any valid frame from the peer proves it alive. Silence longer than the timeout is a fault.
class Watchdog {
 public:
  constexpr void heard(Tick now) noexcept {
    last_ = now;
    ever_ = true;
  }
  constexpr bool silent(Tick now, Tick timeout) const noexcept { return !ever_ || now - last_ > timeout; }
  constexpr bool ever_heard() const noexcept { return ever_; }
  constexpr Tick last_heard() const noexcept { return last_; }

 private:
  Tick last_ = 0;
  bool ever_ = false;
};

}  // namespace lever::fw
