#pragma once
// lever-hil serve's ticks on the wall clock: one a millisecond, at absolute deadlines. A late tick is caught up
// step by step; a lag longer than kMaxCatchUpMs is given up (a slip, counted), since a burst of physics steps to
// catch up seconds would only show the levers a jump.
#include <chrono>
#include <cstdint>

namespace lever::hil {

class WallClockPacer {
 public:
  using Clock = std::chrono::steady_clock;
  static constexpr std::int64_t kMaxCatchUpMs = 50;

  // Ticks on whole milliseconds of the clock, where lever-fw's loops have theirs (the board layer's RealtimeLoop): the
  // world and the levers keep one phase however they were started.
  WallClockPacer() : start_(Clock::now()), grid_start_(whole_ms(start_)) {}

  // Until the next tick is due.
  void wait();

  Clock::time_point start() const { return start_; }
  std::uint64_t slips() const { return slips_; }
  std::int64_t max_lag_ms() const { return max_lag_ms_; }

 private:
  static Clock::time_point whole_ms(Clock::time_point t) { return std::chrono::floor<std::chrono::milliseconds>(t); }

  Clock::time_point start_, grid_start_;
  std::int64_t grid_tick_ = 0;  // ticks since grid_start_
  std::uint64_t slips_ = 0;
  std::int64_t max_lag_ms_ = 0;  // the furthest it was behind
};

}  // namespace lever::hil
