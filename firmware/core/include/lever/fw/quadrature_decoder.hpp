#pragma once
// Software quadrature decoder for an incremental encoder whose A/B edges arrive as events (libgpiod on the
// board, the simulated encoder in the HIL).
#include <cstdint>
#include <optional>

#include "lever/fw/hal.hpp"  // AbState, EncoderEdge

namespace lever::fw {

class QuadratureDecoder {
 public:
  struct Config {
    std::uint32_t illegal_threshold = 8;  // illegal transitions tolerated before the fault latches
  };

  constexpr QuadratureDecoder() noexcept : QuadratureDecoder(Config{}) {}
  explicit constexpr QuadratureDecoder(const Config& config) noexcept : config_(config) {}

  // Start from the lines' current levels without counting.
  constexpr void reset(AbState levels) noexcept {
    state_ = levels & 3u;
    primed_ = true;
  }

  // One observed level change. Gray-code order 00 -> 01 -> 11 -> 10 -> 00 in (A, B) counts up: B leads A
  // (B rises while A is low). Before reset() the first edge only sets the state, so start with reset().
  constexpr void feed(AbState levels) noexcept {
    levels &= 3u;
    ++edges_;
    if (!primed_) {
      reset(levels);
      return;
    }
    const int step = kTransition[state_][levels];
    if (step == kIllegal) {
      // Both lines changed at once: an edge was missed, the direction is unknown, the count is now off.
      if (illegal_ != UINT32_MAX) ++illegal_;
    } else {
      counts_ += step;
    }
    state_ = levels;
  }

  // An edge with its index flag: the index marks the count at which the Z line rose.
  constexpr void feed(const EncoderEdge& edge) noexcept {
    feed(edge.levels);
    if (edge.index) index_counts_ = counts_;
  }

  // The source knows it dropped edges: the count is off by an unknown amount, whatever the levels say.
  constexpr void note_lost(std::uint32_t edges) noexcept {
    if (edges == 0) return;
    lost_ = lost_ > UINT32_MAX - edges ? UINT32_MAX : lost_ + edges;
  }

  constexpr std::int32_t counts() const noexcept { return counts_; }
  constexpr std::uint64_t edges() const noexcept { return edges_; }  // fed since power-up
  constexpr std::uint32_t illegal_transitions() const noexcept { return illegal_; }
  constexpr std::uint32_t lost_edges() const noexcept { return lost_; }
  constexpr bool fault() const noexcept { return illegal_ > config_.illegal_threshold || lost_ > 0; }
  // Re-arming or homing after an encoder fault restarts the tallies; the position stays invalid until the
  // lever is homed again (EncoderPosition), since the count itself is off.
  constexpr void clear_fault() noexcept {
    illegal_ = 0;
    lost_ = 0;
  }

  // The count at the newest index edge since the last call, once.
  constexpr std::optional<std::int32_t> take_index() noexcept {
    const auto i = index_counts_;
    index_counts_.reset();
    return i;
  }

 private:
  static constexpr int kIllegal = 2;
  // [previous][current] in (A<<1)|B coding: 0=00, 1=01, 2=10, 3=11.
  static constexpr int kTransition[4][4] = {
      {0, +1, -1, kIllegal},  // from 00
      {-1, 0, kIllegal, +1},  // from 01
      {+1, kIllegal, 0, -1},  // from 10
      {kIllegal, -1, +1, 0},  // from 11
  };

  Config config_;
  AbState state_ = 0;
  bool primed_ = false;
  std::int32_t counts_ = 0;
  std::uint32_t illegal_ = 0;
  std::uint32_t lost_ = 0;
  std::uint64_t edges_ = 0;
  std::optional<std::int32_t> index_counts_;
};

// A hardware counter of `bits` width (16 for most MCU timers, 32 for a kernel counter device) extended to
// 64 bits by sign-extended differences: a 16-bit timer wraps every 4 turns of a 16384-count encoder, and
// taking its raw value as the count would jump by 65536 at each wrap. Valid while it is read at least once
// per half a wrap (32768 counts at 16 bits: 2 turns per millisecond, far beyond any hand).
class CounterUnwrapper {
 public:
  explicit constexpr CounterUnwrapper(std::uint8_t bits = 32) noexcept
      : mask_(bits >= 32 ? 0xFFFFFFFFu : (1u << bits) - 1u), sign_(bits >= 32 ? 0x80000000u : 1u << (bits - 1)) {}

  constexpr std::int64_t update(std::uint32_t raw) noexcept {
    raw &= mask_;
    if (!primed_) {
      // An absolute counter's power-up value is its position: taken as the signed value of its width.
      primed_ = true;
      last_ = raw;
      extended_ = (raw & sign_) != 0 ? static_cast<std::int64_t>(raw) - static_cast<std::int64_t>(mask_) - 1 : raw;
      return extended_;
    }
    const std::uint32_t diff = (raw - last_) & mask_;
    const std::int64_t delta =
        (diff & sign_) != 0 ? static_cast<std::int64_t>(diff) - static_cast<std::int64_t>(mask_) - 1 : diff;
    extended_ += delta;
    last_ = raw;
    return extended_;
  }
  constexpr std::int64_t counts() const noexcept { return extended_; }

 private:
  std::uint32_t mask_;
  std::uint32_t sign_;
  std::uint32_t last_ = 0;
  bool primed_ = false;
  std::int64_t extended_ = 0;
};

}  // namespace lever::fw
