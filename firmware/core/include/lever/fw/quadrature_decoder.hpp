#pragma once
// Software quadrature decoder for an incremental encoder whose A/B edges arrive as events (libgpiod on the
// board, the simulated encoder in the HIL).
#include <cstdint>

namespace lever::fw {

// A and B line levels packed as (A << 1) | B.
using AbState = std::uint8_t;
constexpr AbState ab(bool a, bool b) noexcept { return static_cast<AbState>((a ? 2 : 0) | (b ? 1 : 0)); }

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

  // One observed level change. Gray-code order 00 -> 01 -> 11 -> 10 -> 00 counts up.
  constexpr void feed(AbState levels) noexcept {
    levels &= 3u;
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

  constexpr std::int32_t counts() const noexcept { return counts_; }
  constexpr std::uint32_t illegal_transitions() const noexcept { return illegal_; }
  constexpr bool fault() const noexcept { return illegal_ > config_.illegal_threshold; }
  // Re-arming after an encoder fault: the position is only trustworthy again from a known reference, so the
  // count is kept but the illegal-transition tally restarts.
  constexpr void clear_fault() noexcept { illegal_ = 0; }

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
};

}  // namespace lever::fw
